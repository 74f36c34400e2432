//! The groom's screen rectangle (ours): where on screen one groom can have
//! G-buffer samples, so that `lipp.shade` runs over that part of the screen
//! and not all of it.
//!
//! The paper shades "every pixel of the G-buffer" (§3.4) and draws grooms
//! one after another (§3.5), so each groom paid a full-screen shading pass
//! however small it was on screen: on the H100, 0.059 ms of the far view's
//! 0.35 and about 0.09 ms per groom of the crowd's 28.
//!
//! - `lipp.lod` bounds each drawn bundle in world space ([`bundle_box`]),
//!   projects the box ([`screen_rect`]) and keeps the rectangle in tiles of
//!   [`granularity`] pixels in `lod_choices` word 2, which the scan later
//!   overwrites with the bundle's first strand ([`Rect::pack_tiles`]).
//! - `lipp.lod_scan` unites the drawn bundles' rectangles into `raster_args`
//!   words [`ARGS_RECT_LO`] and [`ARGS_RECT_HI`] ([`Rect::args`]).
//!   With its `groom_rect` off the rectangle is the whole screen (the bench
//!   row "shading every pixel").
//! - The scan also writes the indirect dispatch (`raster_args` words
//!   [`ARGS_RUNS`]..) of the passes that work in runs of [`TILE`] pixels,
//!   one workgroup per run from the one holding the rectangle's first
//!   pixel to the one holding its last ([`Rect::runs`]): `lipp.shade`,
//!   which returns at once in a run the rectangle's rows pass by. A
//!   full-screen dispatch whose workgroups return still cost the H100
//!   launching them: 36 µs of shading for the far view's groom, about
//!   60 µs for each of the crowd's. `lipp.clear_gbuffer` gets its own
//!   dispatch over blocks of those runs (words [`ARGS_CLEAR`]..).
//! - `lipp.clear_gbuffer` clears those runs only: every pixel `lipp.shade`
//!   reads. Elsewhere the G-buffer keeps what an earlier groom, or another
//!   resource aliased to it, left there, which nothing reads.
//! - `lipp.shade` tells `lipp.filter` which pixels it shaded (`filter_args`
//!   words [`FILTER_RECT_LO`], [`FILTER_RECT_HI`]): the filter's taps
//!   outside them read no hair, where the `shaded` records are not this
//!   frame's.
//!
//! The box must hold everything the rasterizer can draw from the bundle
//! (`strand::eval_cp`), or hair would be cut off:
//! - the layer quads' bilinear patches over (u, v) ∈ [−¼, 1¼]²: the twist
//!   rotates a strand's (u, v) about the centre, reaching 0.5 − √½ ≈ −0.21;
//!   a bilinear patch lies in the hull of its four corners;
//! - widened by the Hermite bulge, at most 8/27 of a piece's chord (the
//!   basis functions h10 and h11 peak at 4/27, their tangents unit vectors
//!   scaled by the chord);
//! - and by the styling offsets, curl radius plus √3 × noise amplitude.
//!
//! The rasterizer's segments join points in the box, so they stay in it;
//! projected with every corner in front of the near plane, the box's screen
//! rectangle holds their pixels, grown by [`PAD`] pixels for the lines'
//! width and the sub-pixel snap. A corner at or behind the near plane gives
//! the whole screen. `tests/lipp_rect.rs` checks every sample the
//! rasterizer wrote lies inside, on the built-in scenes.

use super::strand::bilinear;
use super::tiles::TILE;
use super::{BundleRecord, Corner, MAX_GROUPS_X, length, sub, transform};
use crate::kernel::Words;
use crate::kulikov::clip_to_screen;
use crate::layout::FrameData;

/// `raster_args` words: the groom's rectangle, x | y << 16 of its first
/// pixel and of the pixel past its last (exclusive).
pub const ARGS_RECT_LO: usize = 6;
pub const ARGS_RECT_HI: usize = 7;
/// `raster_args` words 8..=10: the workgroups (x, 1, 1) of one per run of
/// [`TILE`] pixels [`Rect::runs`] covers, at most [`MAX_GROUPS_X`] (past
/// it a workgroup takes a block of runs, [`Rect::runs_of_group`]).
pub const ARGS_RUNS: usize = 8;
/// `raster_args` words 13..=15: `lipp.clear_gbuffer`'s workgroups (x, 1, 1),
/// one per `lipp.lod_scan`'s `clear_runs` runs ([`Rect::run_dispatch`]).
pub const ARGS_CLEAR: usize = 13;
/// `filter_args` words: the pixels `lipp.shade` wrote records for, the same
/// packing; a `filter_args` with no room for them shades the whole screen.
pub const FILTER_RECT_LO: usize = 4;
pub const FILTER_RECT_HI: usize = 5;

