// kulikov.cull: frustum, occlusion and fedora culling per segment; raises a
// visibility bit, grows the model's screen bounds and counts sort bins.
// Port of passes/src/kulikov/cull.rs. With `wave_aggregated_atomics` each
// subgroup issues one atomic per distinct target (subgroupOr for visibility
// words, subgroupMin for bounds, subgroupAdd for bins, written by one
// elected lane), as Kulikov: "utilize wave intrinsics and only do actual
// atomic write once per wave". The memory left behind is the same either way.

// Bindings 1..=3 (frame, models, lod_models) are declared in segments.wgsl.
#define FRAME_BINDING 1
#define MODELS_BINDING 2
#define LOD_MODELS_BINDING 3
#import strandgraph::kulikov_segments::{frame, models, lod_models, nth_drawn}
#import strandgraph::layout::ModelData
#import strandgraph::clip::{transform, clip_to_screen, near_clip}
#import strandgraph::kulikov::{DrawnSegment, screen_bin}
#import strandgraph::hiz::hiz_farthest
#import strandgraph::subgroup::elected

struct CullParams {
    frustum: u32,
    occlusion: u32,
    fedora: u32,
    wave_aggregated_atomics: u32,
    // Scene quantity: segments in the full numbering.
    segments: u32,
}

@group(0) @binding(0) var<uniform> params: CullParams;
@group(0) @binding(4) var<storage, read> clip_positions: array<vec4<f32>>;
@group(0) @binding(5) var hiz: texture_2d<f32>;
// One bit per segment.
@group(0) @binding(6) var<storage, read_write> segment_visibility: array<atomic<u32>>;
// Per model: min x, min y, !max x, !max y (all atomicMin).
@group(0) @binding(7) var<storage, read_write> screen_bounds: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> sort_bins: array<atomic<u32>>;
// lod::drawn_dispatch at word 4: the dispatch over drawn segments, whose
// count is word 7.
@group(0) @binding(9) var<storage, read> lod_args: array<u32>;

const GROUP: u32 = 256u;
const NONE: u32 = 0xFFFFFFFFu;

// cull::fedora_culls: inside the exclusion box and outside the inclusion sphere.
fn fedora_culls(m: ModelData, p: vec3<f32>) -> bool {
    if m.fedora_min.w == 0.0 {
        return false;
    }
    let in_box = all(p >= m.fedora_min.xyz) && all(p <= m.fedora_max.xyz);
    let d = vec3<f32>(p.x - m.fedora_sphere.x, p.y - m.fedora_sphere.y, p.z - m.fedora_sphere.z);
    let d2 = d.x * d.x + d.y * d.y + d.z * d.z;
    return in_box && d2 > m.fedora_sphere.w * m.fedora_sphere.w;
}

fn to_world(c: vec4<f32>) -> vec3<f32> {
    let p = transform(frame.inv_view_proj, c);
    return vec3<f32>(p.x / p.w, p.y / p.w, p.z / p.w);
}

struct Verdict {
    visible: bool,
    bounds: vec4<u32>,
    bin: u32,
}

// CullKernel::test.
fn test(seg: DrawnSegment, c0_in: vec4<f32>, c1_in: vec4<f32>) -> Verdict {
    var out = Verdict(false, vec4<u32>(0u), 0u);
    // Only the part in front of the near plane is drawn.
    let part = near_clip(c0_in, c1_in, frame.near);
    if !part.valid {
        return out;
    }
    let c0 = part.a;
    let c1 = part.b;
    if params.frustum != 0u {
        let right = c0.x > c0.w && c1.x > c1.w;
        let left = -c0.x > c0.w && -c1.x > c1.w;
        let top = c0.y > c0.w && c1.y > c1.w;
        let bottom = -c0.y > c0.w && -c1.y > c1.w;
        let far = c0.z > c0.w && c1.z > c1.w;
        if right || left || top || bottom || far || (c0.z < 0.0 && c1.z < 0.0) {
            return out;
        }
    }
    if params.fedora != 0u {
        let m = models[seg.model];
        if fedora_culls(m, to_world(c0)) && fedora_culls(m, to_world(c1)) {
            return out;
        }
    }
    let w = frame.screen.x;
    let h = frame.screen.y;
    let s0 = clip_to_screen(c0, w, h);
    let s1 = clip_to_screen(c1, w, h);
    let bounds = vec4<u32>(
        u32(clamp(min(s0.x, s1.x), 0.0, w - 1.0)),
        u32(clamp(min(s0.y, s1.y), 0.0, h - 1.0)),
        u32(clamp(max(s0.x, s1.x), 0.0, w - 1.0)),
        u32(clamp(max(s0.y, s1.y), 0.0, h - 1.0)),
    );
    // hiz_farthest: long segments span many blocks and are not tested.
    if params.occlusion != 0u && min(s0.z, s1.z) > hiz_farthest(hiz, bounds) {
        return out;
    }
    out.visible = true;
    out.bounds = bounds;
    out.bin = screen_bin(w, h, s0, s1);
    return out;
}

