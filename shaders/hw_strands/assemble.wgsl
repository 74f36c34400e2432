// hw_strands.assemble: the strands Lipp's rasterizer draws, assembled the
// same way (lipp/assembly.wgsl: one 32-lane workgroup per strand the LOD
// keeps, Code 1's cooperative passes), then projected once per control point
// and written as segment records for the hardware rasterizer
// (hw_strands/raster.wgsl). Port of passes/src/hw_strands/assemble.rs.
//
// Lane 0 reserves the strand's C - 1 segments with one atomicAdd on the
// indirect draw's vertex count (6 vertices per segment), so the records of a
// strand are contiguous and the draw covers exactly the segments written.

#define FRAME_BINDING 1
#define MODELS_BINDING 6
#define LIGHTS_BINDING 7
#import strandgraph::lipp_dom::frame
#import strandgraph::clip::transform
#import strandgraph::lipp::{LOD_WORDS, RASTER_GROUP}
#import strandgraph::hw_strands_segment::segment_bits
#import strandgraph::lipp_assembly::{raster_args, bundle_lod, ControlPoint, Strip, load_strand, lanes_of, pass_one, pass_two, strip_point, strip_tangent, strip_segments}

struct AssembleParams {
    cooperative_assembly: u32,
    styling: u32,
    bundles: u32,
    // Records `hw_segments` holds (its size / SEGMENT_WORDS).
    capacity: u32,
}

// hw_strands::SEGMENT_WORDS.
const SEGMENT_WORDS: u32 = 10u;
const VERTICES_PER_SEGMENT: u32 = 6u;

@group(0) @binding(0) var<uniform> params: AssembleParams;
@group(0) @binding(6) var<storage, read_write> hw_segments: array<u32>;
// VkDrawIndirectCommand: vertex count, instance count, first vertex, first instance.
@group(0) @binding(7) var<storage, read_write> hw_draw_args: array<atomic<u32>>;

var<workgroup> first_record: u32;

// hw_strands::Segment::words: both ends in clip space, then the payload
// bits the fragment shader completes (hw_strands/segment.wgsl).
fn write_segment(r: u32, a: ControlPoint, ta: vec3<f32>, b: ControlPoint, tb: vec3<f32>, uv: vec2<f32>) {
    let base = r * SEGMENT_WORDS;
    let ca = transform(frame.view_proj, vec4<f32>(a.pos, 1.0));
    let cb = transform(frame.view_proj, vec4<f32>(b.pos, 1.0));
    for (var k = 0u; k < 4u; k++) {
        hw_segments[base + k] = bitcast<u32>(ca[k]);
        hw_segments[base + 4u + k] = bitcast<u32>(cb[k]);
    }
    let bits = segment_bits(a, ta, b, tb, uv);
    hw_segments[base + 8u] = bits.x;
    hw_segments[base + 9u] = bits.y;
}

@compute @workgroup_size(32)
fn assemble(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(subgroup_invocation_id) sg_lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    let total = raster_args[3];
    let count = min(params.bundles, arrayLength(&bundle_lod) / LOD_WORDS);
    let l = lanes_of(lane, sg_lane, sg_size, params.cooperative_assembly != 0u);
    let stride = max(groups.x, 1u);
    if wg.x == 0u && lane == 0u {
        atomicMax(&hw_draw_args[1], 1u);
    }
    for (var s = wg.x; s < total; s += stride) {
        let st = load_strand(count, s, params.styling != 0u);
        if lane == 0u {
            let vertices = atomicAdd(&hw_draw_args[0], (st.c - 1u) * VERTICES_PER_SEGMENT);
            first_record = vertices / VERTICES_PER_SEGMENT;
        }
        pass_one(st, l);
        workgroupBarrier();
        let strip = pass_two(st, l);
        // A lane's strip starts at control point lane * ceil((C - 1) / 32).
        let first = lane * ((st.c - 1u + RASTER_GROUP - 1u) / RASTER_GROUP);
        let base = first_record + first;
        for (var m = 0u; m < strip_segments(strip); m++) {
            if base + m < params.capacity {
                write_segment(base + m, strip_point(strip, m), strip_tangent(strip, m), strip_point(strip, m + 1u), strip_tangent(strip, m + 1u), st.uv);
            }
        }
        // smLayer and first_record are rewritten by the next strand.
        workgroupBarrier();
    }
}
