//! Baked ambient occlusion per patch vertex. Scheuermann 2004: "Ambient occlusion to
//! approximate self-shadowing - Per vertex"; the shader multiplies the colour by it
//! ("modulate color by ambient occlusion term"). Strand length is splatted into a voxel
//! grid over the groom; a vertex's AO is the mean transmittance along a fixed set of
//! directions over the hemisphere about its outward normal.

use glam::Vec3;
use rayon::prelude::*;

use super::{Patch, Strands};
use crate::bounds::Aabb;
use crate::density::DensityGrid;

/// Cells along the groom's longest side.
const RES: i32 = 48;

/// Optical depth per cell length at the groom's typical density (see [`typical`]).
/// Chosen so that where the hair lies on the scalp (on the procedural head's Straight
/// and Long grooms, 6k to 60k strands) the outermost vertices stay near 1 (their
/// hemisphere leaves the hair within a cell; only grazing directions cross it) and the
/// innermost, next to the skin under 2-3 cm of hair, are clearly darker. Twice this
/// (1.2) put the innermost tenth at 0.35-0.55 but took the hair bunched over the
/// shoulders nearly black in the renders; 0.35 left the inner vertices at 0.7-0.8,
/// barely darker than the outer ones. The density is normalized per
/// groom, so a sparse groom darkens like a dense one of the same shape: AO here
/// measures depth in the hair, not strand count.
const EXTINCTION: f32 = 0.6;

/// The directions, in the vertex's (binormal, tangent, normal) frame: eight points of a
/// Fibonacci spiral on the unit disc lifted onto the hemisphere, which spreads them
/// evenly in cosine-weighted measure, so an equal-weight mean approximates the cosine-
/// weighted occlusion integral.
pub(super) fn directions() -> [Vec3; 8] {
    const GOLDEN_ANGLE: f32 = 2.399_963;
    std::array::from_fn(|k| {
        let r = ((k as f32 + 0.5) / 8.0).sqrt();
        let phi = k as f32 * GOLDEN_ANGLE;
        Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - r * r).sqrt())
    })
}

/// Bakes `ao` into every vertex of `patches`.
pub(super) fn bake(patches: &mut [Patch], grid: &DensityGrid) {
    let dirs = directions();
    let marcher = grid.marcher();
    patches.par_iter_mut().for_each(|p| {
        for v in &mut p.vertices {
            v.ao = occlusion(grid, &marcher, &dirs, v.position, v.tangent, v.normal);
        }
    });
}

/// The AO of one point with unit `tangent` and `normal`: the mean
/// transmittance along `dirs` over the hemisphere about `normal`.
pub(super) fn occlusion(
    grid: &DensityGrid,
    marcher: &crate::density::Marcher<'_>,
    dirs: &[Vec3; 8],
    position: Vec3,
    tangent: Vec3,
    normal: Vec3,
) -> f32 {
    // Beyond this depth a direction's transmittance is below 1e-4.
    let limit = 9.3 / EXTINCTION;
    let b = tangent.cross(normal);
    let from = grid.to_grid(position);
    let sum: f32 = dirs
        .iter()
        .map(|d| {
            let dir = b * d.x + tangent * d.y + normal * d.z;
            (-EXTINCTION * marcher.optical_depth(from, dir, limit)).exp()
        })
        .sum();
    (sum / dirs.len() as f32).clamp(0.0, 1.0)
}

/// Strand length (in cell lengths) per cell, splatted at half-cell steps along every
/// segment so that long segments leave no holes, then divided by [`typical`]. Splatted
/// in a fixed number of chunks summed in order, so the result does not depend on the
/// thread count.
pub(super) fn density(strands: &Strands) -> Option<DensityGrid> {
    let bounds = strands
        .valid
        .iter()
        .flat_map(|&s| strands.points(s))
        .fold(Aabb::EMPTY, |b, &p| b.grow(p));
    let empty = DensityGrid::cubic(bounds, RES)?;
    let edge = empty.cell_size().x;
    let max_steps = 4 * RES as u32;
    let chunk = strands.valid.len().div_ceil(16).max(1);
    let parts: Vec<DensityGrid> = strands
        .valid
        .par_chunks(chunk)
        .map(|ids| {
            let mut g = empty.cleared();
            for &s in ids {
                for w in strands.points(s).windows(2) {
                    let len = w[0].distance(w[1]);
                    let m = ((len / (0.5 * edge)) as u32 + 1).min(max_steps);
                    let step = 1.0 / m as f32;
                    for k in 0..m {
                        g.add(w[0].lerp(w[1], (k as f32 + 0.5) * step), len * step / edge);
                    }
                }
            }
            g
        })
        .collect();
    let mut grid = parts.iter().fold(empty, |a, b| a.merge(b));
    let t = typical(grid.data());
    if t > 0.0 {
        grid.scale(1.0 / t);
    }
    Some(grid)
}

/// The density the average bit of strand sits in: the density-weighted mean Σd²/Σd. Unlike
/// the maximum it ignores a lone hot cell (where roots crowd), and unlike the plain mean
/// it ignores the many near-empty cells at the wispy tips.
fn typical(data: &[f32]) -> f32 {
    let (s1, s2) = data.iter().fold((0f64, 0f64), |(a, b), &d| {
        (a + d as f64, b + (d as f64).powi(2))
    });
    if s1 > 0.0 { (s2 / s1) as f32 } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_cover_the_hemisphere() {
        let d = directions();
        assert!(
            d.iter()
                .all(|v| (v.length() - 1.0).abs() < 1e-5 && v.z > 0.0)
        );
        // Cosine-weighted: the mean cosine is 2/3.
        let mean = d.iter().map(|v| v.z).sum::<f32>() / 8.0;
        assert!((mean - 2.0 / 3.0).abs() < 0.02, "{mean}");
        let centroid = d.iter().map(|v| v.truncate()).sum::<glam::Vec2>() / 8.0;
        assert!(centroid.length() < 0.15, "{centroid}");
    }

    #[test]
    fn typical_density_ignores_empty_cells() {
        assert_eq!(typical(&[0.0, 0.0, 2.0, 2.0]), 2.0);
        assert_eq!(typical(&[0.0; 4]), 0.0);
    }
}
