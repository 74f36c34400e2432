//! Scheuermann's shading inputs at the groom's own strands, for his ground
//! truth (`scheuermann.reference_shade`, docs/reference.md). At every point
//! of every strand: the normal a patch would face there ([`super::outward`]),
//! the ambient occlusion baked as for patch vertices ([`super::ao`]), and a
//! texture column, one of the hair texture's strands picked per groom
//! strand, so that strands vary in brightness, highlight shift and sparkle
//! as the texture's strands do.

use glam::Vec3;
use rayon::prelude::*;

use super::texture::{HairTexture, hash};
use super::{Strands, ao, centre, outward};
use crate::groom::Groom;

/// One point's inputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrandShading {
    /// Unit, outward, perpendicular to the strand's tangent (groom space).
    pub normal: Vec3,
    /// Ambient occlusion in [0, 1], 1 = unoccluded.
    pub ao: f32,
    /// Texture u at the centre of the strand's column.
    pub u: f32,
}

/// The inputs at every point of `groom`, in its point order; `seed` is the
/// hair texture's (the scene's patch seed).
pub fn strand_shading(groom: &Groom, seed: u64) -> Vec<StrandShading> {
    let strands = Strands::new(groom);
    let centre = centre::head_centre(&strands);
    let density = ao::density(&strands);
    let out = outward::Outward {
        centre,
        grid: density.as_ref(),
    };
    let columns = HairTexture::strand_columns(seed);
    let dirs = ao::directions();
    let marcher = density.as_ref().map(|g| g.marcher());
    (0..groom.strand_count())
        .into_par_iter()
        .flat_map_iter(|s| {
            let points = &groom.positions[groom.strand_range(s)];
            let column = columns[hash(seed, &[s as u32]) as usize % columns.len().max(1)];
            let u = (column as f32 + 0.5) / HairTexture::WIDTH as f32;
            (0..points.len())
                .map(|i| {
                    let (a, b) = (
                        points[i.saturating_sub(1)],
                        points[(i + 1).min(points.len() - 1)],
                    );
                    let tangent = (b - a).normalize_or(Vec3::Y);
                    let radial = out.at(points[i]);
                    let normal = (radial - tangent * radial.dot(tangent))
                        .normalize_or(tangent.any_orthonormal_vector());
                    let ao = match (&density, &marcher) {
                        (Some(g), Some(m)) => {
                            ao::occlusion(g, m, &dirs, points[i], tangent, normal)
                        }
                        _ => 1.0,
                    };
                    StrandShading { normal, ao, u }
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_point_gets_a_frame_an_occlusion_and_a_strand_column() {
        let groom = super::super::tests::sphere_groom(3);
        let shading = strand_shading(&groom, 1);
        assert_eq!(shading.len(), groom.point_count());
        let columns = HairTexture::strand_columns(1);
        for (i, s) in shading.iter().enumerate() {
            assert!((s.normal.length() - 1.0).abs() < 1e-4, "{i}: {s:?}");
            assert!((0.0..=1.0).contains(&s.ao), "{i}: {s:?}");
            let column = (s.u * HairTexture::WIDTH as f32) as u32;
            assert!(
                columns.contains(&column),
                "{i}: column {column} is not on a strand"
            );
        }
        // Inner points are occluded more than the outermost.
        let (lo, hi) = shading
            .iter()
            .fold((1.0f32, 0.0f32), |(lo, hi), s| (lo.min(s.ao), hi.max(s.ao)));
        assert!(hi - lo > 0.1, "AO spans {lo}..{hi}");
    }
}
