// scheuermann.hair: Scheuermann 2004's polygonal hair, one stage of its
// "Optimized Rendering Scheme" per graph pass. Port of
// passes/src/scheuermann/{hair,shading,texture}.rs; the pipeline state of
// each stage (culling, depth test, blending) is `stage_state` there.
//
// Vertex pulling, no vertex buffers: patch p is a strip of SEGMENTS quads,
// cross-section i holding vertices 2i (left) and 2i + 1 (right); triangle
// t = p * 2 * SEGMENTS + 2i + h has corners (2i, 2i+1, 2i+2) for h = 0 and
// (2i+1, 2i+3, 2i+2) for h = 1, counter-clockwise seen from the patch's
// outward normal.
//
// Bindings (group 0), in the order of the pass's bindings less its
// attachments: 0 = parameters, 1 = frame, 2 = models, 3 = lights,
// 4 = patches.vertices (8 words per vertex: world xyz, AO, octahedral
// tangent, octahedral normal, unorm16 u | v << 16, texels per metre),
// 5 = patches.models (model index per patch), 6 = patches.texture (RGBA8:
// base, alpha, shift, sparkle; mips along u only). Attachments: colour
// `output` (Rgba16Float), depth `depth_buffer` (D32Float).
#import strandgraph::layout::{FrameData, ModelData, LightData}
#import strandgraph::clip::transform
#import strandgraph::octahedral::unpack_unit_vector

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
@group(0) @binding(4) var<storage, read> patches_vertices: array<u32>;
@group(0) @binding(5) var<storage, read> patches_models: array<u32>;
@group(0) @binding(6) var<storage, read> patches_texture: array<u32>;

struct VertexOut {
    // Invariant: the opaque stage tests depth Equal against the prime stage.
    @invariant @builtin(position) position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) tangent: vec3<f32>,
    @location(2) normal: vec3<f32>,
    @location(3) uv: vec2<f32>,
    // AO, texels per metre across the strip, clip w.
    @location(4) ao_density_w: vec3<f32>,
    @location(5) @interpolate(flat) model: u32,
}

// hair.rs: corner_vertex.
fn corner_vertex(t: u32, k: u32) -> u32 {
    let strip = t / (2u * SEGMENTS);
    let q = t % (2u * SEGMENTS);
    let base = strip * 2u * (SEGMENTS + 1u) + 2u * (q / 2u);
    if q % 2u == 0u {
        return base + array<u32, 3>(0u, 1u, 2u)[k];
    }
    return base + array<u32, 3>(1u, 3u, 2u)[k];
}

fn vertex_position(v: u32) -> vec3<f32> {
    let o = 8u * v;
    return vec3<f32>(
        bitcast<f32>(patches_vertices[o]),
        bitcast<f32>(patches_vertices[o + 1u]),
        bitcast<f32>(patches_vertices[o + 2u]),
    );
}

fn clip_of(v: u32) -> vec4<f32> {
    return transform(frame.view_proj, vec4<f32>(vertex_position(v), 1.0));
}

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> VertexOut {
    // Keeps every binding in use whichever fragment entry a stage draws
    // with (the prime stage's reads neither models nor lights).
    _ = arrayLength(&models);
    _ = arrayLength(&lights);
    let t = index / 3u;
    let v = corner_vertex(t, index % 3u);
    let clip_a = clip_of(corner_vertex(t, 0u));
    let clip_b = clip_of(corner_vertex(t, 1u));
    let clip_c = clip_of(corner_vertex(t, 2u));
    var out: VertexOut;
    // Like the CPU kernel, drop (rather than clip) a triangle with a corner
    // at or behind the near plane: collapsed to a point, it covers nothing.
    if min(clip_a.w, min(clip_b.w, clip_c.w)) <= frame.near {
        out.position = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return out;
    }
    let o = 8u * v;
    let clip = clip_of(v);
    out.position = clip;
    out.world = vertex_position(v);
    out.tangent = unpack_unit_vector(patches_vertices[o + 4u]);
    out.normal = unpack_unit_vector(patches_vertices[o + 5u]);
    out.uv = unpack2x16unorm(patches_vertices[o + 6u]);
    out.ao_density_w = vec3<f32>(
        bitcast<f32>(patches_vertices[o + 3u]),
        bitcast<f32>(patches_vertices[o + 7u]),
        clip.w,
    );
    out.model = patches_models[t / (2u * SEGMENTS)];
    return out;
}

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

