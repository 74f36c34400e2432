//! Root skinning data. Kulikov (Indiana Jones, SIGGRAPH 2025):
//! "for each strand root we compute the closest triangle on the parent mesh, its
//! barycentrics and tangent frame", stored as `hairRootSkinningInfo_t`.

use glam::Vec3;
use rayon::prelude::*;

use crate::mesh::{Bvh, TriMesh};
use crate::octahedral::{
    pack_barycentrics, pack_unit_vector, unpack_barycentrics, unpack_unit_vector,
};

/// Kulikov: hairRootSkinningInfo_t, 16 bytes per strand root per mesh LOD.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RootSkinningInfo {
    pub idx_triangle: u32,
    /// Packed x and y barycentrics (16-bit unorm each); z = 1 - x - y.
    pub barycentrics: u32,
    /// Triangle normal, octahedral-packed.
    pub triangle_normal: u32,
    /// Triangle tangent (direction of the first edge), octahedral-packed.
    pub triangle_tangent: u32,
}

/// A triangle's tangent frame: tangent along edge ab, normal of the face.
pub fn triangle_frame(mesh: &TriMesh, t: usize) -> (Vec3, Vec3) {
    let [a, b, _] = mesh.corners(t);
    let n = mesh.face_normal(t);
    let tangent = (b - a).reject_from(n).normalize_or_zero();
    (tangent, n)
}

impl RootSkinningInfo {
    /// Builds the record for a root known to lie on triangle `t` with barycentrics `bary`.
    pub fn new(mesh: &TriMesh, t: u32, bary: Vec3) -> Self {
        let (tangent, normal) = triangle_frame(mesh, t as usize);
        RootSkinningInfo {
            idx_triangle: t,
            barycentrics: pack_barycentrics(bary),
            triangle_normal: pack_unit_vector(normal),
            triangle_tangent: pack_unit_vector(tangent),
        }
    }

    /// The root position re-derived from the (possibly deformed) mesh.
    pub fn root_position(&self, mesh: &TriMesh) -> Option<Vec3> {
        let tri = mesh.triangles.get(self.idx_triangle as usize)?;
        let [a, b, c] = tri.map(|i| mesh.positions.get(i as usize).copied());
        let w = unpack_barycentrics(self.barycentrics);
        Some(a? * w.x + b? * w.y + c? * w.z)
    }

    pub fn normal(&self) -> Vec3 {
        unpack_unit_vector(self.triangle_normal)
    }
    pub fn tangent(&self) -> Vec3 {
        unpack_unit_vector(self.triangle_tangent)
    }
}

/// Bakes skinning records for strand roots against their parent mesh (closest triangle).
pub fn bake(mesh: &TriMesh, roots: &[Vec3]) -> Vec<RootSkinningInfo> {
    if mesh.triangles.is_empty() {
        return Vec::new();
    }
    let bvh = Bvh::new(mesh);
    roots
        .par_iter()
        .map(|&r| {
            bvh.closest(r)
                .map(|h| RootSkinningInfo::new(mesh, h.triangle, h.barycentric))
                .unwrap_or_default()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural::generators::{GroomParams, Style};
    use crate::procedural::head::HeadParams;
    use crate::procedural::surface::{Shape, Surface};

    #[test]
    fn record_is_16_bytes() {
        assert_eq!(std::mem::size_of::<RootSkinningInfo>(), 16);
    }

    #[test]
    fn roots_rederived_from_skinning_land_where_they_were() {
        let surface = Surface::procedural(Shape::Head(HeadParams::default()));
        let head = &surface.mesh;
        let g = GroomParams {
            style: Style::Straight,
            strands: 2000,
            points: 4,
            ..GroomParams::default()
        }
        .generate(&surface);
        let roots = g.groom.roots();
        let skin = bake(head, &roots);
        let size = head.bounds().size().max_element();
        for (r, s) in roots.iter().zip(&skin) {
            let p = s.root_position(head).unwrap();
            // 16-bit barycentrics on triangles of a few mm: well under 1e-4 of the head size.
            assert!(p.distance(*r) < 1e-4 * size, "{r} vs {p}");
            let (t, n) = triangle_frame(head, s.idx_triangle as usize);
            assert!(s.normal().distance(n) < 1e-3);
            assert!(s.tangent().distance(t) < 1e-3);
        }
        // The generator's own records (made while planting) re-derive the roots too.
        for (r, s) in roots.iter().zip(&g.skinning) {
            assert!(s.root_position(head).unwrap().distance(*r) < 1e-4 * size);
        }
    }

    #[test]
    fn skinned_roots_follow_a_moved_mesh() {
        let head = HeadParams::default().build();
        let roots: Vec<Vec3> = head.positions.iter().step_by(97).copied().collect();
        let skin = bake(&head, &roots);
        let mut moved = head.clone();
        moved
            .positions
            .iter_mut()
            .for_each(|p| *p += Vec3::new(0.1, 0.2, 0.3));
        for (r, s) in roots.iter().zip(&skin) {
            let p = s.root_position(&moved).unwrap();
            assert!(p.distance(*r + Vec3::new(0.1, 0.2, 0.3)) < 1e-4);
        }
    }
}
