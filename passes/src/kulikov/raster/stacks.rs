//! The pixel request stacks, executed as `shaders/kulikov/raster.wgsl` does.
//!
//! Kulikov, "Pixel request stack": "Shipped with 2 stacks - for depth test
//! and actual pixel writes". A lane that produced a covered pixel pushes a
//! request (subgroup exclusive add for its slot); once a subgroup's worth is
//! queued, the top `width` entries are flushed one per lane, so the depth
//! test and the atomics run with every lane busy instead of only the lanes
//! that happened to have a pixel this step. Each subgroup owns 2 × width
//! entries of each stack: a push adds at most `width` to fewer than `width`
//! queued, so it never overflows.
//!
//! The CPU kernel runs the same pushes, flushes and drain as the WGSL, entry
//! for entry (packed the same way), and counts the lanes of every depth-test
//! and write step in a [`LaneTally`].

use crate::kernel::subgroup;

/// Bits of a stack entry's atlas texel; the coverage increment takes the
/// other 11 (at most `COVERAGE_SCALE` = 1024).
pub const TEXEL_BITS: u32 = 21;
pub const TEXEL_MASK: u32 = (1 << TEXEL_BITS) - 1;
/// Largest subgroup the WGSL lays its stacks out for.
pub const MAX_SUBGROUP: usize = 128;
/// Entries of each stack per workgroup (2 × 256 lanes).
pub const STACK: usize = 512;

/// A covered pixel on its way to the atlas (the WGSL's `Request`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Request {
    /// Screen pixel of the depth test, `x | y << 16`.
    pub pos: u32,
    pub view_depth: f32,
    pub texel: u32,
    pub payload: u32,
    /// Coverage increment, `round(coverage × 1024)`.
    pub cov: u32,
}

/// What a flushed request does: the depth test and the atlas write.
pub trait Sink {
    fn depth_passes(&mut self, pos: u32, view_depth: f32) -> bool;
    fn write(&mut self, texel: u32, payload: u32, cov: u32);
}

/// Active and total lanes of one kind of subgroup step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Region {
    pub active: u64,
    pub total: u64,
    pub steps: u64,
}

impl Region {
    pub fn step(&mut self, active: usize, width: usize) {
        self.active += active as u64;
        self.total += width as u64;
        self.steps += 1;
    }
    pub fn utilisation(&self) -> f64 {
        self.active as f64 / self.total.max(1) as f64
    }
}

/// Lane activity of the raster, per kind of step a subgroup executes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LaneTally {
    /// Opening a pixel column (`trapezoid_column` and its rows).
    pub columns: Region,
    /// One pixel of the raster loop (coverage and request).
    pub pixels: Region,
    /// Depth tests against the scene depth.
    pub depth_tests: Region,
    /// Atlas writes (last-layer cull, layer atomics, coverage add).
    pub writes: Region,
}

impl LaneTally {
    /// Every step of every kind, each weighted by its lanes.
    pub fn sum(&self) -> Region {
        [self.columns, self.pixels, self.depth_tests, self.writes]
            .iter()
            .fold(Region::default(), |a, r| Region {
                active: a.active + r.active,
                total: a.total + r.total,
                steps: a.steps + r.steps,
            })
    }
    pub fn add(&mut self, o: &LaneTally) {
        for (a, b) in [
            (&mut self.columns, o.columns),
            (&mut self.pixels, o.pixels),
            (&mut self.depth_tests, o.depth_tests),
            (&mut self.writes, o.writes),
        ] {
            a.active += b.active;
            a.total += b.total;
            a.steps += b.steps;
        }
    }
}

#[derive(Debug, Clone, Copy, Default)]
struct DepthEntry {
    pos: u32,
    view: f32,
    texcov: u32,
    payload: u32,
}

/// One subgroup's share of the two LDS stacks (its `stack_base` slice).
pub struct Stacks {
    width: usize,
    /// The depth-test stack and its queued count (`None`: switched off).
    depth: Option<(Vec<DepthEntry>, usize)>,
    /// The pixel-write stack: `texel | cov << 21`, payload.
    write: Option<(Vec<(u32, u32)>, usize)>,
    /// Scratch: per lane, the write a step hands on.
    passed: Vec<Option<(u32, u32, u32)>>,
    pub tally: LaneTally,
}

/// Whether subgroup `id` of `width` lanes gets stacks: the WGSL's
/// `stacks_fit` (its 2 × width entries inside the workgroup's 512, and
/// atlas texels that fit the entry's 21 bits).
pub fn stacks_fit(width: usize, id: usize, layer_stride: usize) -> bool {
    width <= MAX_SUBGROUP && (id + 1) * 2 * width <= STACK && layer_stride <= 1 << TEXEL_BITS
}

