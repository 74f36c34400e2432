//! Strand evaluation from a hair mesh bundle (Lipp §2, §3.1.1), shared by the
//! rasterizer's CPU kernel and ported to `shaders/lipp/common.wgsl`.
//!
//! Lipp §3.1.1: "The first pass assembles a base spline where each control
//! point has a tangent calculated from its previous and next vertices via
//! finite differences. This tangent is then used together with the position
//! to calculate the Hermite spline between two control points. Once the base
//! spline is built, we further subdivide it based on the desired resolution
//! ... Each position is then used as the input for the styling function f(x)
//! ... Each tangent is again calculated from the previous and next control
//! points."
//!
//! Deviations, all deterministic integer or plain f32 arithmetic so every
//! backend evaluates the same strand:
//! - strand identities: (u, v) is the R2 low-discrepancy sequence in 32-bit
//!   fixed point (as `strandgen::strand_uv`, but exact on GPUs without f64),
//!   so the N_LOD strands a LOD keeps are a prefix that covers the bundle;
//!   Code 1 draws (u, v) from a PCG seeded by the strand index, which has no
//!   such prefix property. Per-strand styling randomness is a PCG hash.
//! - twist is applied to (u, v) per layer, before the base spline, so the
//!   styled strand costs one bilinear lookup per layer instead of a second
//!   spline for the bundle centre.
//! - curl and noise are offsets in a frame made of the base direction and the
//!   bundle's u axis (interpolated like the positions), which, unlike an
//!   arbitrary orthonormal basis, does not flip along the strand.

use super::{BundleRecord, Corner, add, cross, dot, mix, normalize, pcg, scale, sub, unit};
use crate::kernel::Words;

const TAU: f32 = std::f32::consts::TAU;
const PI: f32 = std::f32::consts::PI;

/// R2 sequence constants × 2^32 (1/φ₂ and 1/φ₂²).
const R2_A1: u32 = 3_242_174_889;
const R2_A2: u32 = 2_447_445_414;

/// (u, v) of strand `k` of a bundle.
pub fn strand_uv(k: u32) -> [f32; 2] {
    let u = 0x8000_0000u32.wrapping_add(k.wrapping_mul(R2_A1));
    let v = 0x8000_0000u32.wrapping_add(k.wrapping_mul(R2_A2));
    [unit(u), unit(v)]
}

/// Three hashes in [0, 1) identifying strand `k` of a bundle with `seed`.
pub fn strand_id(seed: u32, k: u32) -> [f32; 3] {
    let h = pcg(seed ^ pcg(k));
    let h2 = pcg(h);
    [unit(h), unit(h2), unit(pcg(h2))]
}

/// A base-spline point of one layer: position, direction (finite difference,
/// filled in by the caller), the bundle's u axis, and AO.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LayerPoint {
    pub pos: [f32; 3],
    pub tangent: [f32; 3],
    pub axis: [f32; 3],
    pub ao: f32,
}

/// The quad `c` at (u, v), corner k at [(0,0), (1,0), (1,1), (0,1)][k].
pub fn bilinear(c: [[f32; 3]; 4], u: f32, v: f32) -> [f32; 3] {
    let bottom = mix(c[0], c[1], u);
    let top = mix(c[3], c[2], u);
    mix(bottom, top, v)
}

/// Layer `i` of bundle `b` at strand (u, v), twisted (styling, see above).
pub fn layer_point(layers: &Words<'_>, b: &BundleRecord, i: u32, uv: [f32; 2]) -> LayerPoint {
    let l = (b.first_layer + i) as usize;
    let c: [Corner; 4] = std::array::from_fn(|k| Corner::load(layers, l, k));
    let angle = b.twist * TAU * c[0].w;
    let (s, co) = (angle.sin(), angle.cos());
    let (x, y) = (uv[0] - 0.5, uv[1] - 0.5);
    let u = x * co - y * s + 0.5;
    let v = x * s + y * co + 0.5;
    let pos = bilinear(c.map(|k| k.position), u, v);
    let p = c.map(|k| k.position);
    let axis = scale(add(sub(p[1], p[0]), sub(p[2], p[3])), 0.5);
    let ao_b = c[0].ao + (c[1].ao - c[0].ao) * u;
    let ao_t = c[3].ao + (c[2].ao - c[3].ao) * u;
    LayerPoint {
        pos,
        tangent: [0.0; 3],
        axis,
        ao: ao_b + (ao_t - ao_b) * v,
    }
}

/// Lipp Code 1, `calcTangent`: finite differences, one-sided at root and tip.
pub fn calc_tangent(
    idx: u32,
    count: u32,
    prev: [f32; 3],
    curr: [f32; 3],
    next: [f32; 3],
) -> [f32; 3] {
    if idx == 0 {
        normalize(sub(next, curr))
    } else if idx + 1 >= count {
        normalize(sub(curr, prev))
    } else {
        normalize(sub(next, prev))
    }
}

/// A styled control point.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ControlPoint {
    pub pos: [f32; 3],
    pub w: f32,
    pub ao: f32,
}