/// How far the twist carries (u, v) outside the unit square, rounded up.
const TWIST_REACH: f32 = 0.25;
/// The Hermite bulge over the chord: 2 × 4/27, rounded up.
const HERMITE_BULGE: f32 = 0.3;
/// |2 id − 1| ≤ √3 for the noise offset, rounded up.
const NOISE_REACH: f32 = 1.75;
/// Pixels the rectangle grows by: a line's pixels lie within ½ pixel of the
/// segment between its snapped ends.
pub const PAD: f32 = 2.0;

type V3 = [f32; 3];

/// A rectangle of pixels, [x0, x1) × [y0, y1).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Rect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Rect {
    pub const EMPTY: Rect = Rect {
        x0: 0,
        y0: 0,
        x1: 0,
        y1: 0,
    };

    pub fn full(w: u32, h: u32) -> Self {
        Rect {
            x0: 0,
            y0: 0,
            x1: w,
            y1: h,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.x1 <= self.x0 || self.y1 <= self.y0
    }

    pub fn contains(&self, x: u32, y: u32) -> bool {
        x >= self.x0 && x < self.x1 && y >= self.y0 && y < self.y1
    }

    /// The smallest rectangle holding both (an empty one holds nothing).
    pub fn union(self, o: Rect) -> Rect {
        if self.is_empty() {
            return o;
        }
        if o.is_empty() {
            return self;
        }
        Rect {
            x0: self.x0.min(o.x0),
            y0: self.y0.min(o.y0),
            x1: self.x1.max(o.x1),
            y1: self.y1.max(o.y1),
        }
    }

    /// Whether the row-major run of `len` pixels from pixel `first` on a
    /// `w`-wide screen may touch the rectangle (a run over several rows:
    /// whether those rows do).
    pub fn touches_run(&self, first: u32, len: u32, w: u32) -> bool {
        let last = first + len.max(1) - 1;
        let (ya, yb) = (first / w, last / w);
        if yb < self.y0 || ya >= self.y1 {
            return false;
        }
        ya != yb || (last % w >= self.x0 && first % w < self.x1)
    }

    /// The row-major runs of [`TILE`] pixels from the one holding the
    /// rectangle's first pixel to the one holding its last, on a `w`-wide
    /// screen: (first run, count). Every pixel of the rectangle lies in one.
    pub fn runs(&self, w: u32) -> (u32, u32) {
        if self.is_empty() {
            return (0, 0);
        }
        let first = (self.y0 * w + self.x0) / TILE;
        let last = ((self.y1 - 1) * w + self.x1 - 1) / TILE;
        (first, last - first + 1)
    }

    /// An indirect dispatch over [`Rect::runs`]: a workgroup per
    /// `runs_per_group` runs, at most [`MAX_GROUPS_X`]. `raster_args` words
    /// [`ARGS_RUNS`].. (`lipp.shade`, one run a workgroup) and
    /// [`ARGS_CLEAR`].. (`lipp.clear_gbuffer`, the scan's `clear_runs`).
    pub fn run_dispatch(&self, w: u32, runs_per_group: u32) -> [u32; 3] {
        let groups = self.runs(w).1.div_ceil(runs_per_group.max(1));
        [groups.min(MAX_GROUPS_X), 1, 1]
    }

    /// The runs workgroup `group` of a [`Rect::run_dispatch`] of
    /// `workgroups` takes, those that touch the rectangle: the `group`th of
    /// `workgroups` contiguous blocks of [`Rect::runs`] (one run each where
    /// there are as many workgroups as runs). However many workgroups, the
    /// blocks cover every run once. What `lipp.shade` and
    /// `lipp.clear_gbuffer` each work on.
    pub fn runs_of_group(&self, w: u32, group: u32, workgroups: u32) -> impl Iterator<Item = u32> {
        let (first, runs) = self.runs(w);
        let per = runs.div_ceil(workgroups.max(1));
        let lo = group.saturating_mul(per).min(runs);
        let hi = lo.saturating_add(per).min(runs);
        let rect = *self;
        (lo..hi)
            .map(move |k| first + k)
            .filter(move |&run| rect.touches_run(run * TILE, TILE, w))
    }

    /// The rectangle in tiles of [`granularity`] pixels, a byte per edge
    /// (`lod_choices` word 2): x0 | y0 << 8 | x1 << 16 | y1 << 24, edges
    /// rounded outwards. 0 is empty.
    pub fn pack_tiles(&self, w: u32, h: u32) -> u32 {
        if self.is_empty() {
            return 0;
        }
        let g = granularity(w, h);
        let (x0, y0) = (self.x0 / g, self.y0 / g);
        let (x1, y1) = (self.x1.div_ceil(g), self.y1.div_ceil(g));
        x0 | y0 << 8 | x1 << 16 | y1 << 24
    }

    /// [`Rect::pack_tiles`]'s rectangle in pixels, clamped to the screen.
    pub fn unpack_tiles(word: u32, w: u32, h: u32) -> Self {
        let g = granularity(w, h);
        let edge = |shift: u32, size: u32| ((word >> shift & 0xFF) * g).min(size);
        Rect {
            x0: edge(0, w),
            y0: edge(8, h),
            x1: edge(16, w),
            y1: edge(24, h),
        }
    }

    /// The two words `raster_args` and `filter_args` hold it in.
    pub fn args(&self) -> [u32; 2] {
        [self.x0 | self.y0 << 16, self.x1 | self.y1 << 16]
    }

    pub fn from_args(lo: u32, hi: u32) -> Self {
        Rect {
            x0: lo & 0xFFFF,
            y0: lo >> 16,
            x1: hi & 0xFFFF,
            y1: hi >> 16,
        }
    }
}