impl Stacks {
    pub fn new(width: usize, depth_stack: bool, pixel_stack: bool) -> Self {
        Self {
            width,
            depth: depth_stack.then(|| (vec![DepthEntry::default(); 2 * width], 0)),
            write: pixel_stack.then(|| (vec![(0, 0); 2 * width], 0)),
            passed: Vec::with_capacity(width),
            tally: LaneTally::default(),
        }
    }

    /// Lanes of the subgroup.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Queued entries of the depth-test and write stacks.
    pub fn queued(&self) -> (usize, usize) {
        (
            self.depth.as_ref().map_or(0, |d| d.1),
            self.write.as_ref().map_or(0, |w| w.1),
        )
    }

    /// The WGSL's `submit`, in subgroup-uniform control flow: `reqs[lane]`
    /// is the lane's pixel this step, if it has one.
    pub fn submit(&mut self, reqs: &[Option<Request>], sink: &mut impl Sink) {
        let width = self.width;
        if let Some((entries, count)) = &mut self.depth {
            let base = *count;
            *count += push(reqs, |slot, r| {
                entries[base + slot] = DepthEntry {
                    pos: r.pos,
                    view: r.view_depth,
                    texcov: r.texel | (r.cov << TEXEL_BITS),
                    payload: r.payload,
                }
            });
            if *count >= width {
                self.flush_depth(width, sink);
            }
        } else {
            // No stack: the depth test runs on the lanes that have a pixel.
            let mut passed = std::mem::take(&mut self.passed);
            passed.clear();
            let mut testing = 0;
            for r in reqs {
                passed.push(r.and_then(|r| {
                    testing += 1;
                    sink.depth_passes(r.pos, r.view_depth)
                        .then_some((r.texel, r.payload, r.cov))
                }));
            }
            if testing > 0 {
                self.tally.depth_tests.step(testing, width);
            }
            self.submit_write(&passed, sink);
            self.passed = passed;
        }
    }

    /// `flush_depth`: lane `i < take` tests entry `top + i`, where the top
    /// `take` entries are the ones flushed (the older ones stay queued).
    fn flush_depth(&mut self, take: usize, sink: &mut impl Sink) {
        let Some((entries, count)) = &mut self.depth else {
            return;
        };
        let top = *count - take;
        let mut passed = std::mem::take(&mut self.passed);
        passed.clear();
        passed.extend(entries[top..top + take].iter().map(|e| {
            sink.depth_passes(e.pos, e.view).then_some((
                e.texcov & TEXEL_MASK,
                e.payload,
                e.texcov >> TEXEL_BITS,
            ))
        }));
        passed.resize(self.width, None);
        *count = top;
        self.tally.depth_tests.step(take, self.width);
        self.submit_write(&passed, sink);
        self.passed = passed;
    }

    /// `submit_write`: `passed[lane]` is the write the lane hands on.
    fn submit_write(&mut self, passed: &[Option<(u32, u32, u32)>], sink: &mut impl Sink) {
        let width = self.width;
        if let Some((entries, count)) = &mut self.write {
            let base = *count;
            *count += push(passed, |slot, (texel, payload, cov)| {
                entries[base + slot] = (texel | (cov << TEXEL_BITS), payload)
            });
            if *count >= width {
                self.flush_write(width, sink);
            }
        } else {
            let mut writing = 0;
            for &(texel, payload, cov) in passed.iter().flatten() {
                sink.write(texel, payload, cov);
                writing += 1;
            }
            if writing > 0 {
                self.tally.writes.step(writing, width);
            }
        }
    }

    /// `flush_write`: lane `i < take` writes entry `top + i`.
    fn flush_write(&mut self, take: usize, sink: &mut impl Sink) {
        let Some((entries, count)) = &mut self.write else {
            return;
        };
        let top = *count - take;
        for &(texcov, payload) in &entries[top..top + take] {
            sink.write(texcov & TEXEL_MASK, payload, texcov >> TEXEL_BITS);
        }
        *count = top;
        self.tally.writes.step(take, self.width);
    }

    /// The WGSL's `drain`: whatever is still queued once every lane of the
    /// subgroup is done (the depth stack first, its survivors onto the
    /// write stack, then the write stack a subgroup's worth at a time).
    pub fn drain(&mut self, sink: &mut impl Sink) {
        let (depth, _) = self.queued();
        if depth > 0 {
            self.flush_depth(depth, sink);
        }
        while let (_, queued @ 1..) = self.queued() {
            self.flush_write(queued.min(self.width), sink);
        }
    }
}

