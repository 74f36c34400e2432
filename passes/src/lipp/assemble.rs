//! Lipp §3.1.1 and Appendix B Code 1: cooperative strand assembly, shared
//! by the main-view rasterizer (`lipp.raster`) and the deep opacity maps
//! (`lipp.dom_*`), which project the same segments per light ("Strand
//! assembly is performed only once, while projection is executed per view",
//! Lipp §5). The 32 lanes of a workgroup are emulated as arrays; shuffles go
//! through [`shuffle_up`] / [`shuffle_down`] at the emulated subgroup width,
//! and a neighbour in another subgroup is evaluated instead (same bits).
//! See `raster.rs` for the two passes.

use super::strand::{
    ControlPoint, LayerPoint, calc_tangent, eval_cp, layer_point, shuffle_down, shuffle_up,
    strand_id, strand_uv,
};
use super::{
    BundleLod, BundleRecord, LOD_WORDS, MAX_CONTROL_POINTS, RASTER_GROUP, bundle_count,
    bundle_of_strand, bundle_range,
};
use crate::kernel::{Ctx, Words};

/// What receives each segment: both ends and their tangents.
pub type DrawSegment<'a> = dyn FnMut(&ControlPoint, [f32; 3], &ControlPoint, [f32; 3]) + 'a;

/// How a strand is assembled.
#[derive(Debug, Clone, Copy)]
pub struct Assembly {
    /// Emulated subgroup width (1..=32).
    pub width: usize,
    /// Shuffle neighbours (Code 1) rather than recompute them.
    pub cooperative: bool,
    pub styling: bool,
    /// Points a lane holds at most (1, 2 or 4): Code 1's strips of
    /// S = ceil((C − 1) / 32) points, in rounds of at most this many
    /// ([`strip_len`], [`strip_rounds`]). 4, the default, is one round for
    /// every C ≤ 129; `lipp.raster`'s `strip_rounds` uses 1.
    pub max_strip: u32,
}

impl Assembly {
    /// At `ctx`'s emulated subgroup width, with a pass's two switches.
    pub fn new(ctx: &Ctx<'_>, cooperative: bool, styling: bool) -> Self {
        Self {
            width: ctx.subgroup_width.clamp(1, RASTER_GROUP) as usize,
            cooperative,
            styling,
            max_strip: 4,
        }
    }
}

/// S = ceil((C − 1) / 32), the points a lane holds in Code 1, at most
/// `max_strip` (shaders/lipp/assembly.wgsl, `strip_len`).
pub fn strip_len(c: u32, max_strip: u32) -> u32 {
    (c - 1).div_ceil(RASTER_GROUP).min(max_strip)
}

/// The rounds of 32 strips of [`strip_len`] points that cover C points.
pub fn strip_rounds(c: u32, max_strip: u32) -> u32 {
    (c - 1).div_ceil(RASTER_GROUP * strip_len(c, max_strip))
}

/// What Code 1 reads, bound the same way by every pass that assembles
/// strands: the LOD records (`bundle_lod`), the bundles and their layers,
/// and how many strands the LOD keeps (`raster_args` word 3).
pub struct Strands<'a> {
    pub lods: Words<'a>,
    pub bundles: Words<'a>,
    pub layers: Words<'a>,
    /// Strands the LOD keeps, numbered across bundles.
    pub total: u32,
    /// The bundles the drawn strands lie in (`raster_args`, [`bundle_range`]).
    pub range: std::ops::Range<usize>,
}

impl<'a> Strands<'a> {
    pub fn load(ctx: &Ctx<'a>) -> Self {
        let (lods, args) = (ctx.words("bundle_lod"), ctx.words("raster_args"));
        let count = bundle_count(ctx).min(lods.len() / LOD_WORDS);
        Self {
            range: bundle_range(&args, count),
            lods,
            bundles: ctx.words("hairmesh.bundles"),
            layers: ctx.words("hairmesh.layers"),
            total: args.load(3),
        }
    }

    /// Kept strand `s`: its bundle's LOD and record, and its index `k` in
    /// the bundle.
    pub fn strand(&self, s: u32) -> (BundleLod, BundleRecord, u32) {
        let b = bundle_of_strand(|i| self.lods.load(i * LOD_WORDS + 2), self.range.clone(), s);
        let lod = BundleLod::load(&self.lods, b);
        let k = s - lod.first_strand;
        (lod, BundleRecord::load(&self.bundles, b), k)
    }
}

/// Lipp Code 1 for strand `k` of bundle `rec`, lanes emulated as arrays:
/// calls `draw` with each segment's ends and tangents; returns (segments
/// drawn, lane slots of the drawing loop) for the lane-utilisation counter.
pub fn assemble(
    layers: &Words<'_>,
    rec: &BundleRecord,
    lod: &BundleLod,
    k: u32,
    opts: &Assembly,
    draw: &mut DrawSegment<'_>,
) -> (u64, u64) {
    let (coop, width) = (opts.cooperative, opts.width);
    let lanes = RASTER_GROUP as usize;
    let uv = strand_uv(k);
    let id = strand_id(rec.seed, k);
    let n = rec.layers();
    // Pass 1 (Code 1 lines 14-28): one layer per lane, neighbours by shuffle.
    let load = |i: u32| layer_point(layers, rec, i, uv);
    let mine: Vec<LayerPoint> = (0..lanes as u32)
        .map(|i| {
            if i < n {
                load(i)
            } else {
                LayerPoint::default()
            }
        })
        .collect();
    let (up, down) = (shuffle_up(&mine, width), shuffle_down(&mine, width));
    let mut sm: Vec<LayerPoint> = mine[..n as usize].to_vec();
    for i in 0..n {
        let iu = i as usize;
        let prev = match (coop, up[iu]) {
            (true, Some(p)) if i > 0 => p.pos,
            _ if i > 0 => load(i - 1).pos,
            _ => mine[iu].pos,
        };
        let next = match (coop, down[iu]) {
            (true, Some(p)) if i + 1 < n => p.pos,
            _ if i + 1 < n => load(i + 1).pos,
            _ => mine[iu].pos,
        };
        sm[iu].tangent = calc_tangent(i, n, prev, mine[iu].pos, next);
    }
    // Pass 2 (Code 1 lines 30-50): strips of S control points per lane, in
    // rounds when a lane holds fewer (`max_strip`).
    let c = lod.control_points.clamp(2, MAX_CONTROL_POINTS);
    let strip = strip_len(c, opts.max_strip);
    let rounds = strip_rounds(c, opts.max_strip);
    let pass = PassTwo {
        sm: &sm,
        rec,
        id,
        c,
        strip,
        opts,
    };
    let active = (0..rounds).map(|r| pass.round(r, draw)).sum();
    (active, u64::from(RASTER_GROUP * strip * rounds))
}

