// scene.opaque: shade opaque meshes from their visibility buffer, once per
// pixel. Port of passes/src/opaque_mesh/opaque.rs.
//
// Each lane takes one pixel, fetches the triangle scene.visibility kept
// there, sets it up again with the same integer rasterizer
// (shaders/opaque_mesh/setup.wgsl) and interpolates the corners
// perspective-correctly from the exact edge functions at the pixel centre.
//
// Bindings (group 0): 0 = parameters, 1 = frame, 2 = mesh.triangles,
// 3 = lights, 4 = skin_shadow (one mask word per pixel,
// kulikov/skin_shadow.wgsl), 5 = scene.visibility (word pairs, low word
// first), 6 = output (Rgba16Float storage image).
//
#import strandgraph::layout::{FrameData, TriangleData, LightData}
#import strandgraph::octahedral::unpack_unit_vector
#import strandgraph::opaque_setup::{setup_world, edges, barycentrics}

// passes/src/opaque_mesh/opaque.rs: OpaqueParams::uniform.
struct OpaqueParams {
    // rgb: albedo; a: ambient.
    albedo_ambient: vec4<f32>,
    // Diffuse wrap per channel (xyz).
    wrap: vec4<f32>,
    // rgb: where no mesh is drawn.
    background: vec4<f32>,
    width: u32,
    height: u32,
}

@group(0) @binding(0) var<uniform> params: OpaqueParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> mesh_triangles: array<TriangleData>;
@group(0) @binding(3) var<storage, read> lights: array<LightData>;
@group(0) @binding(4) var<storage, read> skin_shadow: array<u32>;
@group(0) @binding(5) var<storage, read> scene_visibility: array<vec2<u32>>;
@group(0) @binding(6) var output: texture_storage_2d<rgba16float, write>;

// 1/π, multiplied as the CPU kernel does (std::f32::consts::FRAC_1_PI).
const FRAC_1_PI: f32 = 0.318309886183791;

// Each corner's painted albedo (8-bit square roots) or the pass's albedo.
fn corner_albedo(packed: u32) -> vec3<f32> {
    let e = unpack4x8unorm(packed).xyz;
    return select(params.albedo_ambient.rgb, e * e, packed != 0u);
}

// Lambert (BRDF albedo/π) over every light plus ambient × albedo, scaled by
// the pixel's shadow mask (bytes 0-2: lights 0-2, byte 3: ambient), as
// `shade` in passes/src/opaque_mesh/opaque.rs. Linear RGB; false when the
// triangle does not set up.
fn shade_pixel(t: u32, x: u32, y: u32, mask: u32, color: ptr<function, vec3<f32>>) -> bool {
    if t >= arrayLength(&mesh_triangles) {
        return false;
    }
    let tri = mesh_triangles[t];
    let s = setup_world(tri.a.xyz, tri.b.xyz, tri.c.xyz, frame.view_proj, frame.near, params.width, params.height);
    if !s.valid {
        return false;
    }
    let b = barycentrics(s, edges(s, x, y));
    let world = tri.a.xyz * b.x + tri.b.xyz * b.y + tri.c.xyz * b.z;
    let f = cross(tri.b.xyz - tri.a.xyz, tri.c.xyz - tri.a.xyz);
    let face = select(vec3<f32>(0.0, 0.0, 1.0), normalize(f), dot(f, f) > 0.0);
    let normal = unpack_unit_vector(bitcast<u32>(tri.a.w)) * b.x
        + unpack_unit_vector(bitcast<u32>(tri.b.w)) * b.y
        + unpack_unit_vector(bitcast<u32>(tri.c.w)) * b.z;
    var n = face;
    if dot(normal, normal) > 0.0 {
        n = normalize(normal);
    }
    let albedo = corner_albedo(tri.albedo[0]) * b.x + corner_albedo(tri.albedo[1]) * b.y
        + corner_albedo(tri.albedo[2]) * b.z;
    let count = min(frame.light_count, arrayLength(&lights));
    var irradiance = vec3<f32>(0.0);
    for (var i = 0u; i < count; i += 1u) {
        let l = lights[i];
        var to_light: vec3<f32>;
        var falloff = 1.0;
        if l.position_or_direction.w == 0.0 {
            let d = l.position_or_direction.xyz;
            to_light = select(vec3<f32>(0.0), -normalize(d), dot(d, d) > 0.0);
        } else {
            let d = l.position_or_direction.xyz - world;
            // Clamped at 1 cm, as in the CPU kernel.
            let d2 = max(dot(d, d), 1e-4);
            to_light = d / sqrt(d2);
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
    let ambient = params.albedo_ambient.a * (f32(mask >> 24u) / 255.0);
    *color = albedo * (irradiance * FRAC_1_PI + vec3<f32>(ambient));
    return true;
}

@compute @workgroup_size(256)
fn opaque(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.width * params.height {
        return;
    }
    let x = i % params.width;
    let y = i / params.width;
    let v = scene_visibility[i];
    var color = params.background.rgb;
    if !(v.x == 0xFFFFFFFFu && v.y == 0xFFFFFFFFu) {
        var lit: vec3<f32>;
        if shade_pixel(v.x, x, y, skin_shadow[i], &lit) {
            color = lit;
        }
    }
    // Alpha 0: no hair yet (`output`'s alpha is the hair's coverage).
    textureStore(output, vec2<u32>(x, y), vec4<f32>(color, 0.0));
}
