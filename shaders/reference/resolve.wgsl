// reference.resolve: per pixel, n x n stratified samples, every covering
// hair fragment blended front to back over the opaque image, no layer
// limit. Port of passes/src/reference/resolve.rs (which says what is and is
// not exact): a workgroup per 8x8 tile, a lane per pixel; every segment of
// the tile's list that reaches the pixel is tested at every sample, and
// each sample keeps the nearest (strands are opaque). Samples go in blocks
// of 64, so a lane walks the list once per block (256 samples: 4 times).

#import strandgraph::layout::FrameData
#import strandgraph::kulikov::F32_MAX
#import strandgraph::half::unpack_radiance
#import strandgraph::reference::{Ribbon, ribbon_unpack, ribbon_axis, ribbon_covers, ribbon_may_touch, ribbon_depth_at, ribbon_world_t, sample_position, REFERENCE_TILE}

struct ResolveParams {
    samples_per_axis: u32,
    width: u32,
    height: u32,
    tiles_x: u32,
}

@group(0) @binding(0) var<uniform> params: ResolveParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> reference_offsets: array<u32>;
@group(0) @binding(3) var<storage, read> reference_segments: array<u32>;
@group(0) @binding(4) var<storage, read> reference_ribbons: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> vertex_lighting: array<vec2<u32>>;
@group(0) @binding(6) var scene_depth: texture_2d<f32>;
@group(0) @binding(7) var output: texture_storage_2d<rgba16float, read_write>;

// Samples a lane resolves at a time (one 8 x 8 block of the pattern), and
// no fragment.
const BLOCK: u32 = 64u;
const NONE: u32 = 0xFFFFFFFFu;

// kulikov::compose::ndc_depth.
fn ndc_depth(w: f32) -> f32 {
    return frame.far * (w - frame.near) / (w * (frame.far - frame.near));
}

fn load_ribbon(id: u32) -> Ribbon {
    return ribbon_unpack(reference_ribbons[3u * id], reference_ribbons[3u * id + 1u], reference_ribbons[3u * id + 2u]);
}

fn lighting(r: Ribbon, t: f32) -> vec3<f32> {
    let a = unpack_radiance(vertex_lighting[r.va]);
    let b = unpack_radiance(vertex_lighting[r.vb]);
    return a + t * (b - a);
}

// One block's samples: positions, and the nearest fragment found so far.
struct Block {
    at: array<vec2<f32>, BLOCK>,
    z: array<f32, BLOCK>,
    id: array<u32, BLOCK>,
    // Samples of the block that exist (fewer than BLOCK when n < 8).
    count: u32,
}

// Sample k of the block keeps fragment `id` of ribbon r if it is nearer
// (ties to the lower segment id, so every backend picks alike).
fn consider(b: ptr<function, Block>, r: Ribbon, id: u32, k: u32) {
    if k >= (*b).count {
        return;
    }
    let t = ribbon_covers(r, (*b).at[k]);
    if t < 0.0 {
        return;
    }
    let z = ribbon_depth_at(r, t);
    let bz = (*b).z[k];
    if z < bz || (z == bz && id < (*b).id[k]) {
        (*b).z[k] = z;
        (*b).id[k] = id;
    }
}

// Eight samples in straight-line code, not a loop: lavapipe (llvmpipe)
// stops every loop of an invocation once it has run 65,535 iterations in
// all (LP_MAX_TGSI_LOOP_ITERATIONS), and a sample loop inside the list loop
// reached that on a few thousand segments.
fn consider_row(b: ptr<function, Block>, r: Ribbon, id: u32, row: u32) {
    let k = row * 8u;
    consider(b, r, id, k);
    consider(b, r, id, k + 1u);
    consider(b, r, id, k + 2u);
    consider(b, r, id, k + 3u);
    consider(b, r, id, k + 4u);
    consider(b, r, id, k + 5u);
    consider(b, r, id, k + 6u);
    consider(b, r, id, k + 7u);
}

@compute @workgroup_size(64)
fn resolve(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let x = wg.x % params.tiles_x * REFERENCE_TILE + lane % REFERENCE_TILE;
    let y = wg.x / params.tiles_x * REFERENCE_TILE + lane / REFERENCE_TILE;
    if x >= params.width || y >= params.height {
        return;
    }
    let capacity = arrayLength(&reference_segments);
    let end = min(reference_offsets[wg.x + 1u], capacity);
    let start = min(reference_offsets[wg.x], end);
    let n = params.samples_per_axis;
    let samples = n * n;
    let centre = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    let scene_z = textureLoad(scene_depth, vec2<u32>(x, y), 0).x;
    var sum = vec3<f32>(0.0);
    var bare = 0u;
    var b: Block;
    for (var first = 0u; first < samples; first += BLOCK) {
        b.count = min(samples - first, BLOCK);
        for (var k = 0u; k < b.count; k++) {
            b.at[k] = sample_position(x, y, params.width, n, first + k);
            b.z[k] = F32_MAX;
            b.id[k] = NONE;
        }
        for (var e = start; e < end; e++) {
            let id = reference_segments[e];
            let r = load_ribbon(id);
            if r.valid && ribbon_may_touch(r, centre, 0.5) {
                consider_row(&b, r, id, 0u);
                consider_row(&b, r, id, 1u);
                consider_row(&b, r, id, 2u);
                consider_row(&b, r, id, 3u);
                consider_row(&b, r, id, 4u);
                consider_row(&b, r, id, 5u);
                consider_row(&b, r, id, 6u);
                consider_row(&b, r, id, 7u);
            }
        }
        for (var k = 0u; k < b.count; k++) {
            let id = b.id[k];
            // The opaque scene is nearer: no hair at this sample.
            if id == NONE || ndc_depth(b.z[k]) > scene_z {
                bare += 1u;
                continue;
            }
            let r = load_ribbon(id);
            let t = max(ribbon_covers(r, b.at[k]), 0.0);
            sum += lighting(r, ribbon_world_t(r, t));
        }
    }
    let inv = 1.0 / f32(samples);
    let hair = sum * inv;
    let uncovered = f32(bare) * inv;
    let bg = textureLoad(output, vec2<u32>(x, y));
    textureStore(output, vec2<u32>(x, y), vec4<f32>(hair + uncovered * bg.rgb, 1.0 - uncovered * (1.0 - bg.a)));
}
