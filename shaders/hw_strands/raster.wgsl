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
// sample's layer, tested as Lipp's write_sample tests: against scene.depth
// and, after the first groom, against hair_depth.

#import strandgraph::layout::FrameData
#import strandgraph::lipp::{quantize, depth_bits}

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
// Which end (bit 0: b) and side (bit 1: +) each of the six vertices takes:
// triangles (a-, b-, a+) and (a+, b-, b+).
const CORNERS: array<u32, 6> = array<u32, 6>(0u, 1u, 2u, 2u, 1u, 3u);

@group(0) @binding(0) var<uniform> params: RasterParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> hw_segments: array<u32>;
@group(0) @binding(3) var<storage, read> hw_draw_args: array<u32>;
@group(0) @binding(4) var scene_depth: texture_2d<f32>;
@group(0) @binding(5) var<storage, read> hair_depth: array<u32>;
@group(0) @binding(6) var<storage, read_write> gbuffer: array<atomic<u64>>;

struct Varyings {
    @builtin(position) position: vec4<f32>,
    // 0 at end a, 1 at end b, linear in screen space like lipp.raster's t.
    @location(0) @interpolate(linear, sample) t: f32,
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

fn to_pixels(c: vec4<f32>, size: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5) * size;
}

// hw_strands::quad_corner: corner `corner` of segment (a, b)'s quad, `half`
// pixels either side of the segment and past each end (square caps, so
// the quads of a bent strand leave no gaps).
fn quad_corner(a: vec4<f32>, b: vec4<f32>, corner: u32, half: f32, size: vec2<f32>) -> vec4<f32> {
    let d = to_pixels(b, size) - to_pixels(a, size);
    let len = length(d);
    let dir = select(vec2<f32>(1.0, 0.0), d / len, len > 1e-6);
    let normal = vec2<f32>(-dir.y, dir.x);
    let along = select(-half, half, (corner & 1u) != 0u);
    let across = select(-half, half, (corner & 2u) != 0u);
    let offset = dir * along + normal * across;
    let c = select(a, b, (corner & 1u) != 0u);
    // Pixels (y down) to NDC (y up), scaled by w to stay in clip space.
    let ndc = vec2<f32>(offset.x * 2.0 / size.x, -offset.y * 2.0 / size.y);
    return vec4<f32>(c.xy + ndc * c.w, c.z, c.w);
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
    let a = clip_at(base);
    let b = clip_at(base + 4u);
    // lipp.raster drops a segment with an end at or behind the near plane.
    if a.w <= frame.near || b.w <= frame.near {
        return out;
    }
    let size = vec2<f32>(f32(params.width), f32(params.height));
    out.position = quad_corner(a, b, corner, 0.5 * params.width_px, size);
    return out;
}

// Segment::payload's 6-bit interpolation, operation for operation.
fn lerp6(a: u32, b: u32, t: f32) -> u32 {
    let fa = f32(a & 63u);
    let fb = f32(b & 63u);
    return quantize((fa + (fb - fa) * t) / 63.0, 63.0);
}

// Lipp's write_sample for this sample: position and t are the sample's.
@fragment
@early_depth_test(force)
fn fs_main(in: Varyings, @builtin(sample_index) sample: u32) {
    let x = u32(in.position.x);
    let y = u32(in.position.y);
    let z = in.position.z;
    if x >= params.width || y >= params.height || !(z >= 0.0 && z < 1.0) {
        return;
    }
    if z >= textureLoad(scene_depth, vec2<i32>(i32(x), i32(y)), 0).x {
        return;
    }
    let pixel = y * params.width + x;
    if params.model_index > 0u && z >= bitcast<f32>(hair_depth[pixel]) {
        return;
    }
    let base = in.segment * SEGMENT_WORDS;
    let lo_a = hw_segments[base + 8u];
    let bits_b = hw_segments[base + 9u];
    let t = clamp(in.t, 0.0, 1.0);
    let w = lerp6(lo_a >> 6u, bits_b >> 8u, t);
    let ao = lerp6(lo_a, bits_b >> 14u, t);
    let lo = (lo_a & 0xFFFFF000u) | (w << 6u) | ao;
    let hi = (depth_bits(z) << 8u) | (bits_b & 255u);
    let payload = (u64(hi) << 32u) | u64(lo);
    let pixels = params.width * params.height;
    if sample < min(8u, arrayLength(&gbuffer) / max(pixels, 1u)) {
        atomicMin(&gbuffer[sample * pixels + pixel], payload);
    }
}
