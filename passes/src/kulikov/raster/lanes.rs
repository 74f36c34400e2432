//! One subgroup's raster loop, executed as `shaders/kulikov/raster.wgsl`
//! executes it: lanes side by side in lock step, an active mask where
//! control flow diverges, the request stacks fed once per step.
//!
//! Kulikov, "Divergence": "Only 45% of lanes are active on average ...
//! Nested loops with divergent bounds". With nested loops every column costs
//! the subgroup as many steps as the lane with the tallest slice of it;
//! "Flatten 2 loops into one" lets a lane that finishes a column open its
//! next one on its own, so the subgroup loops only as long as its busiest
//! lane has pixels. Each step of each kind (column opening, pixel, depth
//! test, write) is counted with its active lanes in a [`LaneTally`].

use super::geometry::{Poly, Trapezoid};
use super::stacks::{LaneTally, Request, Sink, Stacks};
use super::{Lane, TILE};
use crate::kulikov::payload::COVERAGE_SCALE;

/// What a pixel step needs besides the lane: turning a covered pixel into a
/// request, then the depth test and write of [`Sink`].
pub(super) trait Pixels: Sink {
    fn request(&self, lane: &Lane, x: u32, y: u32, coverage: f32) -> Request;
}

/// One lane's place in its segment's loop (the WGSL's `x`, `col`, `y`, ...).
#[derive(Clone, Copy)]
struct Cursor<'l> {
    lane: Option<&'l Lane>,
    x: i32,
    x_end: i32,
    grid_h: i32,
    col: Poly,
    /// Coverage from the trapezoid's edges ([`Trapezoid::pixel_coverage`])
    /// rather than by clipping `col` per pixel.
    analytic: bool,
    y: i32,
    y_end: i32,
    /// Flattened loop: the lane has a pixel left in its open column.
    alive: bool,
    /// Flattened loop: the lane is looking for its next non-empty column.
    searching: bool,
}

impl<'l> Cursor<'l> {
    fn new(lane: Option<&'l Lane>, analytic: bool) -> Self {
        let mut c = Cursor {
            lane,
            x: 0,
            x_end: -1,
            grid_h: 0,
            col: Poly::new(&[]),
            analytic,
            y: 0,
            y_end: -1,
            alive: false,
            searching: false,
        };
        if let Some(l) = lane {
            let (x0, x1) = l.trap.columns();
            c.x = x0.max(0);
            c.x_end = x1.min((l.tiles.grid_w * TILE) as i32 - 1);
            c.grid_h = (l.tiles.grid_h * TILE) as i32;
        }
        c
    }

    /// Opens column `x`: its rows in the grid, from the trapezoid's edges
    /// with analytic coverage, else from its slice, which the clipper reads.
    fn open(&mut self, trap: &Trapezoid) {
        let span = if self.analytic {
            trap.column_span(self.x)
        } else {
            self.col = trap.column(self.x);
            (!self.col.is_empty()).then(|| self.col.range(1))
        };
        (self.y, self.y_end) = column_rows(span, self.grid_h);
    }

    /// The pixel at (x, y) of the open column, then the next row.
    fn pixel(&mut self, px: &impl Pixels) -> Option<Request> {
        let lane = self.lane?;
        let coverage = if self.analytic {
            lane.trap.pixel_coverage(self.x, self.y)
        } else {
            Trapezoid::coverage(&self.col, self.y)
        };
        let req =
            covers(coverage).then(|| px.request(lane, self.x as u32, self.y as u32, coverage));
        self.y += 1;
        req
    }
}

/// First and last row of a column's y extent within the grid (empty:
/// first > last).
fn column_rows(span: Option<(f32, f32)>, grid_h: i32) -> (i32, i32) {
    let Some((lo, hi)) = span else {
        return (1, 0);
    };
    (
        (lo.floor() as i32).max(0),
        (hi.floor() as i32).min(grid_h - 1),
    )
}

/// Only coverage that quantises to at least 1/1024 is written: thinner
/// slivers are float noise the GPU backends need not agree on.
fn covers(coverage: f32) -> bool {
    (coverage * COVERAGE_SCALE).round() >= 1.0
}

