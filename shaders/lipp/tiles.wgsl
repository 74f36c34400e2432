// The tiles with hair (ours): lipp.shade lists them, lipp.filter runs over
// them through the indirect dispatch the list sizes. Port of
// passes/src/lipp/tiles.rs (why a far groom's filter runs wider there).
#define_import_path strandgraph::lipp_tiles

#import strandgraph::lipp::MAX_GROUPS_X

// tiles::{TILE, FILTER_GROUP, MAX_FILTER_LANES}.
const TILE: u32 = 64u;
const FILTER_GROUP: u32 = 128u;
const MAX_FILTER_LANES: u32 = 16u;

// tiles::filter_groups: workgroups for n listed tiles, at the most lanes a
// pixel whose lanes fit `budget`; non-decreasing in n.
fn filter_groups(n: u32, budget: u32) -> u32 {
    var groups = n;
    for (var lanes = 4u; lanes <= MAX_FILTER_LANES; lanes *= 2u) {
        let fit = budget / (TILE * lanes);
        groups = max(groups, min(n, fit) * (lanes * TILE / FILTER_GROUP));
    }
    return min(groups, MAX_GROUPS_X);
}

// tiles::filter_lanes: lanes a pixel the dispatch holds, at most `most`,
// at least two (or `most`).
fn filter_lanes(groups: u32, n: u32, most: u32) -> u32 {
    var lanes = min(most, 2u);
    // groups * 2 >= n * wider, each side split so as not to overflow.
    loop {
        let wider = lanes * 2u;
        if wider > most || (n > 0u && (groups * 2u) / wider < n) {
            break;
        }
        lanes = wider;
    }
    return lanes;
}
