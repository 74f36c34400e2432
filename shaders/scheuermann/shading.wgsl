// Scheuermann 2004's shading, shared by scheuermann.hair's stages
// (hair.wgsl) and his ground truth (reference_shade.wgsl). Port of
// passes/src/scheuermann/{shading,texture}.rs.
//
// Both importers bind, in group 0: 0 = parameters (HairParams), 1 = frame,
// 2 = models, 3 = lights, 6 = patches.texture (RGBA8: base, alpha, shift,
// sparkle; mips along u only).
#define_import_path strandgraph::scheuermann_shading

#import strandgraph::layout::{FrameData, ModelData, LightData}

// assets/src/hairpatch: PATCH_SEGMENTS and HairTexture's size.
const SEGMENTS: u32 = 16u;
const TEX_WIDTH: u32 = 512u;
const TEX_HEIGHT: u32 = 128u;
const TEX_LEVELS: u32 = 10u;
// Fragments less opaque than this neither blend nor write depth (the
// ALPHAFUNC GREATER 0 of the day): half an 8-bit step.
const MIN_ALPHA: f32 = 0.001960784;
// std::f32::consts::FRAC_1_PI: shading.rs says why the lit term has it.
const FRAC_1_PI: f32 = 0.318309886183791;

// passes/src/scheuermann/hair.rs: HairGpu.
struct HairParams {
    stage: u32,
    primed: u32,
    patches: u32,
    opaque_alpha: f32,
    primary_shift: f32,
    secondary_shift: f32,
    shift_scale: f32,
    primary_exponent: f32,
    secondary_exponent: f32,
    primary_r: f32,
    primary_g: f32,
    primary_b: f32,
    secondary_strength: f32,
    diffuse_floor: f32,
    lod_bias: f32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: HairParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> models: array<ModelData>;
@group(0) @binding(3) var<storage, read> lights: array<LightData>;
@group(0) @binding(6) var<storage, read> patches_texture: array<u32>;

// texture.rs: level_offset, texel, sample_level, sample.
fn level_offset(level: u32) -> u32 {
    return TEX_HEIGHT * (2u * TEX_WIDTH - 2u * (TEX_WIDTH >> level));
}

fn texel(level: u32, x: i32, y: i32) -> vec4<f32> {
    let w = i32(TEX_WIDTH >> level);
    let xi = u32(clamp(x, 0, w - 1));
    let yi = u32(clamp(y, 0, i32(TEX_HEIGHT) - 1));
    return unpack4x8unorm(patches_texture[level_offset(level) + yi * u32(w) + xi]);
}

fn sample_level(level: u32, uv: vec2<f32>) -> vec4<f32> {
    let x = uv.x * f32(TEX_WIDTH >> level) - 0.5;
    let y = uv.y * f32(TEX_HEIGHT) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let ix = i32(x0);
    let iy = i32(y0);
    let top = mix(texel(level, ix, iy), texel(level, ix + 1, iy), fx);
    let bottom = mix(texel(level, ix, iy + 1), texel(level, ix + 1, iy + 1), fx);
    return mix(top, bottom, fy);
}

fn safe_normalize(v: vec3<f32>) -> vec3<f32> {
    let len2 = dot(v, v);
    if len2 > 0.0 {
        return v * inverseSqrt(len2);
    }
    return vec3<f32>(0.0);
}

// shading.rs: shift_tangent (Scheuermann: ShiftTangent).
fn shift_tangent(t: vec3<f32>, n: vec3<f32>, shift: f32) -> vec3<f32> {
    return safe_normalize(t + shift * n);
}

// shading.rs: strand_specular (Scheuermann: StrandSpecular).
fn strand_specular(t: vec3<f32>, v: vec3<f32>, l: vec3<f32>, exponent: f32) -> f32 {
    let h = safe_normalize(l + v);
    let dot_th = dot(t, h);
    let sin_th = sqrt(max(1.0 - dot_th * dot_th, 0.0));
    let dir_atten = smoothstep(-1.0, 0.0, dot_th);
    return dir_atten * pow(max(sin_th, 1e-6), exponent);
}

// shading.rs: hair_lighting (Scheuermann: HairLighting), summed over the
// lights at a point with unit-or-zero `tangent` and `normal`; straight (not
// premultiplied) colour and alpha.
fn hair_lighting_at(world: vec3<f32>, tangent: vec3<f32>, normal: vec3<f32>, ao: f32, tex: vec4<f32>, model_index: u32) -> vec4<f32> {
    let model = models[model_index];
    let colour = max(model.color.rgb, vec3<f32>(0.0));
    let base_colour = sqrt(colour);
    let primary = vec3<f32>(params.primary_r, params.primary_g, params.primary_b);
    let secondary = params.secondary_strength * pow(colour, vec3<f32>(0.8));
    let t = safe_normalize(tangent);
    let n = safe_normalize(normal);
    let v = safe_normalize(frame.camera_pos.xyz - world);
    let shift_tex = (tex.z - 0.5) * params.shift_scale;
    let t1 = shift_tangent(t, n, params.primary_shift + shift_tex);
    let t2 = shift_tangent(t, n, params.secondary_shift + shift_tex);
    var rgb = vec3<f32>(0.0);
    for (var i = 0u; i < frame.light_count; i++) {
        let pd = lights[i].position_or_direction;
        var l = safe_normalize(-pd.xyz);
        var atten = 1.0;
        if pd.w != 0.0 {
            let d = pd.xyz - world;
            l = safe_normalize(d);
            atten = 1.0 / max(dot(d, d), 1e-4);
        }
        let diffuse = clamp(mix(params.diffuse_floor, 1.0, dot(n, l)), 0.0, 1.0) * base_colour;
        var specular = primary * strand_specular(t1, v, l, params.primary_exponent);
        specular += secondary * tex.w * strand_specular(t2, v, l, params.secondary_exponent);
        rgb += (diffuse + specular) * tex.x * lights[i].radiance.rgb * (atten * FRAC_1_PI);
    }
    return vec4<f32>(rgb * ao, tex.y);
}