/// Runs one subgroup: `lanes[i]` is lane `i`'s segment (`None`: the lane
/// has none); the subgroup has `stacks.width` lanes however many are given.
pub(super) fn raster(
    lanes: &[Option<&Lane>],
    flattened: bool,
    analytic: bool,
    stacks: &mut Stacks,
    px: &mut impl Pixels,
) {
    let width = stacks.width();
    let mut cur: Vec<Cursor> = lanes.iter().map(|l| Cursor::new(*l, analytic)).collect();
    cur.resize(width, Cursor::new(None, analytic));
    let mut reqs = vec![None; width];
    if flattened {
        flattened_loop(&mut cur, &mut reqs, stacks, px);
    } else {
        nested_loops(&mut cur, &mut reqs, stacks, px);
    }
    stacks.drain(px);
}

/// Kulikov's flattened loop: each step, every lane with a pixel left takes
/// one; a lane that finishes its column opens its next non-empty one in
/// the same step (the inner search loop skips empty slices).
fn flattened_loop(
    cur: &mut [Cursor],
    reqs: &mut [Option<Request>],
    stacks: &mut Stacks,
    px: &mut impl Pixels,
) {
    for c in cur.iter_mut() {
        c.searching = c.lane.is_some();
    }
    search(cur, &mut stacks.tally);
    // `subgroupAny(alive)`.
    while cur.iter().any(|c| c.alive) {
        let mut active = 0;
        for (c, r) in cur.iter_mut().zip(reqs.iter_mut()) {
            *r = None;
            if !c.alive {
                continue;
            }
            active += 1;
            *r = c.pixel(px);
            if c.y > c.y_end {
                c.alive = false;
                c.x += 1;
                c.searching = true;
            }
        }
        stacks.tally.pixels.step(active, cur.len());
        search(cur, &mut stacks.tally);
        stacks.submit(reqs, px);
    }
}

/// The search loop of the flattened raster: each step, every searching lane
/// opens its column `x`; it stops at a non-empty one (alive) or past its
/// last column, and moves on otherwise.
fn search(cur: &mut [Cursor], tally: &mut LaneTally) {
    loop {
        let mut active = 0;
        for c in cur.iter_mut().filter(|c| c.searching) {
            let Some(lane) = c.lane.filter(|_| c.x <= c.x_end) else {
                c.searching = false;
                continue;
            };
            active += 1;
            c.open(&lane.trap);
            if c.y <= c.y_end {
                c.alive = true;
                c.searching = false;
            } else {
                c.x += 1;
            }
        }
        if active == 0 {
            return;
        }
        tally.columns.step(active, cur.len());
    }
}

