// scene.opaque: shade opaque meshes where they won the depth prepass.
//
// A raster pipeline; the CPU kernel is passes/src/opaque_mesh/opaque.rs.
// Pipeline state the backend sets: topology TriangleList, FrontFace::Ccw,
// CullMode::Back; depth attachment `scene.depth` loaded (not cleared), compare
// Equal, writes off; colour attachment 0 `output` (Rgba16Float) cleared to
// params.background, alpha 1. Draw 3 × triangles vertices, no vertex buffers.
//
// Bindings (group 0), in the order of the pass's bindings less its attachments,
// every record a storage buffer: 0 = frame, 1 = mesh.triangles, 2 = lights,
// 3 = skin_shadow (one mask word per pixel, kulikov/skin_shadow.wgsl).
// Parameters are the uniform block at binding 0 (OpaqueParams::uniform).
//
#import strandgraph::layout::{FrameData, TriangleData, LightData}

// passes/src/opaque_mesh/opaque.rs: OpaqueParams. `background` is the colour
// attachment's clear value, not a shader input.
struct OpaqueParams {
    // rgb: albedo; a: ambient.
    albedo_ambient: vec4<f32>,
    // Diffuse wrap per channel (xyz).
    wrap: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: OpaqueParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> mesh_triangles: array<TriangleData>;
@group(0) @binding(3) var<storage, read> lights: array<LightData>;
@group(0) @binding(4) var<storage, read> skin_shadow: array<u32>;


const PI: f32 = 3.14159265358979;

struct VertexOut {
    // Invariant: must match scene.depth_prepass bit for bit (depth Equal).
    @invariant @builtin(position) position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    // Geometric normal, the fallback when the corner normals cancel out.
    @location(2) @interpolate(flat) face: vec3<f32>,
    @location(3) albedo: vec3<f32>,
}

// assets/src/octahedral.rs: unpack_unit_vector (two snorm16, x low, y high;
// Cigolle et al. 2014). unpack2x16snorm clamps at -1 like unsnorm16.
fn sign_not_zero(v: vec2<f32>) -> vec2<f32> {
    return select(vec2<f32>(-1.0), vec2<f32>(1.0), v >= vec2<f32>(0.0));
}

fn unpack_unit_vector(bits: u32) -> vec3<f32> {
    let e = unpack2x16snorm(bits);
    let z = 1.0 - abs(e.x) - abs(e.y);
    var xy = e;
    if z < 0.0 {
        xy = (vec2<f32>(1.0) - abs(e.yx)) * sign_not_zero(e);
    }
    let n = vec3<f32>(xy, z);
    let len2 = dot(n, n);
    if len2 > 0.0 {
        return n * inverseSqrt(len2);
    }
    return vec3<f32>(0.0);
}

fn corner(t: TriangleData, k: u32) -> vec4<f32> {
    if k == 1u {
        return t.b;
    } else if k == 2u {
        return t.c;
    }
    return t.a;
}

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32) -> VertexOut {
    let t = mesh_triangles[vertex / 3u];
    let w_a = (frame.view_proj * vec4<f32>(t.a.xyz, 1.0)).w;
    let w_b = (frame.view_proj * vec4<f32>(t.b.xyz, 1.0)).w;
    let w_c = (frame.view_proj * vec4<f32>(t.c.xyz, 1.0)).w;
    let p = corner(t, vertex % 3u);
    var out: VertexOut;
    // Each corner's painted albedo (8-bit square roots) or the pass's albedo.
    let packed = t.albedo[vertex % 3u];
    let e = unpack4x8unorm(packed).xyz;
    out.albedo = select(params.albedo_ambient.rgb, e * e, packed != 0u);
    out.world = p.xyz;
    out.normal = unpack_unit_vector(bitcast<u32>(p.w));
    let f = cross(t.b.xyz - t.a.xyz, t.c.xyz - t.a.xyz);
    out.face = select(vec3<f32>(0.0, 0.0, 1.0), normalize(f), dot(f, f) > 0.0);
    // The same near-plane drop as depth_prepass.wgsl and the CPU kernels.
    if min(w_a, min(w_b, w_c)) <= frame.near {
        out.position = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return out;
    }
    out.position = frame.view_proj * vec4<f32>(p.xyz, 1.0);
    return out;
}

// Lambert (BRDF albedo/π) over every light plus ambient × albedo, scaled by
// the pixel's shadow mask (bytes 0-2: lights 0-2, byte 3: ambient), as
// `shade` in passes/src/opaque_mesh/opaque.rs. Linear RGB.
@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    // Perspective-correct interpolation (the default) of the corner normals.
    var n = in.face;
    if dot(in.normal, in.normal) > 0.0 {
        n = normalize(in.normal);
    }
    let count = min(frame.light_count, arrayLength(&lights));
    // The fragment's pixel: position.xy is its centre (x + 0.5, y + 0.5).
    let pixel = vec2<u32>(in.position.xy);
    let mask = skin_shadow[pixel.y * u32(frame.screen.x) + pixel.x];
    var irradiance = vec3<f32>(0.0);
    for (var i = 0u; i < count; i += 1u) {
        let l = lights[i];
        var to_light: vec3<f32>;
        var falloff = 1.0;
        if l.position_or_direction.w == 0.0 {
            let d = l.position_or_direction.xyz;
            to_light = select(vec3<f32>(0.0), -normalize(d), dot(d, d) > 0.0);
        } else {
            let d = l.position_or_direction.xyz - in.world;
            // Clamped at 1 cm, as in the CPU kernel.
            let d2 = max(dot(d, d), 1e-4);
            to_light = d * inverseSqrt(d2);
            falloff = 1.0 / d2;
        }
        // kulikov::skin_shadow::light_visibility: lights past the third are lit.
        var visible = 1.0;
        if i < 3u {
            visible = f32((mask >> (8u * i)) & 0xFFu) / 255.0;
        }
        // Green 2004's wrap lighting, per channel (opaque::shade).
        let w = params.wrap.xyz;
        let wrapped = max((vec3<f32>(dot(n, to_light)) + w) / (vec3<f32>(1.0) + w), vec3<f32>(0.0));
        irradiance += l.radiance.rgb * wrapped * (falloff * visible);
    }
    let albedo = in.albedo;
    let ambient = params.albedo_ambient.a * (f32(mask >> 24u) / 255.0);
    let color = albedo * (irradiance / PI + vec3<f32>(ambient));
    return vec4<f32>(color, 1.0);
}
