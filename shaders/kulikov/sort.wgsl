// kulikov.sort_scan (`scan`) and kulikov.sort (`scatter`): a global counting
// sort of visible segments into 64x64 screen buckets.
// Port of passes/src/kulikov/sort.rs.

// Bindings 1..=3 (frame, models, lod_models) are declared in segments.wgsl.
#define FRAME_BINDING 1
#define MODELS_BINDING 2
#define LOD_MODELS_BINDING 3
#import strandgraph::kulikov_segments::{frame, models, lod_models, nth_drawn}
#import strandgraph::clip::{clip_to_screen, near_clip}
#import strandgraph::kulikov::{screen_bin, DrawnSegment}
#import strandgraph::scan::{scan_run, scan_lanes, scan_total, SCAN_LANES}
#import strandgraph::subgroup::elected

struct SortParams {
    // kulikov.sort `enabled` (scatter only).
    enabled: u32,
    // Scene quantities: segments in the full numbering, and sort bins
    // (64x64 screen tiles); the word after the bins is the arrival counter.
    segments: u32,
    bins: u32,
    // kulikov.sort `wave_aggregated_atomics` (scatter only).
    aggregate: u32,
}

@group(0) @binding(0) var<uniform> params: SortParams;

// --- scan: sort_bins, sort_offsets, raster_args ---
// Both entry points bind `sort_offsets` at different numbers (binding 2
// written here, binding 6 atomic in scatter), so this one carries the
// entry point as a prefix (`scan_sort_offsets`); passes/tests/wgsl_bindings.rs
// accepts `<entry>_<binding>` names for that reason.
@group(0) @binding(1) var<storage, read> sort_bins: array<u32>;
@group(0) @binding(2) var<storage, read_write> scan_sort_offsets: array<u32>;
@group(0) @binding(3) var<storage, read_write> raster_args: array<u32>;

// Raster workgroup size (raster::GROUP).
const RASTER_GROUP: u32 = 256u;

@compute @workgroup_size(256)
fn scan(@builtin(local_invocation_index) lane: u32) {
    let bins = params.bins;
    let run = scan_run(lane, bins);
    var sum = 0u;
    for (var b = run.x; b < run.y; b++) {
        sum += sort_bins[b];
    }
    var offset = scan_lanes(lane, sum);
    for (var b = run.x; b < run.y; b++) {
        scan_sort_offsets[b] = offset;
        offset += sort_bins[b];
    }
    if lane == SCAN_LANES - 1u {
        let total = scan_total();
        // Header after the bins: the arrival counter the unsorted variant uses.
        scan_sort_offsets[bins] = 0u;
        raster_args[0] = (total + RASTER_GROUP - 1u) / RASTER_GROUP;
        raster_args[1] = 1u;
        raster_args[2] = 1u;
        raster_args[3] = total;
    }
}

// --- scatter: frame, models, lod_models, clip_positions, segment_visibility,
// sort_offsets, sorted_segments, lod_args ---
@group(0) @binding(4) var<storage, read> clip_positions: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> segment_visibility: array<u32>;
@group(0) @binding(6) var<storage, read_write> sort_offsets: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> sorted_segments: array<u32>;
// lod::drawn_dispatch at word 4: the dispatch over drawn segments, whose
// count is word 7.
@group(0) @binding(8) var<storage, read> lod_args: array<u32>;

const GROUP: u32 = 256u;
const NONE: u32 = 0xFFFFFFFFu;

// ScatterKernel::bucket: the bucket drawn segment `seg` (global `id`) goes
// to, NONE when it is not visible.
fn bucket(seg: DrawnSegment, id: u32) -> u32 {
    if !seg.valid || id >= params.segments || (segment_visibility[id / 32u] & (1u << (id % 32u))) == 0u {
        return NONE;
    }
    if params.enabled == 0u {
        return params.bins;
    }
    let w = frame.screen.x;
    let h = frame.screen.y;
    // The bin the cull counted: that of the part in front of the near plane.
    let part = near_clip(clip_positions[seg.va], clip_positions[seg.vb], frame.near);
    return screen_bin(w, h, clip_to_screen(part.a, w, h), clip_to_screen(part.b, w, h));
}

// One invocation per drawn segment (cull::nth_drawn), striding when the
// dispatch was capped; the round count is workgroup-uniform.
@compute @workgroup_size(256)
fn scatter(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
    @builtin(subgroup_invocation_id) lane: u32,
) {
    let stride = groups.x * GROUP;
    let drawn = lod_args[7];
    for (var first = wg.x * GROUP; first < drawn; first += stride) {
        scatter_one(first + index, lane);
    }
}

fn scatter_one(d: u32, lane: u32) {
    let seg = nth_drawn(d);
    let id = models[seg.model].segment_first + seg.local;
    let key = bucket(seg, id);
    if params.aggregate == 0u {
        if key != NONE {
            sorted_segments[atomicAdd(&sort_offsets[key], 1u)] = id;
        }
        return;
    }
    // Ours: one atomicAdd per subgroup and bucket, the subgroup's lanes of
    // that bucket taking consecutive slots in lane order. The loop
    // condition is subgroup-uniform, so all lanes run the collectives.
    var pending = key != NONE;
    loop {
        let k = subgroupMin(select(NONE, key, pending));
        if k == NONE {
            break;
        }
        let mine = pending && key == k;
        let n = subgroupAdd(select(0u, 1u, mine));
        let rank = subgroupExclusiveAdd(select(0u, 1u, mine));
        var base = 0u;
        if elected(lane) {
            base = atomicAdd(&sort_offsets[k], n);
        }
        // The elected lane is the lowest active one, as subgroupBroadcastFirst reads.
        base = subgroupBroadcastFirst(base);
        if mine {
            sorted_segments[base + rank] = id;
        }
        pending = pending && !mine;
    }
}
