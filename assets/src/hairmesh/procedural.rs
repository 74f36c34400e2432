//! Procedural hair meshes: bundles grown like guide strands from the surface, each a stack
//! of quads around its guide.

use glam::Vec3;

use super::{HairMesh, HairMeshParams};
use crate::procedural::surface::Surface;
use crate::procedural::{GroomParams, generators::perpendiculars};

impl HairMesh {
    /// Builds a hair mesh with `params.bundles` bundles shaped like `guide` strands on
    /// `surface`, holding `strands` strands in all.
    pub fn procedural(
        surface: &Surface,
        guide: &GroomParams,
        params: &HairMeshParams,
        strands: u32,
    ) -> HairMesh {
        let layers = params.layers.max(2);
        let guides = GroomParams {
            seed: guide.seed ^ params.seed,
            ..*guide
        }
        .guides(surface, params.bundles.max(1), layers);
        let count = guides.strand_count().max(1);
        // Bundle size from the area each bundle covers.
        let area: f32 = (0..surface.mesh.triangle_count())
            .map(|t| surface.mesh.face_area(t))
            .sum::<f32>()
            / 4.0; // the scalp is roughly a quarter of the head
        let half = (area / count as f32).sqrt() * 0.6;
        let mut mesh = HairMesh::default();
        let base = strands / count as u32;
        let extra = strands as usize % count;
        for s in 0..guides.strand_count() {
            let pts = guides.strand(s);
            let mut corners = Vec::with_capacity(pts.len());
            let mut axis: Option<Vec3> = None;
            for i in 0..pts.len() {
                let (a, b) = (i.saturating_sub(1), (i + 1).min(pts.len() - 1));
                let t = (pts[b] - pts[a]).normalize_or_zero();
                let a1 = match axis {
                    // Parallel transport keeps the quads from twisting.
                    Some(prev) => prev.reject_from(t).normalize_or_zero(),
                    None => perpendiculars(t).0,
                };
                let a1 = if a1 == Vec3::ZERO {
                    perpendiculars(t).0
                } else {
                    a1
                };
                axis = Some(a1);
                let a2 = t.cross(a1);
                let h = half * (1.0 - 0.4 * i as f32 / (pts.len() - 1) as f32);
                // Guides lie on the skin: lift the bundle's centre so its
                // cross-section rests on the head instead of half inside it.
                let c = if i == 0 {
                    pts[i]
                } else {
                    surface.push_out(pts[i], h + 0.001)
                };
                let q = [
                    c - a1 * h - a2 * h,
                    c + a1 * h - a2 * h,
                    c + a1 * h + a2 * h,
                    c - a1 * h + a2 * h,
                ];
                corners.push(q.map(|p| surface.push_out(p, 0.001)));
            }
            let n = base + u32::from(s < extra);
            mesh.push_bundle(&corners, n, params.style);
        }
        mesh.bake_ao(2.0);
        mesh
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural::surface::Shape;
    use crate::procedural::{HeadParams, Style};

    #[test]
    fn procedural_mesh_has_the_requested_shape() {
        let head = Surface::procedural(Shape::Head(HeadParams::default()));
        let m = HairMesh::procedural(
            &head,
            &GroomParams {
                style: Style::Long,
                ..Default::default()
            },
            &HairMeshParams {
                bundles: 300,
                layers: 8,
                style: Default::default(),
                seed: 1,
            },
            130_000,
        );
        m.validate().unwrap();
        assert_eq!(m.bundle_count(), 300);
        assert_eq!(m.layer_count(), 300 * 8);
        assert_eq!(m.strand_count(), 130_000);
        let g = m.to_groom(32, 1e-4);
        assert_eq!(g.point_count(), 130_000 * 32);
    }
}
