//! The tiles with hair (ours): `lipp.shade` lists the 64-pixel tiles (its
//! workgroups, runs of 64 pixels in row order) where either G-buffer layer
//! holds a sample, and `lipp.filter` runs one workgroup per listed tile
//! through an indirect dispatch, not one per tile of the screen.
//!
//! A workgroup per tile of the screen cost every groom a full-screen pass
//! however small it is on screen, and the graph draws grooms one after
//! another (Lipp §3.5). On the H100 the list took the crowd's 28 grooms
//! from 8.65 to 7.74 ms and the MSAA reference's SWR 8 from 45.6 to
//! 28.5 ms (there `lipp.shade` also stopped writing every empty sample
//! layer); at one head's close / mid / far views the filter went 0.49 /
//! 0.17 / 0.13 to 0.44 / 0.14 / 0.11 ms, the rest being Code 2's window.
//! The list's order is the order tiles finish shading, which does not
//! change the image: each tile is filtered on its own. With the shade's
//! `hair_tiles` off every tile is listed (the bench row "filter over every
//! tile"; its atomics make it slower than the direct dispatch it replaced).
//!
//! How wide the filter runs (ours): a pixel's window is one lane's long
//! chain of taps, so a far groom, whose few tiles leave most of the GPU
//! idle, waits on that chain. The list therefore sizes the filter's
//! dispatch for as many lanes a pixel (up to [`MAX_FILTER_LANES`]) as fit
//! `lipp.shade`'s `filter_lane_budget`, and the filter splits each window
//! over the lanes its dispatch gives it ([`filter_lanes`]), within a
//! subgroup: sixteen lanes a pixel for the far view's 191 tiles, two for the
//! close view's, whose tiles already fill the GPU (eight there made the
//! filter 0.18 → 0.32 ms on the H200; benches/results/lipp-filter-lanes-h200.txt).

use super::MAX_GROUPS_X;
use crate::kernel::Words;

/// Pixels per tile: `lipp.shade`'s and `lipp.filter`'s workgroup size.
pub const TILE: u32 = 64;
/// `filter_args` words: the dispatch (0-2) and the tiles listed (3).
pub const ARGS_TILES: usize = 3;

/// `lipp.filter`'s workgroup: 128 lanes (filter.rs `FILTER_GROUP`).
pub const FILTER_GROUP: u32 = 2 * TILE;
/// The most lanes a pixel the filter's dispatch is sized for.
pub const MAX_FILTER_LANES: u32 = 16;

/// Workgroups of [`FILTER_GROUP`] lanes for `n` listed tiles: a workgroup a
/// tile (two lanes a pixel), or more, up to [`MAX_FILTER_LANES`] lanes a
/// pixel, while the tiles' lanes fit `budget` (0: a workgroup a tile).
/// Non-decreasing in `n`, so the largest over the tiles as they are listed
/// is the final count's.
pub fn filter_groups(n: u32, budget: u32) -> u32 {
    let mut groups = n;
    let mut lanes = 4;
    while lanes <= MAX_FILTER_LANES {
        let fit = budget / (TILE * lanes);
        groups = groups.max(n.min(fit) * (lanes * TILE / FILTER_GROUP));
        lanes *= 2;
    }
    groups.min(MAX_GROUPS_X)
}

/// Lanes a pixel `lipp.filter` takes over `n` listed tiles with `groups`
/// workgroups: the most, up to `most` (a power of two), that the dispatch
/// holds, and at least two (or `most`), striding past what it holds.
pub fn filter_lanes(groups: u32, n: u32, most: u32) -> u32 {
    let mut lanes = most.min(2);
    // groups * FILTER_GROUP >= n * TILE * wider, without the overflow.
    while lanes * 2 <= most && u64::from(groups) * 2 >= u64::from(n) * u64::from(lanes * 2) {
        lanes *= 2;
    }
    lanes
}

/// Appends tile `t` to `filter_tiles` and grows the dispatch in
/// `filter_args` to cover it at the lanes `budget` allows
/// ([`filter_groups`]; the filter strides past 65,535 workgroups).
/// The first tile listed sets the dispatch's other two dimensions: every
/// tile writing them would add two more atomics on the one hot address.
pub fn list(args: &Words<'_>, tiles: &Words<'_>, t: u32, budget: u32) {
    let k = args.fetch_add(ARGS_TILES, 1);
    tiles.store(k as usize, t);
    args.fetch_max(0, filter_groups(k + 1, budget));
    if k == 0 {
        args.store(1, 1);
        args.store(2, 1);
    }
}