/// A push onto a stack: `subgroupExclusiveAdd` of the lanes that have an
/// entry gives each its slot above the queued ones; returns `subgroupAdd`.
fn push<T: Copy>(lanes: &[Option<T>], mut store: impl FnMut(usize, T)) -> usize {
    let want: Vec<u32> = lanes.iter().map(|l| u32::from(l.is_some())).collect();
    let all = vec![true; lanes.len()];
    let slots = subgroup::exclusive_add(&want, &all);
    for (l, slot) in lanes.iter().zip(slots) {
        if let Some(v) = l {
            store(slot as usize, *v);
        }
    }
    subgroup::add(&want, &all) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Records the order of depth tests and writes; fails the depth test of
    /// odd positions.
    #[derive(Default)]
    struct Log {
        tests: Vec<u32>,
        writes: Vec<(u32, u32, u32)>,
    }

    impl Sink for Log {
        fn depth_passes(&mut self, pos: u32, _: f32) -> bool {
            self.tests.push(pos);
            pos.is_multiple_of(2)
        }
        fn write(&mut self, texel: u32, payload: u32, cov: u32) {
            self.writes.push((texel, payload, cov));
        }
    }

    fn req(n: u32) -> Request {
        Request {
            pos: n,
            view_depth: 1.0,
            texel: n,
            payload: 100 + n,
            cov: 1024,
        }
    }

    #[test]
    fn a_full_subgroup_flushes_the_top_entries_and_keeps_the_rest() {
        // Width 4: 3 queued, then 4 more overflow the subgroup's worth.
        let mut s = Stacks::new(4, true, false);
        let mut log = Log::default();
        s.submit(&[Some(req(0)), None, Some(req(1)), Some(req(2))], &mut log);
        assert_eq!(s.queued(), (3, 0));
        assert!(log.tests.is_empty());
        s.submit(
            &[Some(req(3)), Some(req(4)), Some(req(5)), Some(req(6))],
            &mut log,
        );
        // 7 queued ≥ 4: lanes 0..4 test entries 3..7; entries 0..3 stay.
        assert_eq!(log.tests, vec![3, 4, 5, 6]);
        assert_eq!(s.queued(), (3, 0));
        assert_eq!(s.tally.depth_tests.steps, 1);
        assert_eq!(s.tally.depth_tests.active, 4);
        // Without a write stack the passing lanes write at once.
        assert_eq!(log.writes, vec![(4, 104, 1024), (6, 106, 1024)]);
        assert_eq!(
            s.tally.writes,
            Region {
                active: 2,
                total: 4,
                steps: 1
            }
        );
        s.drain(&mut log);
        assert_eq!(log.tests, vec![3, 4, 5, 6, 0, 1, 2]);
        assert_eq!(s.queued(), (0, 0));
        assert_eq!(s.tally.depth_tests.active, 7);
    }

    #[test]
    fn survivors_queue_for_writes_and_drain_a_subgroup_at_a_time() {
        let mut s = Stacks::new(4, true, true);
        let mut log = Log::default();
        let even = |k: u32| Some(req(2 * k));
        // All pass the depth test: 4 + 3 + ... requests.
        s.submit(&[even(0), even(1), even(2), even(3)], &mut log);
        assert_eq!(s.queued(), (0, 4 - 4));
        // The flush of 4 depth tests filled the write stack, which flushed.
        assert_eq!(log.writes.len(), 4);
        s.submit(&[even(4), even(5), even(6), None], &mut log);
        s.submit(&[even(7), even(8), None, None], &mut log);
        // 5 depth entries queued ≥ 4: entries 1..5 tested, 4 writes queued, flushed.
        assert_eq!(log.writes.len(), 8);
        assert_eq!(s.queued(), (1, 0));
        s.drain(&mut log);
        assert_eq!(s.queued(), (0, 0));
        assert_eq!(log.writes.len(), 9);
        // Every write is a request's, packed and unpacked intact.
        let mut texels: Vec<u32> = log.writes.iter().map(|w| w.0).collect();
        texels.sort_unstable();
        assert_eq!(texels, (0..9).map(|k| 2 * k).collect::<Vec<_>>());
        assert!(log.writes.iter().all(|w| w.1 == 100 + w.0 && w.2 == 1024));
        assert_eq!(s.tally.writes.active, 9);
        assert_eq!(s.tally.writes.steps, 3);
    }

    #[test]
    fn stacks_fit_as_the_wgsl_lays_them_out() {
        assert!(stacks_fit(32, 7, 1 << 21));
        assert!(!stacks_fit(32, 7, (1 << 21) + 1));
        assert!(stacks_fit(128, 1, 4096));
        assert!(!stacks_fit(256, 0, 4096));
        // 48 lanes do not divide 256: the sixth subgroup finds no room.
        assert!(stacks_fit(48, 4, 4096));
        assert!(!stacks_fit(48, 5, 4096));
    }
}
