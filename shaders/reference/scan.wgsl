// reference.scan: the tiles' list offsets (exclusive prefix sum of the
// counts) and, after them, the total. Port of passes/src/reference/scan.rs,
// on strandgraph::scan (as kulikov/sort.wgsl's scan).

#import strandgraph::scan::{scan_run, scan_lanes, scan_total, SCAN_LANES}

struct ScanParams {
    tiles: u32,
}

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read> reference_counts: array<u32>;
@group(0) @binding(2) var<storage, read_write> reference_offsets: array<u32>;

@compute @workgroup_size(256)
fn scan(@builtin(local_invocation_index) lane: u32) {
    let n = params.tiles;
    let run = scan_run(lane, n);
    var sum = 0u;
    for (var t = run.x; t < run.y; t++) {
        sum += reference_counts[t];
    }
    var offset = scan_lanes(lane, sum);
    for (var t = run.x; t < run.y; t++) {
        reference_offsets[t] = offset;
        offset += reference_counts[t];
    }
    if lane == SCAN_LANES - 1u {
        reference_offsets[n] = scan_total();
    }
}