/// The tiles listed in `filter_args` (at most what `filter_tiles` holds).
pub fn listed(args: &Words<'_>, tiles: &Words<'_>) -> u32 {
    args.load(ARGS_TILES).min(tiles.len() as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU32, AtomicU64};

    #[test]
    fn listed_tiles_are_appended_and_the_dispatch_covers_them() {
        let oob = AtomicU64::new(0);
        let (args, tiles): (Vec<AtomicU32>, Vec<AtomicU32>) = (
            (0..4).map(|_| AtomicU32::new(0)).collect(),
            (0..8).map(|_| AtomicU32::new(0)).collect(),
        );
        let (a, t) = (Words::new(&args, &oob), Words::new(&tiles, &oob));
        for tile in [7, 3, 12] {
            list(&a, &t, tile, 0);
        }
        assert_eq!([0, 1, 2, 3].map(|i| a.load(i)), [3, 1, 1, 3]);
        assert_eq!([0, 1, 2].map(|i| t.load(i)), [7, 3, 12]);
        assert_eq!(listed(&a, &t), 3);
        // A count past the list's room reads only what it holds.
        a.store(ARGS_TILES, 100);
        assert_eq!(listed(&a, &t), 8);
    }

    #[test]
    fn the_dispatch_stops_at_the_dimension_limit() {
        let oob = AtomicU64::new(0);
        let args: Vec<AtomicU32> = [0, 0, 0, MAX_GROUPS_X + 5].map(AtomicU32::new).into();
        let tiles: Vec<AtomicU32> = (0..1).map(|_| AtomicU32::new(0)).collect();
        let (a, t) = (Words::new(&args, &oob), Words::new(&tiles, &oob));
        list(&a, &t, 9, 1 << 18);
        // The filter strides over the rest.
        assert_eq!(a.load(0), MAX_GROUPS_X);
        // The slot past the list's room is counted, not a panic.
        assert_eq!(oob.load(std::sync::atomic::Ordering::Relaxed), 1);
    }

    #[test]
    fn the_dispatch_grows_with_the_tiles_and_widens_the_few() {
        let budget = 1 << 19;
        // Never fewer workgroups for more tiles: the atomicMax of each
        // tile's count is the final count's.
        let mut last = 0;
        for n in 0..20_000 {
            let g = filter_groups(n, budget);
            assert!(g >= last && g >= n, "{n} tiles: {g} after {last}");
            last = g;
        }
        // Off: a workgroup a tile, two lanes a pixel.
        for n in [1, 191, 16_000] {
            assert_eq!(filter_groups(n, 0), n);
            assert_eq!(filter_lanes(filter_groups(n, 0), n, MAX_FILTER_LANES), 2);
        }
        let lanes = |n| filter_lanes(filter_groups(n, budget), n, MAX_FILTER_LANES);
        // The far view's tiles take sixteen lanes a pixel, within the budget.
        assert_eq!(filter_groups(191, budget), 8 * 191);
        assert_eq!(lanes(191), 16);
        assert!(191 * TILE * 16 <= budget);
        // Fewer as the tiles grow, by the lanes they fit.
        assert_eq!(lanes(700), 8);
        assert_eq!(lanes(1500), 4);
        // A close groom's fill the GPU at two.
        assert_eq!(filter_groups(16_000, budget), 16_000);
        assert_eq!(lanes(16_000), 2);
    }

    #[test]
    fn the_filter_takes_what_the_dispatch_holds_up_to_its_cap() {
        // A lane a pixel stays one; a cap below the dispatch's width wins.
        assert_eq!(filter_lanes(1528, 191, 1), 1);
        assert_eq!(filter_lanes(1528, 191, 4), 4);
        // Past 65,535 workgroups the filter strides at two lanes a pixel.
        let n = 200_000;
        assert_eq!(filter_groups(n, 1 << 18), MAX_GROUPS_X);
        assert_eq!(filter_lanes(MAX_GROUPS_X, n, 16), 2);
        // The check itself does not overflow at the largest counts.
        assert_eq!(filter_lanes(u32::MAX, u32::MAX, 16), 2);
        assert_eq!(filter_lanes(MAX_GROUPS_X, 0, 16), 16);
    }
}
