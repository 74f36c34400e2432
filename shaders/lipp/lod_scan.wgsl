// lipp.lod_scan: the exclusive prefix sum of lipp.lod's strand counts into
// bundle_lod's first strands, and the rasterizer's indirect dispatch. Port of
// passes/src/lipp/lod/scan.rs: one workgroup of 256 lanes, each owning a
// contiguous run of bundles; the lanes' sums are scanned in workgroup memory
// (Hillis and Steele), then each lane writes its run.

#import strandgraph::lipp_rect::{ARGS_RECT_LO, ARGS_RECT_HI, ARGS_RUNS, ARGS_CLEAR, rect_union, rect_is_empty, unpack_tiles, rect_args, rect_runs, run_groups}
#import strandgraph::lipp::{BUNDLE_WORDS, MAX_GROUPS_X, LOD_OTHER_GROOM, LOD_CULLED, ARGS_BUNDLES_LO, ARGS_BUNDLES_HI}

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
    // Ours: runs a lipp.clear_gbuffer workgroup clears (scan.rs).
    clear_runs: u32,
    _pad1: u32,
    _pad2: u32,
}

// lod::ALL_MODELS.
const ALL_MODELS: u32 = 0xFFFFFFFFu;

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read> hairmesh_bundles: array<u32>;
// A bundle's record (lipp::LOD_WORDS, 4 words) as one load and one store.
@group(0) @binding(2) var<storage, read> lod_choices: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read_write> bundle_lod: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read_write> raster_args: array<u32>;

// scan::SCAN_GROUP.
const SCAN_GROUP: u32 = 256u;

var<workgroup> sums: array<u32, SCAN_GROUP>;
var<workgroup> full_sums: array<u32, SCAN_GROUP>;
var<workgroup> kept_sums: array<u32, SCAN_GROUP>;
// The drawn bundles' screen rectangle (rect.rs): min x0, y0 and max x1, y1.
var<workgroup> groom_rect: array<atomic<u32>, 4>;

// Bundles whose groom is below the scanned one, and at most it, counted in
// two rounds by the whole workgroup (upload.rs packs grooms' bundles
// together, in model order, so each count is where a run starts).
var<workgroup> below: array<atomic<u32>, 2>;

fn model_of(b: u32) -> u32 {
    return hairmesh_bundles[b * BUNDLE_WORDS + 3u];
}

// lipp::groom_bundles: [first, end) of the groom's bundles. Round one finds
// the chunk of SCAN_GROUP bundles each boundary lies in, round two the
// bundle. Every lane calls it (it has barriers).
fn groom_bundles(count: u32, lane: u32) -> vec2<u32> {
    let m = params.model;
    let chunk = max((count + SCAN_GROUP - 1u) / SCAN_GROUP, 1u);
    if lane < 2u {
        atomicStore(&below[lane], 0u);
    }
    workgroupBarrier();
    // Chunks whose first bundle lies before each boundary.
    if lane * chunk < count {
        let g = model_of(lane * chunk);
        if lane > 0u && g < m {
            atomicAdd(&below[0], 1u);
        }
        if lane > 0u && g <= m {
            atomicAdd(&below[1], 1u);
        }
    }
    workgroupBarrier();
    let start = vec2<u32>(atomicLoad(&below[0]), atomicLoad(&below[1])) * chunk;
    workgroupBarrier();
    if lane < 2u {
        atomicStore(&below[lane], 0u);
    }
    workgroupBarrier();
    // Within each boundary's chunk.
    for (var i = lane; i < chunk; i += SCAN_GROUP) {
        if start.x + i < count && model_of(start.x + i) < m {
            atomicAdd(&below[0], 1u);
        }
        if start.y + i < count && model_of(start.y + i) <= m {
            atomicAdd(&below[1], 1u);
        }
    }
    workgroupBarrier();
    let r = min(start + vec2<u32>(atomicLoad(&below[0]), atomicLoad(&below[1])), vec2<u32>(count));
    workgroupBarrier();
    if params.model == ALL_MODELS || arrayLength(&raster_args) <= ARGS_BUNDLES_HI {
        return vec2<u32>(0u, count);
    }
    return r;
}

// scan.rs: a frustum-culled bundle draws none of the strands it keeps.
fn drawn(c: vec4<u32>) -> u32 {
    return select(c.x, 0u, (c.w & LOD_CULLED) != 0u);
}

@compute @workgroup_size(256)
fn scan(@builtin(local_invocation_index) lane: u32) {
    let count = min(min(params.bundles, arrayLength(&hairmesh_bundles) / BUNDLE_WORDS), min(arrayLength(&lod_choices), arrayLength(&bundle_lod)));
    // Each lane owns a run of this groom's bundles.
    let range = groom_bundles(count, lane);
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
        let c = lod_choices[b];
        let n = drawn(c);
        sum += n;
        if n > 0u {
            rect = rect_union(rect, unpack_tiles(c.z, params.width, params.height));
        }
        if (c.w & LOD_OTHER_GROOM) == 0u {
            full += hairmesh_bundles[b * BUNDLE_WORDS + 2u];
            kept += c.x;
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
        let c = lod_choices[b];
        let n = drawn(c);
        bundle_lod[b] = vec4<u32>(n, c.y, first, c.w);
        first += n;
    }
    if lane == SCAN_GROUP - 1u {
        let total = sums[SCAN_GROUP - 1u];
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
        if arrayLength(&raster_args) > ARGS_BUNDLES_HI {
            raster_args[ARGS_BUNDLES_LO] = range.x;
            raster_args[ARGS_BUNDLES_HI] = range.y;
        }
        if arrayLength(&raster_args) > ARGS_RUNS + 2u {
            raster_args[ARGS_RUNS] = run_groups(rect_runs(groom, params.width).y, 1u);
            raster_args[ARGS_RUNS + 1u] = 1u;
            raster_args[ARGS_RUNS + 2u] = 1u;
        }
        // rect::Rect::run_dispatch, again in blocks of clear_runs.
        if arrayLength(&raster_args) > ARGS_CLEAR + 2u {
            raster_args[ARGS_CLEAR] = run_groups(rect_runs(groom, params.width).y, params.clear_runs);
            raster_args[ARGS_CLEAR + 1u] = 1u;
            raster_args[ARGS_CLEAR + 2u] = 1u;
        }
    }
}
