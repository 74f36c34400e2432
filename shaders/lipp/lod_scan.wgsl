// lipp.lod_scan: the exclusive prefix sum of lipp.lod's strand counts into
// bundle_lod's first strands, and the rasterizer's indirect dispatch. Port of
// passes/src/lipp/lod/scan.rs: one workgroup of 256 lanes, each owning a
// contiguous run of bundles; the lanes' sums are scanned in workgroup memory
// (Hillis and Steele), then each lane writes its run.

#import strandgraph::lipp_rect::{ARGS_RECT_LO, ARGS_RECT_HI, ARGS_RUNS, rect_union, rect_is_empty, unpack_tiles, rect_args, rect_runs}
#import strandgraph::lipp::{BUNDLE_WORDS, LOD_WORDS, MAX_GROUPS_X, LOD_OTHER_GROOM, LOD_CULLED}

struct ScanParams {
    // Scene quantity: bundles packed.
    bundles: u32,
    // Scene quantities: the screen.
    width: u32,
    height: u32,
    // Ours: off, the rectangle is the whole screen (scan.rs).
    groom_rect: u32,
    // The groom scanned (the per-model block), or ALL_MODELS.
    model: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// lod::ALL_MODELS.
const ALL_MODELS: u32 = 0xFFFFFFFFu;

// The first of the first `count` bundles whose groom is at least `m`
// (upload.rs packs grooms' bundles together, in model order).
fn first_of_groom(count: u32, m: u32) -> u32 {
    var lo = 0u;
    var hi = count;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if hairmesh_bundles[mid * BUNDLE_WORDS + 3u] < m {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// lipp::groom_bundles: [first, end) of this groom's bundles.
fn groom_bundles(count: u32) -> vec2<u32> {
    if params.model == ALL_MODELS {
        return vec2<u32>(0u, count);
    }
    return vec2<u32>(first_of_groom(count, params.model), first_of_groom(count, params.model + 1u));
}

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read> hairmesh_bundles: array<u32>;
@group(0) @binding(2) var<storage, read> lod_choices: array<u32>;
@group(0) @binding(3) var<storage, read_write> bundle_lod: array<u32>;
@group(0) @binding(4) var<storage, read_write> raster_args: array<u32>;

// scan::SCAN_GROUP.
const SCAN_GROUP: u32 = 256u;

var<workgroup> sums: array<u32, SCAN_GROUP>;
var<workgroup> full_sums: array<u32, SCAN_GROUP>;
var<workgroup> kept_sums: array<u32, SCAN_GROUP>;
// The drawn bundles' screen rectangle (rect.rs): min x0, y0 and max x1, y1.
var<workgroup> groom_rect: array<atomic<u32>, 4>;

// scan.rs: a frustum-culled bundle draws none of the strands it keeps.
fn drawn(b: u32) -> u32 {
    return select(lod_choices[b * LOD_WORDS], 0u, (lod_choices[b * LOD_WORDS + 3u] & LOD_CULLED) != 0u);
}

@compute @workgroup_size(256)
fn scan(@builtin(local_invocation_index) lane: u32) {
    let count = min(min(params.bundles, arrayLength(&hairmesh_bundles) / BUNDLE_WORDS), min(arrayLength(&lod_choices), arrayLength(&bundle_lod)) / LOD_WORDS);
    // Each lane owns a run of this groom's bundles.
    let range = groom_bundles(count);
    let per = (range.y - range.x + SCAN_GROUP - 1u) / SCAN_GROUP;
    let begin = min(range.x + lane * per, range.y);
    let end = min(begin + per, range.y);
    if lane == 0u {
        atomicStore(&groom_rect[0], 0xFFFFFFFFu);
        atomicStore(&groom_rect[1], 0xFFFFFFFFu);
        atomicStore(&groom_rect[2], 0u);
        atomicStore(&groom_rect[3], 0u);
    }
    workgroupBarrier();
    var sum = 0u;
    var full = 0u;
    var kept = 0u;
    var rect = vec4<u32>(0u);
    for (var b = begin; b < end; b++) {
        sum += drawn(b);
        if drawn(b) > 0u {
            rect = rect_union(rect, unpack_tiles(lod_choices[b * LOD_WORDS + 2u], params.width, params.height));
        }
        if (lod_choices[b * LOD_WORDS + 3u] & LOD_OTHER_GROOM) == 0u {
            full += hairmesh_bundles[b * BUNDLE_WORDS + 2u];
            kept += lod_choices[b * LOD_WORDS];
        }
    }
    if !rect_is_empty(rect) {
        atomicMin(&groom_rect[0], rect.x);
        atomicMin(&groom_rect[1], rect.y);
        atomicMax(&groom_rect[2], rect.z);
        atomicMax(&groom_rect[3], rect.w);
    }
    sums[lane] = sum;
    full_sums[lane] = full;
    kept_sums[lane] = kept;
    workgroupBarrier();
    // Inclusive scans of the lanes' sums.
    for (var d = 1u; d < SCAN_GROUP; d <<= 1u) {
        var v = sums[lane];
        var f = full_sums[lane];
        var k = kept_sums[lane];
        if lane >= d {
            v += sums[lane - d];
            f += full_sums[lane - d];
            k += kept_sums[lane - d];
        }
        workgroupBarrier();
        sums[lane] = v;
        full_sums[lane] = f;
        kept_sums[lane] = k;
        workgroupBarrier();
    }
    var first = 0u;
    if lane > 0u {
        first = sums[lane - 1u];
    }
    for (var b = begin; b < end; b++) {
        let o = b * LOD_WORDS;
        let n = drawn(b);
        bundle_lod[o] = n;
        bundle_lod[o + 1u] = lod_choices[o + 1u];
        bundle_lod[o + 2u] = first;
        bundle_lod[o + 3u] = lod_choices[o + 3u];
        first += n;
    }
    // Every other groom's bundle: no strands, its first strand where the
    // running sum is (the rasterizer's search skips it).
    let total = sums[SCAN_GROUP - 1u];
    let per_all = (count + SCAN_GROUP - 1u) / SCAN_GROUP;
    for (var b = lane * per_all; b < min(lane * per_all + per_all, count); b++) {
        if b >= range.x && b < range.y {
            continue;
        }
        let o = b * LOD_WORDS;
        bundle_lod[o] = 0u;
        bundle_lod[o + 1u] = 0u;
        bundle_lod[o + 2u] = select(total, 0u, b < range.x);
        bundle_lod[o + 3u] = LOD_OTHER_GROOM;
    }
    if lane == SCAN_GROUP - 1u {
        raster_args[0] = min(total, MAX_GROUPS_X);
        raster_args[1] = 1u;
        raster_args[2] = 1u;
        raster_args[3] = total;
        // β of Lipp Eq. 8 is word 5 / word 4 (lipp::ARGS_KEPT, ARGS_ALL).
        raster_args[4] = full_sums[SCAN_GROUP - 1u];
        raster_args[5] = kept_sums[SCAN_GROUP - 1u];
        // The drawn bundles' screen rectangle and the dispatch over its
        // runs, if there is room.
        var groom = vec4<u32>(atomicLoad(&groom_rect[0]), atomicLoad(&groom_rect[1]), atomicLoad(&groom_rect[2]), atomicLoad(&groom_rect[3]));
        if rect_is_empty(groom) {
            groom = vec4<u32>(0u);
        }
        if params.groom_rect == 0u {
            groom = vec4<u32>(0u, 0u, params.width, params.height);
        }
        if arrayLength(&raster_args) > ARGS_RECT_HI {
            let a = rect_args(groom);
            raster_args[ARGS_RECT_LO] = a.x;
            raster_args[ARGS_RECT_HI] = a.y;
        }
        if arrayLength(&raster_args) > ARGS_RUNS + 2u {
            raster_args[ARGS_RUNS] = min(rect_runs(groom, params.width).y, MAX_GROUPS_X);
            raster_args[ARGS_RUNS + 1u] = 1u;
            raster_args[ARGS_RUNS + 2u] = 1u;
        }
    }
}
