//! From a clump of strands to its layered strips. Scheuermann 2004: "Several layers of
//! patches to approximate volumetric qualities of hair". A clump's strands are ranked by
//! how far outward they lie from the clump's mean, cut into layers of near-equal size,
//! and each layer becomes one ribbon along its own mean strand, facing outward, as wide
//! as its strands spread across it.

use glam::Vec3;

use super::outward::Outward;
use super::texture::{HairTexture, hash};
use super::{PATCH_SEGMENTS, Patch, PatchParams, PatchVertex, Strands};

const N: usize = PATCH_SEGMENTS + 1;

/// Narrowest strip: half a millimetre, so a one-strand layer still shows its texture.
const MIN_WIDTH: f32 = 0.5e-3;

/// A clump split into layers: its outward normals and its strands, innermost layer first.
pub(super) struct ClumpLayers {
    /// Unit outward normals of the clump's mean strand, per cross-section.
    pub n: [Vec3; N],
    pub groups: Vec<Vec<u32>>,
}

/// Ranks the clump's strands by how far outward they lie from its mean strand and cuts
/// them into `layers` (at most one per strand) groups of near-equal size. `None` for a
/// clump without length.
pub(super) fn clump_layers(
    strands: &Strands,
    members: &[u32],
    outward: &Outward<'_>,
    layers: u32,
) -> Option<ClumpLayers> {
    let mut guide = mean_line(strands, members);
    relax(&mut guide);
    let t = tangents(&guide)?;
    // Outward: out of the hair volume (outward.rs), perpendicular to the strands.
    let n = frame_normals(&t, |i| outward.at(guide[i]));
    let ranked = ranked_outward(strands, members, &guide, &n);
    let l = (layers as usize).min(ranked.len());
    let groups = (0..l)
        .map(|g| ranked[g * ranked.len() / l..(g + 1) * ranked.len() / l].to_vec())
        .collect();
    Some(ClumpLayers { n, groups })
}

/// The patches of one clump with their inside-to-outside sort keys, inner layer first.
pub(super) fn clump_patches(
    strands: &Strands,
    members: &[u32],
    clump: u32,
    outward: &Outward<'_>,
    params: &PatchParams,
) -> Vec<(f32, Patch)> {
    let Some(c) = clump_layers(strands, members, outward, params.layers) else {
        return Vec::new();
    };
    c.groups
        .iter()
        .enumerate()
        .filter_map(|(l, g)| strip(strands, g, &c.n, clump, l as u32, outward.centre, params))
        .collect()
}

/// The mean of the members' resampled points, per cross-section.
fn mean_line(strands: &Strands, members: &[u32]) -> [Vec3; N] {
    let mut line = [Vec3::ZERO; N];
    for &s in members {
        for (a, p) in line.iter_mut().zip(strands.points(s)) {
            *a += *p;
        }
    }
    line.map(|a| a / members.len().max(1) as f32)
}

/// The sharpest turn a centre line may take at a cross-section: 60°.
const MAX_TURN_COS: f32 = 0.5;

