// What hw_strands.raster (raster.wgsl, vertex pulling) and hw_strands.mesh
// (mesh.wgsl, mesh shaders) share: the camera-facing quad of a segment and
// the fragment's write into its sample's G-buffer layer, so the two draw
// exactly the same quads and fragments. Port of passes/src/hw_strands/mod.rs.
// Composed with naga_oil:
//   #define SCENE_DEPTH_BINDING 4
//   #define HAIR_DEPTH_BINDING 5
//   #define GBUFFER_BINDING 6
//   #import strandgraph::hw_strands_quad::{quad_corner_clipped, write_sample, ...}
// Each pass numbers its bindings in the order of its definition's bindings()
// (passes/tests/wgsl_bindings.rs checks it); the defines say where these sit.
#define_import_path strandgraph::hw_strands_quad

#import strandgraph::lipp::{quantize, depth_bits}
#import strandgraph::clip::near_clip

@group(0) @binding(#{SCENE_DEPTH_BINDING}) var scene_depth: texture_2d<f32>;
@group(0) @binding(#{HAIR_DEPTH_BINDING}) var<storage, read> hair_depth: array<u32>;
@group(0) @binding(#{GBUFFER_BINDING}) var<storage, read_write> gbuffer: array<atomic<u64>>;

// hw_strands::CORNERS: which end (bit 0: b) and side (bit 1: +) each of the
// six vertices of a non-indexed quad takes: triangles (a-, b-, a+) and
// (a+, b-, b+). An indexed quad uses corners 0-3 with these as indices.
const CORNERS: array<u32, 6> = array<u32, 6>(0u, 1u, 2u, 2u, 1u, 3u);

// One quad corner as hw_strands.mesh emits it, the segment's payload bits
// (Segment::bits_a, bits_b) flat across the quad. hw_strands.raster passes
// the segment's index instead and its fragment shader loads the bits: on the
// H100 two more flat varyings per vertex cost that draw 27% at the close
// view (80.9 against 63.9 ms), where mesh shaders have no record to load.
struct QuadVertex {
    @builtin(position) position: vec4<f32>,
    // 0 at end a, 1 at end b, linear in screen space like lipp.raster's t
    // (a cut end's parameter where the near plane cuts the segment).
    @location(0) @interpolate(linear, sample) t: f32,
    @location(1) @interpolate(flat) bits_a: u32,
    @location(2) @interpolate(flat) bits_b: u32,
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

// A quad corner: its clip position and its parameter t along the segment.
struct Corner {
    position: vec4<f32>,
    t: f32,
}

// View::triangles: corner `corner` of the `width_px` wide quad of the part
// of segment (a, b) in front of the near plane (near_clip), as lipp.raster
// draws that part. With no such part every corner is the same point outside
// the clip volume, so nothing is drawn.
fn quad_corner_clipped(a: vec4<f32>, b: vec4<f32>, corner: u32, width_px: f32, size: vec2<f32>, near: f32) -> Corner {
    let part = near_clip(a, b, near);
    let t = select(part.ta, part.tb, (corner & 1u) != 0u);
    if part.valid {
        return Corner(quad_corner(part.a, part.b, corner, 0.5 * width_px, size), t);
    }
    return Corner(vec4<f32>(2.0, 2.0, 2.0, 1.0), t);
}

// Segment::payload's 6-bit interpolation, operation for operation.
fn lerp6(a: u32, b: u32, t: f32) -> u32 {
    let fa = f32(a & 63u);
    let fb = f32(b & 63u);
    return quantize((fa + (fb - fa) * t) / 63.0, 63.0);
}

// Lipp's write_sample for one covered sample of a quad: position and t are
// the sample's, bits_a and bits_b the segment's. Tested as lipp.raster
// tests: against scene.depth and, after the first groom (model_index > 0),
// against hair_depth.
fn write_sample(position: vec4<f32>, t_in: f32, bits_a: u32, bits_b: u32, sample: u32, width: u32, height: u32, model_index: u32) {
    let x = u32(position.x);
    let y = u32(position.y);
    let z = position.z;
    if x >= width || y >= height || !(z >= 0.0 && z < 1.0) {
        return;
    }
    if z >= textureLoad(scene_depth, vec2<i32>(i32(x), i32(y)), 0).x {
        return;
    }
    let pixel = y * width + x;
    if model_index > 0u && z >= bitcast<f32>(hair_depth[pixel]) {
        return;
    }
    let t = clamp(t_in, 0.0, 1.0);
    let w = lerp6(bits_a >> 6u, bits_b >> 8u, t);
    let ao = lerp6(bits_a, bits_b >> 14u, t);
    let lo = (bits_a & 0xFFFFF000u) | (w << 6u) | ao;
    let hi = (depth_bits(z) << 8u) | (bits_b & 255u);
    let payload = (u64(hi) << 32u) | u64(lo);
    let pixels = width * height;
    if sample < min(8u, arrayLength(&gbuffer) / max(pixels, 1u)) {
        atomicMin(&gbuffer[sample * pixels + pixel], payload);
    }
}
