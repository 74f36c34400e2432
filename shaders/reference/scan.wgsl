// reference.scan: the tiles' list offsets (exclusive prefix sum of the
// counts) and, after them, the total. Port of passes/src/reference/scan.rs;
// the shape of kulikov/sort.wgsl's scan: each lane sums a run of tiles,
// the lanes' sums are scanned in workgroup memory (Hillis and Steele),
// then each lane writes its run.

struct ScanParams {
    tiles: u32,
}

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read> reference_counts: array<u32>;
@group(0) @binding(2) var<storage, read_write> reference_offsets: array<u32>;

const LANES: u32 = 256u;
var<workgroup> lane_sums: array<u32, LANES>;

@compute @workgroup_size(256)
fn scan(@builtin(local_invocation_index) lane: u32) {
    let n = params.tiles;
    let per = (n + LANES - 1u) / LANES;
    let first = min(lane * per, n);
    let last = min(first + per, n);
    var sum = 0u;
    for (var t = first; t < last; t++) {
        sum += reference_counts[t];
    }
    lane_sums[lane] = sum;
    workgroupBarrier();
    for (var d = 1u; d < LANES; d <<= 1u) {
        var v = lane_sums[lane];
        if lane >= d {
            v += lane_sums[lane - d];
        }
        workgroupBarrier();
        lane_sums[lane] = v;
        workgroupBarrier();
    }
    var run = 0u;
    if lane > 0u {
        run = lane_sums[lane - 1u];
    }
    for (var t = first; t < last; t++) {
        reference_offsets[t] = run;
        run += reference_counts[t];
    }
    if lane == LANES - 1u {
        reference_offsets[n] = lane_sums[LANES - 1u];
    }
}
