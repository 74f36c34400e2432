//! A mesh to plant strands on: root sampling by region, interpolated normals and, for
//! the procedural star-shaped meshes, an exact push-out so strands never enter it.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::head::{BodyParams, HeadParams};
use crate::mesh::TriMesh;

/// The analytic shape behind a procedural mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Shape {
    Head(HeadParams),
    Body(BodyParams),
}

impl Shape {
    pub fn radial(&self, d: Vec3) -> f32 {
        match self {
            Shape::Head(h) => h.radial(d),
            Shape::Body(b) => b.radial(d),
        }
    }
    pub fn build(&self) -> TriMesh {
        match self {
            Shape::Head(h) => h.build(),
            Shape::Body(b) => b.build(),
        }
    }
}

/// Where on a mesh roots are planted (directions are about the mesh's centre; y up, +z front).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Region {
    /// Above a hairline: high on the forehead, low at the nape.
    Scalp,
    /// Chin, jaw and upper lip.
    Beard,
    /// Two arcs above the eyes.
    Eyebrows,
    /// The whole surface (fur).
    Everywhere,
}

impl Region {
    /// Whether the surface point in direction `d` (unit, from the centre) is in the region.
    pub fn contains(self, d: Vec3) -> bool {
        let elev = d.y.clamp(-1.0, 1.0).asin();
        let horizontal = (d.x * d.x + d.z * d.z).sqrt();
        let front = if horizontal > 1e-6 {
            d.z / horizontal
        } else {
            0.0
        };
        let azimuth = d.x.atan2(d.z);
        match self {
            Region::Scalp => {
                let hairline = if front > 0.0 {
                    0.12 + 0.42 * front
                } else {
                    0.12 + 0.75 * front
                };
                elev > hairline
            }
            Region::Beard => front > 0.45 && elev < -0.12 && elev > -0.95,
            Region::Eyebrows => {
                elev > 0.2 && elev < 0.27 && azimuth.abs() > 0.1 && azimuth.abs() < 0.6
            }
            Region::Everywhere => true,
        }
    }
}

/// A mesh with what strand generation needs.
pub struct Surface {
    pub mesh: TriMesh,
    pub normals: Vec<Vec3>,
    pub shape: Option<Shape>,
    pub center: Vec3,
}

impl Surface {
    pub fn procedural(shape: Shape) -> Surface {
        let mesh = shape.build();
        Surface {
            normals: mesh.vertex_normals(),
            mesh,
            shape: Some(shape),
            center: Vec3::ZERO,
        }
    }
    pub fn from_mesh(mesh: TriMesh) -> Surface {
        Surface {
            normals: mesh.vertex_normals(),
            center: mesh.bounds().center(),
            mesh,
            shape: None,
        }
    }

    pub fn point(&self, t: u32, bary: Vec3) -> Vec3 {
        let [a, b, c] = self.mesh.corners(t as usize);
        a * bary.x + b * bary.y + c * bary.z
    }
    /// Smooth (vertex-interpolated) normal.
    pub fn normal(&self, t: u32, bary: Vec3) -> Vec3 {
        let [a, b, c] = self.mesh.triangles[t as usize].map(|i| self.normals[i as usize]);
        let n = (a * bary.x + b * bary.y + c * bary.z).normalize_or_zero();
        if n == Vec3::ZERO {
            self.mesh.face_normal(t as usize)
        } else {
            n
        }
    }

    /// Moves `p` out of the analytic shape to at least `margin` above its surface.
    pub fn push_out(&self, p: Vec3, margin: f32) -> Vec3 {
        let Some(shape) = self.shape else { return p };
        let v = p - self.center;
        let len = v.length();
        if len < 1e-9 {
            return p;
        }
        let d = v / len;
        let min = shape.radial(d) + margin;
        if len < min { self.center + d * min } else { p }
    }

    /// Area-weighted cumulative distribution over the triangles in `region`.
    pub fn region_cdf(&self, region: Region) -> Vec<f32> {
        let mut acc = 0.0;
        (0..self.mesh.triangle_count())
            .map(|t| {
                let [a, b, c] = self.mesh.corners(t);
                let d = ((a + b + c) / 3.0 - self.center).normalize_or_zero();
                if region.contains(d) {
                    acc += self.mesh.face_area(t);
                }
                acc
            })
            .collect()
    }
}

/// Picks a triangle from a CDF and a uniform `u` in [0, 1), and a uniform barycentric
/// point from two more uniforms.
pub fn sample_triangle(cdf: &[f32], u: f32, r1: f32, r2: f32) -> Option<(u32, Vec3)> {
    let total = *cdf.last()?;
    if total <= 0.0 {
        return None;
    }
    let target = u * total;
    let t = cdf.partition_point(|&c| c <= target).min(cdf.len() - 1);
    let s = r1.sqrt();
    let bary = Vec3::new(1.0 - s, s * (1.0 - r2), s * r2);
    Some((t as u32, bary))
}