/// Pixels per tile of [`Rect::pack_tiles`]: the smallest power of two from
/// 8 up with at most 255 tiles across the screen's longer side.
pub fn granularity(w: u32, h: u32) -> u32 {
    let mut g = 8;
    while w.max(h).div_ceil(g) > 255 {
        g *= 2;
    }
    g
}

/// Corner `k` of layer `layer`'s quad extended to (u, v) ∈ [−¼, 1¼]²
/// (bilinear, as `strand::layer_point` evaluates it).
fn extended_corner(layers: &Words<'_>, layer: usize, k: usize) -> V3 {
    let c = std::array::from_fn(|k| Corner::load(layers, layer, k).position);
    let (lo, hi) = (-TWIST_REACH, 1.0 + TWIST_REACH);
    let (u, v) = [(lo, lo), (hi, lo), (hi, hi), (lo, hi)][k];
    bilinear(c, u, v)
}

fn distance(a: V3, b: V3) -> f32 {
    length(sub(a, b))
}

/// The world box (lo, hi) holding everything bundle `b` can draw (module
/// documentation): its extended layer corners, grown by the styling reach
/// and the Hermite bulge of the longest chord between consecutive layers.
/// A chord is bounded by the distance between the layers' extended quads'
/// centres plus their radii (the farthest corner from the centre), which
/// costs a thread five square roots a layer rather than sixteen.
pub fn bundle_box(layers: &Words<'_>, b: &BundleRecord) -> (V3, V3) {
    let (mut lo, mut hi, mut chord) = ([f32::MAX; 3], [f32::MIN; 3], 0.0f32);
    let (mut prev_c, mut prev_r) = ([0.0f32; 3], 0.0f32);
    for i in 0..b.layers() as usize {
        let e: [V3; 4] =
            std::array::from_fn(|k| extended_corner(layers, b.first_layer as usize + i, k));
        let c = [0, 1, 2].map(|a| (e[0][a] + e[1][a] + e[2][a] + e[3][a]) * 0.25);
        let mut r = 0.0f32;
        for p in e {
            lo = [0, 1, 2].map(|a| lo[a].min(p[a]));
            hi = [0, 1, 2].map(|a| hi[a].max(p[a]));
            r = r.max(distance(p, c));
        }
        if i > 0 {
            chord = chord.max(distance(c, prev_c) + r + prev_r);
        }
        (prev_c, prev_r) = (c, r);
    }
    let pad = b.curl_radius.abs() + NOISE_REACH * b.noise.abs() + HERMITE_BULGE * chord;
    (lo.map(|v| v - pad), hi.map(|v| v + pad))
}

/// The screen rectangle of the world box `lo`..`hi`, grown by [`PAD`] and
/// clamped to the screen: the whole screen when a corner is at or behind
/// the near plane.
pub fn screen_rect(f: &FrameData, lo: V3, hi: V3) -> Rect {
    let (w, h) = (f.screen[0], f.screen[1]);
    let full = Rect::full(w as u32, h as u32);
    let (mut s_lo, mut s_hi) = ([f32::MAX; 2], [f32::MIN; 2]);
    for i in 0..8 {
        let pick = |axis: usize| {
            if i >> axis & 1 == 1 {
                hi[axis]
            } else {
                lo[axis]
            }
        };
        let c = transform(&f.view_proj, [pick(0), pick(1), pick(2), 1.0]);
        if !(c[3] > f.near) {
            return full;
        }
        let s = clip_to_screen(c, w, h);
        s_lo = [s_lo[0].min(s[0]), s_lo[1].min(s[1])];
        s_hi = [s_hi[0].max(s[0]), s_hi[1].max(s[1])];
    }
    let edge = |v: f32, size: f32| v.clamp(0.0, size) as u32;
    Rect {
        x0: edge((s_lo[0] - PAD).floor(), w),
        y0: edge((s_lo[1] - PAD).floor(), h),
        x1: edge((s_hi[0] + PAD).ceil(), w),
        y1: edge((s_hi[1] + PAD).ceil(), h),
    }
}

#[cfg(test)]
mod tests;
