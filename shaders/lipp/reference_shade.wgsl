// lipp.reference_shade: Lipp §3.4's shading (shading.wgsl, the same as
// lipp.shade's) at every control point lipp.reference_strands wrote, into
// `vertex_lighting` for reference.resolve to interpolate. Port of
// passes/src/lipp/reference/shade.rs.

#define FRAME_BINDING 1
#define MODELS_BINDING 2
#define LIGHTS_BINDING 3
#define ENV_SH_BINDING 4
#define DOM_DEPTH_BINDING 7
#define DOM_LAYERS_BINDING 8
#define ENV_PREFILTERED_BINDING 10
#import strandgraph::lipp_shading::{ShadeParams, Shading, shading_of, shade_point, depth_correction, share_light_frames}
#import strandgraph::half::pack_radiance

@group(0) @binding(0) var<uniform> params: ShadeParams;
@group(0) @binding(5) var<storage, read> reference_points: array<vec4<u32>>;
@group(0) @binding(6) var<storage, read> raster_args: array<u32>;
@group(0) @binding(9) var<storage, read_write> vertex_lighting: array<vec2<u32>>;

// shade::{SLOTS_PER_GROUP, SHADE_LANES}.
const SHADE_LANES: u32 = 256u;
const SLOTS_PER_GROUP: u32 = 2064u;

// strands::{MODEL_SHIFT, VALID}.
const MODEL_SHIFT: u32 = 12u;
const VALID: u32 = 0x80000000u;

fn shade_slot(slot: u32, s: Shading, delta: f32) {
    let w1 = reference_points[2u * slot + 1u];
    if (w1.w & VALID) == 0u {
        return;
    }
    let w0 = bitcast<vec4<f32>>(reference_points[2u * slot]);
    let strand = vec2<u32>(w1.w & 63u, (w1.w >> 6u) & 63u);
    let model = (w1.w & ~VALID) >> MODEL_SHIFT;
    let c = shade_point(s, w0.xyz, bitcast<vec3<f32>>(w1.xyz), strand, w0.w, model, delta);
    vertex_lighting[slot] = pack_radiance(c);
}

@compute @workgroup_size(256)
fn reference_shade(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    share_light_frames(lane);
    workgroupBarrier();
    var delta = 0.0;
    if params.lod_depth_correction != 0u {
        delta = depth_correction(raster_args[5], raster_args[4]);
    }
    let s = shading_of(params);
    let first = wg.x * SLOTS_PER_GROUP;
    let end = min(first + SLOTS_PER_GROUP, min(params.slots, arrayLength(&vertex_lighting)));
    for (var slot = first + lane; slot < end; slot += SHADE_LANES) {
        shade_slot(slot, s, delta);
    }
}
