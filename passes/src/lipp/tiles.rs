//! The tiles with hair (ours): `lipp.shade` lists the 64-pixel tiles (its
//! workgroups, runs of 64 pixels in row order) where either G-buffer layer
//! holds a sample, and `lipp.filter` runs one workgroup per listed tile
//! through an indirect dispatch, not one per tile of the screen.
//!
//! The filter's per-pixel work is Code 2's (2r + 1)² window, but most of a
//! frame is empty pixels, which each still cost a launch, two G-buffer
//! loads and the occupancy the window's registers allow: at the far view
//! on the H100 the filter took 0.13 ms for a head a few hundred pixels
//! tall. The list's order is the order tiles finish shading, which does not
//! change the image: each tile is filtered on its own. With the shade's
//! `hair_tiles` off every tile is listed (the bench row that measures this).

use super::MAX_GROUPS_X;
use crate::kernel::Words;

/// Pixels per tile: `lipp.shade`'s and `lipp.filter`'s workgroup size.
pub const TILE: u32 = 64;
/// `filter_args` words: the dispatch (0-2) and the tiles listed (3).
pub const ARGS_TILES: usize = 3;

/// Appends tile `t` to `filter_tiles` and grows the dispatch in
/// `filter_args` to cover it (the filter strides past 65,535 workgroups).
pub fn list(args: &Words<'_>, tiles: &Words<'_>, t: u32) {
    let k = args.fetch_add(ARGS_TILES, 1);
    tiles.store(k as usize, t);
    args.fetch_max(0, (k + 1).min(MAX_GROUPS_X));
    args.store(1, 1);
    args.store(2, 1);
}

/// The tiles listed in `filter_args` (at most what `filter_tiles` holds).
pub fn listed(args: &Words<'_>, tiles: &Words<'_>) -> u32 {
    args.load(ARGS_TILES).min(tiles.len() as u32)
}
