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

use super::MAX_GROUPS_X;
use crate::kernel::Words;

/// Pixels per tile: `lipp.shade`'s and `lipp.filter`'s workgroup size.
pub const TILE: u32 = 64;
/// `filter_args` words: the dispatch (0-2) and the tiles listed (3).
pub const ARGS_TILES: usize = 3;

/// Appends tile `t` to `filter_tiles` and grows the dispatch in
/// `filter_args` to cover it (the filter strides past 65,535 workgroups).
/// The first tile listed sets the dispatch's other two dimensions: every
/// tile writing them would add two more atomics on the one hot address.
pub fn list(args: &Words<'_>, tiles: &Words<'_>, t: u32) {
    let k = args.fetch_add(ARGS_TILES, 1);
    tiles.store(k as usize, t);
    args.fetch_max(0, (k + 1).min(MAX_GROUPS_X));
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
            list(&a, &t, tile);
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
        list(&a, &t, 9);
        // The filter strides over the rest.
        assert_eq!(a.load(0), MAX_GROUPS_X);
        // The slot past the list's room is counted, not a panic.
        assert_eq!(oob.load(std::sync::atomic::Ordering::Relaxed), 1);
    }
}