/// Nested loops: the subgroup opens column k of every lane together, then
/// steps through rows until the tallest slice of them is done.
fn nested_loops(
    cur: &mut [Cursor],
    reqs: &mut [Option<Request>],
    stacks: &mut Stacks,
    px: &mut impl Pixels,
) {
    let width = cur.len();
    loop {
        // `has_col`, then `subgroupAny(has_col)`.
        let mut opened = 0;
        for c in cur.iter_mut() {
            (c.y, c.y_end) = (0, -1);
            if let Some(lane) = c.lane.filter(|_| c.x <= c.x_end) {
                c.open(&lane.trap);
                opened += 1;
            }
        }
        if opened == 0 {
            return;
        }
        stacks.tally.columns.step(opened, width);
        loop {
            // `busy = has_col && y <= y_end`, then `subgroupAny(busy)`.
            let mut busy = 0;
            for (c, r) in cur.iter_mut().zip(reqs.iter_mut()) {
                *r = None;
                if c.lane.is_some() && c.y <= c.y_end {
                    busy += 1;
                    *r = c.pixel(px);
                }
            }
            if busy == 0 {
                break;
            }
            stacks.tally.pixels.step(busy, width);
            stacks.submit(reqs, px);
        }
        for c in cur.iter_mut() {
            c.x += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::stacks::Region;
    use super::super::{ModelLod, ModelTiles};
    use super::*;

    /// Requests carry (x, y) and the lane's segment; every depth test passes.
    #[derive(Default)]
    struct Log {
        written: Vec<(u32, u32, u32)>,
    }

    impl Sink for Log {
        fn depth_passes(&mut self, _: u32, _: f32) -> bool {
            true
        }
        fn write(&mut self, texel: u32, payload: u32, _: u32) {
            self.written.push((payload, texel & 0xFF, texel >> 8));
        }
    }

    impl Pixels for Log {
        fn request(&self, lane: &Lane, x: u32, y: u32, _: f32) -> Request {
            Request {
                texel: x | (y << 8),
                payload: lane.local,
                cov: 1,
                ..Request::default()
            }
        }
    }

    fn lane(local: u32, a: [f32; 2], b: [f32; 2], half: f32) -> Lane {
        Lane {
            trap: Trapezoid::new(a, b, half, half, 1.0, 1.0).unwrap(),
            local,
            lod: ModelLod {
                strands: 1,
                vertex_step: 1,
                thickness_scale: 1.0,
                segments_per_strand: 1,
                strand_prefix: 0,
                depth_near: 0.5,
                depth_far: 10.0,
                segment_prefix: 0,
            },
            tiles: ModelTiles {
                first_tile: 0,
                grid_w: 1,
                grid_h: 1,
                origin_x: 0,
                origin_y: 0,
                downscale: 1,
                valid: 1,
            },
            morton: 0,
        }
    }

    fn run(flattened: bool, stacks: bool) -> (Vec<(u32, u32, u32)>, LaneTally) {
        run_with(flattened, stacks, true)
    }

    fn run_with(
        flattened: bool,
        stacks: bool,
        analytic: bool,
    ) -> (Vec<(u32, u32, u32)>, LaneTally) {
        // Lane 0: 9 columns of one pixel (shallow); lane 1: one column of 5 (steep).
        let shallow = lane(0, [0.5, 10.5], [8.5, 10.5], 0.25);
        let steep = lane(1, [20.5, 0.5], [20.5, 4.5], 0.25);
        let mut st = Stacks::new(2, stacks, stacks);
        let mut log = Log::default();
        raster(
            &[Some(&shallow), Some(&steep)],
            flattened,
            analytic,
            &mut st,
            &mut log,
        );
        log.written.sort_unstable();
        (log.written, st.tally)
    }

    #[test]
    fn nested_loops_wait_for_the_tallest_column_and_flattening_does_not() {
        let (flat_px, flat) = run(true, false);
        let (nested_px, nested) = run(false, false);
        let want: Vec<_> = (0..9)
            .map(|x| (0, x, 10))
            .chain((0..5).map(|y| (1, 20, y)))
            .collect();
        assert_eq!(flat_px, want);
        assert_eq!(nested_px, want);
        let region = |active, steps| Region {
            active,
            total: 2 * steps,
            steps,
        };
        // Flattened: 9 pixel steps (the shallow lane's 9 pixels), the steep
        // lane idle after 5; both lanes open a column, then the shallow one alone 8 times.
        assert_eq!(flat.pixels, region(14, 9));
        assert_eq!(flat.columns, region(2 + 8, 9));
        // Nested: the first column costs the steep lane's 5 rows, the other 8 one each.
        assert_eq!(nested.pixels, region(14, 5 + 8));
        assert_eq!(nested.columns, region(2 + 8, 9));
        // Without stacks, the depth test and write run in the pixel steps that have pixels.
        assert_eq!(flat.depth_tests, flat.pixels);
        assert_eq!(nested.writes, nested.pixels);
        assert!(flat.sum().utilisation() > nested.sum().utilisation());
    }

    #[test]
    fn analytic_and_clipped_coverage_write_the_same_pixels() {
        for flattened in [true, false] {
            let (analytic, a) = run_with(flattened, true, true);
            let (clipped, c) = run_with(flattened, true, false);
            assert_eq!(analytic, clipped);
            assert_eq!(a.pixels, c.pixels);
        }
    }

    #[test]
    fn stacks_batch_the_same_writes_into_full_steps() {
        for flattened in [true, false] {
            let (px, without) = run(flattened, false);
            let (px_stacks, with) = run(flattened, true);
            assert_eq!(px, px_stacks);
            assert_eq!(with.pixels, without.pixels);
            // 14 requests in steps of 2 lanes: every flush is full.
            assert_eq!(
                with.depth_tests,
                Region {
                    active: 14,
                    total: 14,
                    steps: 7
                }
            );
            assert_eq!(with.writes, with.depth_tests);
            assert!(with.sum().utilisation() > without.sum().utilisation());
        }
    }
}