// One invocation per drawn segment (cull::nth_drawn), striding when the
// dispatch was capped; the round count is workgroup-uniform, so every lane
// reaches the subgroup operations.
@compute @workgroup_size(256)
fn cull(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
    @builtin(subgroup_invocation_id) lane: u32,
) {
    let stride = groups.x * GROUP;
    let drawn = lod_args[7];
    for (var first = wg.x * GROUP; first < drawn; first += stride) {
        cull_one(first + index, lane);
    }
}

fn cull_one(d: u32, lane: u32) {
    let seg = nth_drawn(d);
    let id = models[seg.model].segment_first + seg.local;
    var v = Verdict(false, vec4<u32>(0u), 0u);
    var model = 0u;
    // No early return: every lane reaches the subgroup operations below.
    if seg.valid && id < params.segments {
        v = test(seg, clip_positions[seg.va], clip_positions[seg.vb]);
        model = seg.model;
    }
    let word = id / 32u;
    let bit = 1u << (id % 32u);
    // Maxima are stored inverted so that all four bounds are atomicMin.
    let inverted = vec4<u32>(v.bounds.x, v.bounds.y, ~v.bounds.z, ~v.bounds.w);

    if params.wave_aggregated_atomics == 0u {
        if v.visible {
            atomicOr(&segment_visibility[word], bit);
            atomicMin(&screen_bounds[4u * model], inverted.x);
            atomicMin(&screen_bounds[4u * model + 1u], inverted.y);
            atomicMin(&screen_bounds[4u * model + 2u], inverted.z);
            atomicMin(&screen_bounds[4u * model + 3u], inverted.w);
            atomicAdd(&sort_bins[v.bin], 1u);
        }
        return;
    }

    // One atomic per distinct target and subgroup. Each loop takes the
    // smallest pending key of the subgroup; the loop condition is
    // subgroup-uniform, so all lanes run the collectives together.
    var pending = v.visible;
    loop {
        let key = subgroupMin(select(NONE, word, pending));
        if key == NONE {
            break;
        }
        let mine = pending && word == key;
        let mask = subgroupOr(select(0u, bit, mine));
        if elected(lane) {
            atomicOr(&segment_visibility[key], mask);
        }
        pending = pending && !mine;
    }
    pending = v.visible;
    loop {
        let key = subgroupMin(select(NONE, model, pending));
        if key == NONE {
            break;
        }
        let mine = pending && model == key;
        let b = vec4<u32>(
            subgroupMin(select(NONE, inverted.x, mine)),
            subgroupMin(select(NONE, inverted.y, mine)),
            subgroupMin(select(NONE, inverted.z, mine)),
            subgroupMin(select(NONE, inverted.w, mine)),
        );
        if elected(lane) {
            atomicMin(&screen_bounds[4u * key], b.x);
            atomicMin(&screen_bounds[4u * key + 1u], b.y);
            atomicMin(&screen_bounds[4u * key + 2u], b.z);
            atomicMin(&screen_bounds[4u * key + 3u], b.w);
        }
        pending = pending && !mine;
    }
    pending = v.visible;
    loop {
        let key = subgroupMin(select(NONE, v.bin, pending));
        if key == NONE {
            break;
        }
        let mine = pending && v.bin == key;
        let n = subgroupAdd(select(0u, 1u, mine));
        if elected(lane) {
            atomicAdd(&sort_bins[key], n);
        }
        pending = pending && !mine;
    }
}