/// Relaxes sharp turns out of a mean line. The mean of a loose clump (strands of
/// different lengths or paths averaged at equal fractions of their lengths, as where a
/// ponytail gathers them, or an aliased ringlet) can zigzag, turning by more than 90°
/// between cross-sections, and no ribbon follows that without folding over. Interior
/// points turning by more than 60° move halfway to their neighbours' midpoint until none
/// does (at most 32 passes); the root and the tip stay.
fn relax(line: &mut [Vec3; N]) {
    for _ in 0..32 {
        let mut changed = false;
        for i in 1..N - 1 {
            let a = (line[i] - line[i - 1]).normalize_or_zero();
            let b = (line[i + 1] - line[i]).normalize_or_zero();
            if a != Vec3::ZERO && b != Vec3::ZERO && a.dot(b) < MAX_TURN_COS {
                line[i] = line[i] * 0.5 + (line[i - 1] + line[i + 1]) * 0.25;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
}

/// Unit tangents root → tip: the normalized sum of the unit directions of the segments
/// on either side (one-sided at the ends), so a tangent never points against the segment
/// leaving its cross-section, even where the line zigzags. Where the line stalls or turns
/// straight back, the segment ahead or the previous tangent is used; `None` if the line
/// has no length.
fn tangents(line: &[Vec3; N]) -> Option<[Vec3; N]> {
    let d: [Vec3; N - 1] = std::array::from_fn(|k| (line[k + 1] - line[k]).normalize_or_zero());
    let mut t = [Vec3::ZERO; N];
    for (i, ti) in t.iter_mut().enumerate() {
        let ahead = d.get(i).copied().unwrap_or(Vec3::ZERO);
        let behind = i.checked_sub(1).map_or(Vec3::ZERO, |k| d[k]);
        *ti = (ahead + behind).try_normalize().unwrap_or(ahead);
    }
    let first = t.iter().copied().find(|d| *d != Vec3::ZERO)?;
    let mut prev = first;
    for ti in &mut t {
        if *ti == Vec3::ZERO {
            *ti = prev;
        }
        prev = *ti;
    }
    Some(t)
}

/// Most a strip's normal turns about its tangent from one cross-section to the next.
/// Below 90° both triangles of every quad keep facing +normal; 45° leaves margin for
/// the tangent turning too.
const MAX_TWIST: f32 = std::f32::consts::FRAC_PI_4;

/// Unit normals perpendicular to `t` that follow `want(i)` (a unit direction) with its
/// tangent part removed where that is well defined, else carry the neighbouring normal.
/// Where the line runs nearly along `want` (hair hanging straight below the head's
/// centre, or standing straight out of it) the perpendicular part is short and its
/// direction swings between cross-sections, and where the line bends across `want` it
/// flips; following it would turn the strip inside out. So the frame starts where `want`
/// is most perpendicular to the line and walks to both ends, turning the carried normal
/// towards `want`'s perpendicular part by how well defined that is (fully from sin 0.5,
/// 30°, not at all below sin 0.1) and by at most [`MAX_TWIST`] per step.
fn frame_normals(t: &[Vec3; N], want: impl Fn(usize) -> Vec3) -> [Vec3; N] {
    let part = |i: usize| {
        let d = want(i);
        let r = d - t[i] * d.dot(t[i]);
        if r.is_finite() { r } else { Vec3::ZERO }
    };
    let seed = (0..N)
        .max_by(|&a, &b| part(a).length().total_cmp(&part(b).length()))
        .unwrap_or(0);
    let mut n = [Vec3::ZERO; N];
    n[seed] = Some(part(seed))
        .filter(|r| r.length() >= 1e-6)
        .map_or_else(|| t[seed].any_orthonormal_vector(), Vec3::normalize);
    let step = |i: usize, prev: Vec3| {
        let carried = (prev - t[i] * prev.dot(t[i]))
            .try_normalize()
            .unwrap_or_else(|| t[i].any_orthonormal_vector());
        let r = part(i);
        let trust = ((r.length() - 0.1) / 0.4).clamp(0.0, 1.0);
        let trust = trust * trust * (3.0 - 2.0 * trust);
        // Turn about the tangent, in the plane of `carried` and `side`.
        let side = t[i].cross(carried);
        let angle = r.dot(side).atan2(r.dot(carried)) * trust;
        let angle = angle.clamp(-MAX_TWIST, MAX_TWIST);
        carried * angle.cos() + side * angle.sin()
    };
    for i in seed + 1..N {
        n[i] = step(i, n[i - 1]);
    }
    for i in (0..seed).rev() {
        n[i] = step(i, n[i + 1]);
    }
    n
}

/// The members sorted by mean radial offset ρ = mean over i of (p_i − guide_i)·n_i,
/// innermost first (ties by strand index).
fn ranked_outward(
    strands: &Strands,
    members: &[u32],
    guide: &[Vec3; N],
    n: &[Vec3; N],
) -> Vec<u32> {
    let mut rho: Vec<(f32, u32)> = members
        .iter()
        .map(|&s| {
            let p = strands.points(s);
            let sum: f32 = (0..N).map(|i| (p[i] - guide[i]).dot(n[i])).sum();
            (sum / N as f32, s)
        })
        .collect();
    rho.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    rho.into_iter().map(|(_, s)| s).collect()
}

/// One layer's strip along the mean of `group`, keeping the clump's outward normals
/// (re-orthogonalized) so the strip is oriented like its clump. `None` if it has no length.
pub(super) fn strip(
    strands: &Strands,
    group: &[u32],
    clump_n: &[Vec3; N],
    clump: u32,
    layer: u32,
    centre: Vec3,
    params: &PatchParams,
) -> Option<(f32, Patch)> {
    let mut line = mean_line(strands, group);
    relax(&mut line);
    let t = tangents(&line)?;
    let v = arc_parameter(&line)?;
    let n = frame_normals(&t, |i| clump_n[i]);
    let b: [Vec3; N] = std::array::from_fn(|i| t[i].cross(n[i]).normalize_or_zero());
    let mut w: [f32; N] =
        std::array::from_fn(|i| width(strands, group, line[i], b[i], i, params.width_sigmas));
    unfold(&line, &b, &n, &mut w);
    let per_variant = (HairTexture::WIDTH / HairTexture::VARIANTS) as f32;
    let variant = hash(params.seed, &[clump, layer]) % HairTexture::VARIANTS;
    let u = [variant, variant + 1].map(|x| x as f32 / HairTexture::VARIANTS as f32);
    let mut vertices = Vec::with_capacity(2 * N);
    let mut key = 0.0;
    for i in 0..N {
        for (side, u) in [-0.5f32, 0.5].into_iter().zip(u) {
            vertices.push(PatchVertex {
                position: line[i] + b[i] * (w[i] * side),
                tangent: t[i],
                normal: n[i],
                u,
                v: v[i],
                ao: 1.0,
                texels_per_metre: per_variant / w[i],
            });
        }
        key += (line[i] - centre).dot(n[i]) / N as f32;
    }
    Some((
        key,
        Patch {
            layer,
            clump,
            vertices,
        },
    ))
}

/// Cumulative arc length over total, 0 at the root and 1 at the tip.
fn arc_parameter(line: &[Vec3; N]) -> Option<[f32; N]> {
    let mut v = [0f32; N];
    for i in 1..N {
        v[i] = v[i - 1] + line[i].distance(line[i - 1]);
    }
    let total = v[N - 1];
    if total.is_nan() || total <= 1e-7 {
        return None;
    }
    Some(v.map(|x| x / total))
}

/// The strip's width at cross-section `i`: `sigmas` standard deviations of the strands'
/// offsets along the binormal, but at least four strand thicknesses and half a millimetre.
fn width(strands: &Strands, group: &[u32], c: Vec3, b: Vec3, i: usize, sigmas: f32) -> f32 {
    let (mut var, mut thick) = (0.0, 0.0);
    for &s in group {
        let d = (strands.points(s)[i] - c).dot(b);
        var += d * d;
        thick += strands.thickness(s)[i];
    }
    let k = group.len().max(1) as f32;
    let w = sigmas * (var / k).sqrt();
    w.max(4.0 * thick / k).max(MIN_WIDTH)
}

/// Narrows the strip where it would fold over itself: where the line bends in the
/// strip's plane more tightly than half the width, an edge runs backwards and a triangle
/// turns its back to +normal. Both widths of such a quad shrink until it faces +normal
/// again (a few passes, as narrowing one quad's end can fold its neighbour), overriding
/// the minimum width there, but never below 1/32 of the width the strands asked for.
fn unfold(line: &[Vec3; N], b: &[Vec3; N], n: &[Vec3; N], w: &mut [f32; N]) {
    let floor = w.map(|x| x / 32.0);
    for _ in 0..4 {
        let mut changed = false;
        for i in 0..N - 1 {
            while folded(line, b, n[i], w, i) && (w[i] > floor[i] || w[i + 1] > floor[i + 1]) {
                w[i] = (w[i] * 0.75).max(floor[i]);
                w[i + 1] = (w[i + 1] * 0.75).max(floor[i + 1]);
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
}

/// Whether either triangle of quad `i`, (2i, 2i+1, 2i+2) and (2i+1, 2i+3, 2i+2), faces
/// away from `normal`.
fn folded(line: &[Vec3; N], b: &[Vec3; N], normal: Vec3, w: &[f32; N], i: usize) -> bool {
    let left = |k: usize| line[k] - b[k] * (0.5 * w[k]);
    let right = |k: usize| line[k] + b[k] * (0.5 * w[k]);
    let n1 = (right(i) - left(i)).cross(left(i + 1) - left(i));
    let n2 = (right(i + 1) - right(i)).cross(left(i + 1) - right(i));
    !(n1.dot(normal) > 0.0 && n2.dot(normal) > 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangents_carry_over_stalls_and_reject_points() {
        let mut line = [Vec3::ZERO; N];
        for (i, p) in line.iter_mut().enumerate() {
            *p = Vec3::Y * (i.max(3) as f32); // stalls over the first points
        }
        let t = tangents(&line).unwrap();
        assert!(t.iter().all(|d| *d == Vec3::Y));
        assert!(tangents(&[Vec3::ONE; N]).is_none());
        assert!(arc_parameter(&[Vec3::ONE; N]).is_none());
    }

    #[test]
    fn normals_survive_hair_pointing_straight_out() {
        let t = [Vec3::Y; N];
        let check = |n: &[Vec3; N]| {
            for (ni, ti) in n.iter().zip(&t) {
                assert!((ni.length() - 1.0).abs() < 1e-5 && ni.dot(*ti).abs() < 1e-5);
            }
        };
        // Straight out from the centre at the root, then bending away.
        let n = frame_normals(&t, |i| {
            if i < 3 {
                Vec3::Y
            } else {
                Vec3::new(1.0, 1.0, 0.0).normalize()
            }
        });
        check(&n);
        assert!(n.iter().all(|x| x.distance(Vec3::X) < 1e-6), "{n:?}");
        // Nearly along the line, with a perpendicular part that flips from one
        // cross-section to the next: carried instead of followed.
        let n = frame_normals(&t, |i| {
            let side = if i % 2 == 0 { Vec3::Z } else { Vec3::NEG_Z };
            if i == 8 {
                Vec3::X
            } else {
                (Vec3::Y + side * 0.05).normalize()
            }
        });
        check(&n);
        assert!(n.iter().all(|x| x.distance(Vec3::X) < 1e-6), "{n:?}");
        // Nothing defines it: still a frame.
        check(&frame_normals(&t, |_| Vec3::Y));
        check(&frame_normals(&t, |_| Vec3::NAN));
    }
}