// Mips along u only, chosen from the strip's texel density and the view
// depth (texture.rs: lod says why not screen derivatives).
fn sample_hair(uv: vec2<f32>, ao_density_w: vec3<f32>) -> vec4<f32> {
    let texels_per_pixel = ao_density_w.y * ao_density_w.z / frame.pixels_per_unit;
    let lod = clamp(log2(max(texels_per_pixel, 1.0)) + params.lod_bias, 0.0, f32(TEX_LEVELS - 1u));
    let l0 = u32(floor(lod));
    let l1 = min(l0 + 1u, TEX_LEVELS - 1u);
    return mix(sample_level(l0, uv), sample_level(l1, uv), lod - floor(lod));
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
// lights; straight (not premultiplied) colour and alpha.
fn hair_lighting(in: VertexOut, tex: vec4<f32>) -> vec4<f32> {
    let model = models[in.model];
    let colour = max(model.color.rgb, vec3<f32>(0.0));
    let base_colour = sqrt(colour);
    let primary = vec3<f32>(params.primary_r, params.primary_g, params.primary_b);
    let secondary = params.secondary_strength * pow(colour, vec3<f32>(0.8));
    let t = safe_normalize(in.tangent);
    let n = safe_normalize(in.normal);
    let v = safe_normalize(frame.camera_pos.xyz - in.world);
    let shift_tex = (tex.z - 0.5) * params.shift_scale;
    let t1 = shift_tangent(t, n, params.primary_shift + shift_tex);
    let t2 = shift_tangent(t, n, params.secondary_shift + shift_tex);
    var rgb = vec3<f32>(0.0);
    for (var i = 0u; i < frame.light_count; i++) {
        let pd = lights[i].position_or_direction;
        var l = safe_normalize(-pd.xyz);
        var atten = 1.0;
        if pd.w != 0.0 {
            let d = pd.xyz - in.world;
            l = safe_normalize(d);
            atten = 1.0 / max(dot(d, d), 1e-4);
        }
        let diffuse = clamp(mix(params.diffuse_floor, 1.0, dot(n, l)), 0.0, 1.0) * base_colour;
        var specular = primary * strand_specular(t1, v, l, params.primary_exponent);
        specular += secondary * tex.w * strand_specular(t2, v, l, params.secondary_exponent);
        rgb += (diffuse + specular) * tex.x * lights[i].radiance.rgb * (atten * FRAC_1_PI);
    }
    return vec4<f32>(rgb * in.ao_density_w.x, tex.y);
}

// Stage PrimeDepth: "simple pixel shader that only returns alpha", alpha
// tested so only opaque texels write depth; colour writes are off.
@fragment
fn fs_prime(in: VertexOut) -> @location(0) vec4<f32> {
    let alpha = sample_hair(in.uv, in.ao_density_w).y;
    if alpha < params.opaque_alpha {
        discard;
    }
    return vec4<f32>(0.0, 0.0, 0.0, alpha);
}

// Stage Opaque: where the prime stage left this fragment's depth (test
// Equal), or alpha tested itself when the graph runs no prime stage.
@fragment
fn fs_opaque(in: VertexOut) -> @location(0) vec4<f32> {
    let tex = sample_hair(in.uv, in.ao_density_w);
    if params.primed == 0u && tex.y < params.opaque_alpha {
        discard;
    }
    return vec4<f32>(hair_lighting(in, tex).rgb, 1.0);
}

// Stages BackFaces and FrontFaces: premultiplied "over".
@fragment
fn fs_blend(in: VertexOut) -> @location(0) vec4<f32> {
    let tex = sample_hair(in.uv, in.ao_density_w);
    if tex.y < MIN_ALPHA {
        discard;
    }
    let lit = hair_lighting(in, tex);
    return vec4<f32>(lit.rgb * lit.a, lit.a);
}