/// Code 1's second pass over one round of strips.
struct PassTwo<'a> {
    sm: &'a [LayerPoint],
    rec: &'a BundleRecord,
    id: [f32; 3],
    c: u32,
    /// Points a lane holds.
    strip: u32,
    opts: &'a Assembly,
}

impl PassTwo<'_> {
    /// Round `round`: lane l's points start at (round · 32 + l) · S. The
    /// round's first lane evaluates its predecessor and its last lane its
    /// successor, as a lane without a shuffle partner does. Returns the
    /// segments drawn.
    fn round(&self, round: u32, draw: &mut DrawSegment<'_>) -> u64 {
        let (coop, width, c) = (self.opts.cooperative, self.opts.width, self.c);
        let lanes = RASTER_GROUP as usize;
        let eval = |i: u32| eval_cp(self.sm, self.rec, self.id, i, c, self.opts.styling);
        let firsts: Vec<u32> = (0..lanes)
            .map(|l| (round as usize * lanes + l) as u32 * self.strip)
            .collect();
        let cps: Vec<Vec<ControlPoint>> = firsts
            .iter()
            .map(|&f| {
                (0..self.strip)
                    .filter(|m| f + m < c)
                    .map(|m| eval(f + m))
                    .collect()
            })
            .collect();
        let first_cp: Vec<Option<ControlPoint>> = cps.iter().map(|v| v.first().copied()).collect();
        let last_cp: Vec<Option<ControlPoint>> = cps.iter().map(|v| v.last().copied()).collect();
        let (prev_sh, next_sh) = (shuffle_up(&last_cp, width), shuffle_down(&first_cp, width));
        // Neighbour at index i: shuffled when cooperative and available, else evaluated.
        let fetch = |shuffled: Option<Option<ControlPoint>>, i: u32| match (coop, shuffled) {
            (true, Some(Some(p))) => p,
            _ => eval(i),
        };
        let mut tangents: Vec<Vec<[f32; 3]>> = Vec::with_capacity(lanes);
        let mut nexts: Vec<Option<ControlPoint>> = Vec::with_capacity(lanes);
        for l in 0..lanes {
            let (f, v) = (firsts[l], &cps[l]);
            if v.is_empty() {
                tangents.push(Vec::new());
                nexts.push(None);
                continue;
            }
            let prev = (f > 0).then(|| fetch(prev_sh[l], f - 1));
            let end = f + v.len() as u32;
            let next = (end < c).then(|| fetch(next_sh[l], end));
            let t = (0..v.len())
                .map(|m| {
                    let p = if m > 0 {
                        v[m - 1].pos
                    } else {
                        prev.map_or(v[m].pos, |p| p.pos)
                    };
                    let q = if m + 1 < v.len() {
                        v[m + 1].pos
                    } else {
                        next.map_or(v[m].pos, |p| p.pos)
                    };
                    calc_tangent(f + m as u32, c, p, v[m].pos, q)
                })
                .collect();
            tangents.push(t);
            nexts.push(next);
        }
        // The next lane's first tangent (Code 1 line 46).
        let first_t: Vec<Option<[f32; 3]>> = tangents.iter().map(|t| t.first().copied()).collect();
        let next_t = shuffle_down(&first_t, width);
        let mut active = 0u64;
        for l in 0..lanes {
            let Some(next) = nexts[l] else {
                // Only the last strip: its segments end inside the strip.
                draw_strip(draw, &cps[l], &tangents[l], None, &mut active);
                continue;
            };
            let end = firsts[l] + cps[l].len() as u32;
            let tn = match (coop, next_t[l]) {
                (true, Some(Some(t))) => t,
                _ => {
                    let after = if end + 1 < c {
                        eval(end + 1).pos
                    } else {
                        next.pos
                    };
                    calc_tangent(end, c, cps[l][cps[l].len() - 1].pos, next.pos, after)
                }
            };
            draw_strip(draw, &cps[l], &tangents[l], Some((next, tn)), &mut active);
        }
        active
    }
}

/// Draws a lane's segments: consecutive strip points, then the segment to
/// the next lane's first point.
fn draw_strip(
    draw: &mut DrawSegment<'_>,
    cps: &[ControlPoint],
    tangents: &[[f32; 3]],
    next: Option<(ControlPoint, [f32; 3])>,
    active: &mut u64,
) {
    for m in 0..cps.len() {
        let (b, tb) = if m + 1 < cps.len() {
            (cps[m + 1], tangents[m + 1])
        } else if let Some(n) = next {
            n
        } else {
            break;
        };
        *active += 1;
        draw(&cps[m], tangents[m], &b, tb);
    }
}