/// Control point `k` of `c` of a strand whose base layers are `base` (with
/// tangents): the Hermite base spline subdivided at w = k / (c − 1), then
/// the styling function (curl and noise offsets, faded in over the first
/// eighth of the strand as in `strandgen`). `styling` off returns the base.
pub fn eval_cp(
    base: &[LayerPoint],
    b: &BundleRecord,
    id: [f32; 3],
    k: u32,
    c: u32,
    styling: bool,
) -> ControlPoint {
    let n = base.len() as u32;
    let w = k as f32 / (c - 1) as f32;
    let f = w * (n - 1) as f32;
    let i = (f.floor() as u32).min(n - 2);
    let t = f - i as f32;
    let (p0, p1) = (&base[i as usize], &base[i as usize + 1]);
    let len = length3(sub(p1.pos, p0.pos));
    let (t2, t3) = (t * t, t * t * t);
    let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
    let h10 = t3 - 2.0 * t2 + t;
    let h01 = -2.0 * t3 + 3.0 * t2;
    let h11 = t3 - t2;
    let mut pos = add(
        add(scale(p0.pos, h00), scale(p0.tangent, h10 * len)),
        add(scale(p1.pos, h01), scale(p1.tangent, h11 * len)),
    );
    let ao = p0.ao + (p1.ao - p0.ao) * t;
    if styling {
        let dir = normalize(mix(p0.tangent, p1.tangent, t));
        let axis = mix(p0.axis, p1.axis, t);
        let b1 = normalize(sub(axis, scale(dir, dot(axis, dir))));
        let b2 = cross(dir, b1);
        let ramp = (w * 8.0).min(1.0);
        let mut off = [0.0f32; 3];
        if b.curl_radius > 0.0 {
            let a = TAU * (b.curl_turns * w + id[0]);
            off = add(
                off,
                scale(add(scale(b1, a.cos()), scale(b2, a.sin())), b.curl_radius),
            );
        }
        if b.noise > 0.0 {
            let amp = b.noise * (PI * w * (1.0 + 2.0 * id[1])).sin();
            let n = [id[0] * 2.0 - 1.0, id[1] * 2.0 - 1.0, id[2] * 2.0 - 1.0];
            off = add(off, scale(n, amp));
        }
        pos = add(pos, scale(off, ramp));
    }
    ControlPoint { pos, w, ao }
}

fn length3(a: [f32; 3]) -> f32 {
    dot(a, a).sqrt()
}

/// `subgroupShuffleUp(v, 1)` over a workgroup of emulated subgroups of
/// `width` lanes: lane `i` gets lane `i − 1`'s value, or `None` at the first
/// lane of a subgroup (where the WGSL recomputes the neighbour instead).
pub fn shuffle_up<T: Copy>(values: &[T], width: usize) -> Vec<Option<T>> {
    (0..values.len())
        .map(|i| (i % width != 0).then(|| values[i - 1]))
        .collect()
}

/// `subgroupShuffleDown(v, 1)`: lane `i` gets lane `i + 1`'s value, `None` at
/// the last lane of a subgroup or of the workgroup.
pub fn shuffle_down<T: Copy>(values: &[T], width: usize) -> Vec<Option<T>> {
    (0..values.len())
        .map(|i| (i % width != width - 1 && i + 1 < values.len()).then(|| values[i + 1]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU32, AtomicU64};

    #[test]
    fn r2_prefixes_cover_the_bundle() {
        let uvs: Vec<[f32; 2]> = (0..64).map(strand_uv).collect();
        for q in 0..4 {
            let (u0, v0) = ((q % 2) as f32 * 0.5, (q / 2) as f32 * 0.5);
            let n = uvs
                .iter()
                .filter(|p| p[0] >= u0 && p[0] < u0 + 0.5 && p[1] >= v0 && p[1] < v0 + 0.5)
                .count();
            assert!((12..=20).contains(&n), "quadrant {q}: {n}");
        }
    }

    #[test]
    fn shuffles_stop_at_subgroup_edges() {
        let v = [0, 1, 2, 3, 4, 5];
        assert_eq!(
            shuffle_up(&v, 4),
            vec![None, Some(0), Some(1), Some(2), None, Some(4)]
        );
        assert_eq!(
            shuffle_down(&v, 4),
            vec![Some(1), Some(2), Some(3), None, Some(5), None]
        );
    }

    /// A straight vertical bundle: the unstyled strand is a straight line
    /// through the layers, evenly subdivided.
    #[test]
    fn straight_bundle_gives_a_straight_evenly_spaced_strand() {
        let layers = 4u32;
        let mut words = Vec::new();
        for i in 0..layers {
            let y = -(i as f32) * 0.1;
            for c in [[0.0, 0.0], [0.02, 0.0], [0.02, 0.02], [0.0, 0.02]] {
                let w = i as f32 / (layers - 1) as f32;
                words.extend([c[0], y, c[1], 1.0, 0.0, -1.0, 0.0, w].map(f32::to_bits));
            }
        }
        let atoms: Vec<AtomicU32> = words.into_iter().map(AtomicU32::new).collect();
        let oob = AtomicU64::new(0);
        let w = Words::new(&atoms, &oob);
        let b = BundleRecord {
            layer_count: layers,
            strands: 1,
            ..Default::default()
        };
        let uv = [0.5, 0.5];
        let mut base: Vec<LayerPoint> = (0..layers).map(|i| layer_point(&w, &b, i, uv)).collect();
        for i in 0..layers as usize {
            let prev = base[i.saturating_sub(1)].pos;
            let next = base[(i + 1).min(layers as usize - 1)].pos;
            base[i].tangent = calc_tangent(i as u32, layers, prev, base[i].pos, next);
        }
        let c = 9;
        for k in 0..c {
            let p = eval_cp(&base, &b, [0.0; 3], k, c, true);
            let y = -0.3 * k as f32 / (c - 1) as f32;
            assert!(
                length3(sub(p.pos, [0.01, y, 0.01])) < 1e-5,
                "{k}: {:?}",
                p.pos
            );
        }
        assert_eq!(oob.into_inner(), 0);
    }
}
