// hw_strands.raster: the segment records of hw_strands.assemble drawn by the
// hardware rasterizer as camera-facing quads (six vertices per segment,
// pulled from storage: no vertex buffers), at as many samples as the depth
// attachment has, into the G-buffer layers Lipp's MSAA reference mode uses
// (one 64-bit layer per sample, payload::pack), so lipp.shade and lipp.filter
// resolve it unchanged. Port of passes/src/hw_strands/raster.rs.
//
// The depth attachment holds the head (scene.depth_attachment) and the
// strands drawn so far; early fragment tests reject hidden samples before
// the shader's atomics. The shader runs per sample (sample_index; naga's
// SampleMask input is not valid SPIR-V, gfx-rs/wgpu#7311) and writes its
// sample's layer (hw_strands/quad.wgsl's write_sample, which
// hw_strands.mesh shares).

#define SCENE_DEPTH_BINDING 4
#define HAIR_DEPTH_BINDING 5
#define GBUFFER_BINDING 6
#import strandgraph::layout::FrameData
#import strandgraph::hw_strands_quad::{quad_corner_clipped, write_sample, CORNERS}

struct RasterParams {
    // Quad width in pixels (lipp.raster's centre_diameter).
    width_px: f32,
    width: u32,
    height: u32,
    model_index: u32,
    // Records `hw_segments` holds.
    capacity: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

const SEGMENT_WORDS: u32 = 10u;
const VERTICES_PER_SEGMENT: u32 = 6u;

@group(0) @binding(0) var<uniform> params: RasterParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> hw_segments: array<u32>;
@group(0) @binding(3) var<storage, read> hw_draw_args: array<u32>;

struct Varyings {
    @builtin(position) position: vec4<f32>,
    // 0 at end a, 1 at end b, linear in screen space like lipp.raster's t
    // (a cut end's parameter where the near plane cuts the segment).
    @location(0) @interpolate(linear, sample) t: f32,
    // The fragment shader loads the segment's payload bits (quad.wgsl's
    // QuadVertex says why).
    @location(1) @interpolate(flat) segment: u32,
}

fn clip_at(base: u32) -> vec4<f32> {
    return vec4<f32>(
        bitcast<f32>(hw_segments[base]),
        bitcast<f32>(hw_segments[base + 1u]),
        bitcast<f32>(hw_segments[base + 2u]),
        bitcast<f32>(hw_segments[base + 3u]),
    );
}

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32) -> Varyings {
    let segment = vertex / VERTICES_PER_SEGMENT;
    let corner = CORNERS[vertex % VERTICES_PER_SEGMENT];
    var out: Varyings;
    out.t = f32(corner & 1u);
    out.segment = segment;
    // Outside the clip volume, every vertex the same: nothing is drawn.
    out.position = vec4<f32>(2.0, 2.0, 2.0, 1.0);
    if segment >= min(params.capacity, hw_draw_args[0] / VERTICES_PER_SEGMENT) {
        return out;
    }
    let base = segment * SEGMENT_WORDS;
    let size = vec2<f32>(f32(params.width), f32(params.height));
    let c = quad_corner_clipped(clip_at(base), clip_at(base + 4u), corner, params.width_px, size, frame.near);
    out.position = c.position;
    out.t = c.t;
    return out;
}

@fragment
@early_depth_test(force)
fn fs_main(in: Varyings, @builtin(sample_index) sample: u32) {
    let base = in.segment * SEGMENT_WORDS;
    write_sample(in.position, in.t, hw_segments[base + 8u], hw_segments[base + 9u], sample, params.width, params.height, params.model_index);
}
