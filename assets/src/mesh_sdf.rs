//! Signed distance fields of meshes, for hair-head collisions.
//!
//! Kulikov: "Prebuilt SDFs for head collisions (0.25MB per head)". A field
//! is a cube of [`SDF_RES`]³ f32 distances (40³ × 4 bytes = 256,000 bytes,
//! the talk's quarter megabyte), sampled at grid points `min + i · voxel`,
//! negative inside the mesh. The distance is to the closest point of the
//! mesh (a BVH query per grid point); its sign comes from the interpolated
//! vertex normal there, which is robust on a closed or nearly closed surface
//! such as a head with an open neck.

use glam::{Mat4, Vec3};
use rayon::prelude::*;

use crate::Aabb;
use crate::mesh::{Bvh, TriMesh};

/// Grid points along each axis.
pub const SDF_RES: usize = 40;

/// A baked field: `SDF_RES`³ distances, x fastest, then y, then z.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshSdf {
    /// The grid point (0, 0, 0).
    pub min: Vec3,
    /// Spacing of the grid points (the same on every axis).
    pub voxel: f32,
    pub values: Vec<f32>,
}

impl MeshSdf {
    /// The field of `mesh` over `region` (grown to a cube about its centre,
    /// plus `padding` on every side), in a space that `to_mesh` maps into the
    /// mesh's local space (a uniform scale, rotation and translation);
    /// distances are in that space's units. `None` for a mesh without
    /// triangles or an empty region.
    pub fn bake(mesh: &TriMesh, to_mesh: Mat4, region: Aabb, padding: f32) -> Option<MeshSdf> {
        if mesh.triangles.is_empty() || region.is_empty() {
            return None;
        }
        let side = region.size().max_element() + 2.0 * padding;
        let voxel = side / (SDF_RES - 1) as f32;
        let min = region.center() - Vec3::splat(side * 0.5);
        let scale = to_mesh.x_axis.truncate().length();
        let bvh = Bvh::new(mesh);
        let normals = mesh.vertex_normals();
        let values = (0..SDF_RES * SDF_RES * SDF_RES)
            .into_par_iter()
            .map(|i| {
                let (x, y, z) = (i % SDF_RES, i / SDF_RES % SDF_RES, i / (SDF_RES * SDF_RES));
                let p = min + Vec3::new(x as f32, y as f32, z as f32) * voxel;
                let q = to_mesh.transform_point3(p);
                let Some(hit) = bvh.closest(q) else {
                    return f32::MAX;
                };
                let tri = mesh.triangles[hit.triangle as usize];
                let n = tri
                    .iter()
                    .zip(hit.barycentric.to_array())
                    .map(|(&v, w)| normals.get(v as usize).copied().unwrap_or(Vec3::ZERO) * w)
                    .sum::<Vec3>();
                let d = hit.distance_squared.sqrt() / scale;
                if (q - hit.point).dot(n) < 0.0 { -d } else { d }
            })
            .collect();
        Some(MeshSdf { min, voxel, values })
    }

    /// The stored distance at grid point (x, y, z).
    pub fn at(&self, x: usize, y: usize, z: usize) -> f32 {
        self.values[x + SDF_RES * (y + SDF_RES * z)]
    }

    /// The field's bytes on the GPU: [`SDF_RES`]³ × 4.
    pub const BYTES: usize = SDF_RES * SDF_RES * SDF_RES * 4;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural::HeadParams;

    /// An icosphere-like UV sphere of radius `r` at the origin.
    fn sphere(r: f32) -> TriMesh {
        let (rings, segs) = (48u32, 96u32);
        let mut m = TriMesh::default();
        for i in 0..=rings {
            let th = std::f32::consts::PI * i as f32 / rings as f32;
            for j in 0..segs {
                let ph = std::f32::consts::TAU * j as f32 / segs as f32;
                m.positions
                    .push(r * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()));
            }
        }
        for i in 0..rings {
            for j in 0..segs {
                let (a, b) = (i * segs + j, i * segs + (j + 1) % segs);
                let (c, d) = (a + segs, b + segs);
                m.triangles.push([a, b, c]);
                m.triangles.push([b, d, c]);
            }
        }
        m
    }

    #[test]
    fn a_sphere_s_field_is_its_distance() {
        let r = 0.1;
        let region = Aabb {
            min: Vec3::splat(-2.0 * r),
            max: Vec3::splat(2.0 * r),
        };
        // The grid is in a space scaled by 2 against the mesh: distances halve.
        let sdf =
            MeshSdf::bake(&sphere(r), Mat4::from_scale(Vec3::splat(0.5)), region, 0.04).unwrap();
        assert_eq!(sdf.values.len(), SDF_RES.pow(3));
        for (x, y, z) in [(0, 0, 0), (20, 20, 20), (5, 30, 19), (39, 2, 11)] {
            let p = sdf.min + Vec3::new(x as f32, y as f32, z as f32) * sdf.voxel;
            let want = (p.length() * 0.5 - r) * 2.0;
            // The tessellation's chords sit at most r (1 − cos(π/48)) = 0.2 mm inside.
            assert!(
                (sdf.at(x, y, z) - want).abs() < 1e-3,
                "{p}: {} vs {want}",
                sdf.at(x, y, z)
            );
        }
        assert!(sdf.at(20, 20, 20) < 0.0, "the centre is inside");
    }

    #[test]
    fn the_head_is_inside_its_field_and_its_surface_near_zero() {
        let head = HeadParams::default().build();
        let sdf = MeshSdf::bake(&head, Mat4::IDENTITY, head.bounds(), 0.02).unwrap();
        for p in head.positions.iter().step_by(501) {
            let f = (*p - sdf.min) / sdf.voxel;
            let [x, y, z] = f.round().to_array().map(|v| v as usize);
            // Within a voxel of the surface, the field is within a voxel of zero.
            assert!(
                sdf.at(x, y, z).abs() <= sdf.voxel,
                "{p}: {}",
                sdf.at(x, y, z)
            );
        }
        let c = head.bounds().center();
        let f = ((c - sdf.min) / sdf.voxel).round();
        assert!(sdf.at(f.x as usize, f.y as usize, f.z as usize) < -0.02);
    }
}
