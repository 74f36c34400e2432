// The viewer's display transform: a graph's scene-linear Rgba16Float
// output to the Rgba8Unorm texture egui draws. The same transforms as
// src/tonemap.rs (which writes the CLI's PNGs), so the window shows what
// `render` writes: ACES (Hill's RRT + ODT fit), AgX (base look, Wrensch's
// minimal form) or clip, each display-encoded. egui 0.37 samples its
// textures as gamma-encoded values (egui-wgpu's `egui.wgsl`), so the
// target is not an sRGB format and holds the encoded values.

struct Display {
    // 0 ACES, 1 AgX, 2 clip, 3 already display-encoded (Rgba8Unorm outputs).
    tonemap: u32,
    exposure_ev: f32,
}

@group(0) @binding(0) var<uniform> display: Display;
@group(0) @binding(1) var linear_image: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle that covers the target.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn srgb_encode(x: vec3<f32>) -> vec3<f32> {
    let c = clamp(x, vec3<f32>(0.0), vec3<f32>(1.0));
    return select(1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055, 12.92 * c, c <= vec3<f32>(0.0031308));
}

fn aces(c: vec3<f32>) -> vec3<f32> {
    // Hill's matrices, written row by row; WGSL's mat3x3 takes columns, so
    // the rows multiply from the left (v * M = transpose(M) * v).
    let input = mat3x3<f32>(
        vec3<f32>(0.59719, 0.35458, 0.04823),
        vec3<f32>(0.07600, 0.90834, 0.01566),
        vec3<f32>(0.02840, 0.13383, 0.83777),
    );
    let output = mat3x3<f32>(
        vec3<f32>(1.60475, -0.53108, -0.07367),
        vec3<f32>(-0.10208, 1.10813, -0.00605),
        vec3<f32>(-0.00327, -0.07276, 1.07602),
    );
    let v = c * input;
    let rrt_odt = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.432951) + 0.238081);
    return srgb_encode(rrt_odt * output);
}

fn agx(c: vec3<f32>) -> vec3<f32> {
    let inset = mat3x3<f32>(
        vec3<f32>(0.84247906, 0.04232824, 0.042375655),
        vec3<f32>(0.0784336, 0.87846864, 0.0784336),
        vec3<f32>(0.079223745, 0.07916613, 0.879143),
    );
    let outset = mat3x3<f32>(
        vec3<f32>(1.196879, -0.05289685, -0.052971635),
        vec3<f32>(-0.09802088, 1.1519031, -0.09804345),
        vec3<f32>(-0.09902974, -0.09896118, 1.1510737),
    );
    let min_ev = -12.473931;
    let max_ev = 4.026069;
    let v = (clamp(log2(inset * max(c, vec3<f32>(1e-10))), vec3<f32>(min_ev), vec3<f32>(max_ev)) - min_ev)
        / (max_ev - min_ev);
    let x2 = v * v;
    let x4 = x2 * x2;
    let contrast = 15.5 * x4 * x2 - 40.14 * x4 * v + 31.96 * x4 - 6.868 * x2 * v + 0.4298 * x2
        + 0.1191 * v - 0.00232;
    return clamp(outset * contrast, vec3<f32>(0.0), vec3<f32>(1.0));
}

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = textureLoad(linear_image, vec2<i32>(p.xy), 0).rgb;
    if display.tonemap == 3u {
        return vec4<f32>(texel, 1.0);
    }
    var c = max(texel, vec3<f32>(0.0)) * exp2(display.exposure_ev);
    // Tonemap::display maps NaN and infinity to black.
    if any(c != c) || any(abs(c) > vec3<f32>(3.0e38)) {
        c = vec3<f32>(0.0);
    }
    var shown: vec3<f32>;
    switch display.tonemap {
        case 0u: { shown = aces(c); }
        case 1u: { shown = agx(c); }
        default: { shown = srgb_encode(c); }
    }
    return vec4<f32>(shown, 1.0);
}
