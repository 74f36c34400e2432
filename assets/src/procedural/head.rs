//! Procedural head (a deformed ellipsoid with a neck) and body (a deformed ellipsoid),
//! both star-shaped about their origin so that `radial(direction)` gives the surface and
//! an exact outside test.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::mesh::TriMesh;
use crate::transform::Transform;

/// Polynomial smooth minimum (Quilez).
pub fn smin(a: f32, b: f32, k: f32) -> f32 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}
pub fn smax(a: f32, b: f32, k: f32) -> f32 {
    -smin(-a, -b, k)
}

/// Radius of the ellipsoid with semi-axes `s` along unit direction `d`.
fn ellipsoid_radial(d: Vec3, s: Vec3) -> f32 {
    1.0 / (d / s).length()
}

/// A head in metres: y up, +z forward (the face), origin at the head's centre.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HeadParams {
    /// Half width (x), half height above and below the centre (y), half depth (z).
    pub half_width: f32,
    pub half_height_top: f32,
    pub half_height_bottom: f32,
    pub half_depth: f32,
    pub neck_radius: f32,
    /// How far the neck reaches below the centre.
    pub neck_length: f32,
    /// Longitude segments; latitude rings are 3/4 of this.
    pub resolution: u32,
}

impl Default for HeadParams {
    fn default() -> Self {
        HeadParams {
            half_width: 0.076,
            half_height_top: 0.112,
            half_height_bottom: 0.1,
            half_depth: 0.098,
            neck_radius: 0.054,
            neck_length: 0.26,
            resolution: 128,
        }
    }
}

impl HeadParams {
    /// Distance from the origin to the surface along unit direction `d`.
    pub fn radial(&self, d: Vec3) -> f32 {
        let hy = if d.y >= 0.0 {
            self.half_height_top
        } else {
            self.half_height_bottom
        };
        // A slightly narrower jaw: squeeze x in the lower front.
        let jaw = 1.0 - 0.12 * (-d.y).max(0.0) * d.z.max(0.0);
        let head = ellipsoid_radial(d, Vec3::new(self.half_width * jaw, hy, self.half_depth));
        // The neck: a rounded superellipsoid column (|h/r|^4 + |y/l|^4 = 1), short above the centre.
        let horizontal = (d.x * d.x + d.z * d.z).sqrt();
        let l = if d.y < 0.0 { self.neck_length } else { 0.03 };
        let neck = 1.0 / ((horizontal / self.neck_radius).powi(4) + (d.y / l).powi(4)).powf(0.25);
        smax(head, neck, 0.025)
    }

    pub fn build(&self) -> TriMesh {
        star_mesh(|d| self.radial(d), self.resolution)
    }
}

/// A furry body: a deformed ellipsoid, long along z.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BodyParams {
    pub half_extents: [f32; 3],
    pub resolution: u32,
}

impl Default for BodyParams {
    fn default() -> Self {
        BodyParams {
            half_extents: [0.22, 0.26, 0.5],
            resolution: 128,
        }
    }
}

impl BodyParams {
    pub fn radial(&self, d: Vec3) -> f32 {
        let e = ellipsoid_radial(d, Vec3::from_array(self.half_extents));
        // A hump over the shoulders and a slimmer waist.
        e * (1.0 + 0.08 * d.y.max(0.0) * d.z.max(0.0)
            - 0.05 * (1.0 - d.z * d.z) * d.y.min(0.0).abs())
    }
    pub fn build(&self) -> TriMesh {
        star_mesh(|d| self.radial(d), self.resolution)
    }
}

/// Unit direction for latitude `theta` (0 = +y) and longitude `phi`.
fn direction(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.cos(),
        theta.sin() * phi.sin(),
    )
}

/// A closed latitude-longitude mesh of the star-shaped surface `radial`, wound outward.
pub fn star_mesh(radial: impl Fn(Vec3) -> f32, resolution: u32) -> TriMesh {
    let nu = resolution.max(8);
    let nv = (resolution * 3 / 4).max(6);
    let mut m = TriMesh {
        transform: Transform::IDENTITY,
        ..Default::default()
    };
    let top = Vec3::Y * radial(Vec3::Y);
    let bottom = -Vec3::Y * radial(-Vec3::Y);
    m.positions.push(top);
    for i in 1..nv {
        let theta = std::f32::consts::PI * i as f32 / nv as f32;
        for j in 0..nu {
            let phi = std::f32::consts::TAU * j as f32 / nu as f32;
            let d = direction(theta, phi);
            m.positions.push(d * radial(d));
        }
    }
    m.positions.push(bottom);
    let ring = |i: u32, j: u32| 1 + (i - 1) * nu + (j % nu);
    let last = m.positions.len() as u32 - 1;
    for j in 0..nu {
        m.triangles.push([0, ring(1, j + 1), ring(1, j)]);
        m.triangles
            .push([last, ring(nv - 1, j), ring(nv - 1, j + 1)]);
    }
    for i in 1..nv - 1 {
        for j in 0..nu {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            m.triangles.push([a, b, c]);
            m.triangles.push([b, d, c]);
        }
    }
    if m.signed_volume() < 0.0 {
        m.triangles.iter_mut().for_each(|t| t.swap(1, 2));
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn head_is_closed_outward_and_smooth() {
        let p = HeadParams::default();
        let m = p.build();
        m.validate().unwrap();
        assert!(m.signed_volume() > 0.0);
        // Closed: every edge is shared by exactly two triangles.
        let mut edges = std::collections::HashMap::new();
        for t in &m.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        assert!(edges.values().all(|&c| c == 2));
        // Smooth: adjacent vertex normals differ by less than 25 degrees.
        let n = m.vertex_normals();
        for t in &m.triangles {
            for k in 0..3 {
                let a = n[t[k] as usize].angle_between(n[t[(k + 1) % 3] as usize]);
                assert!(
                    a < 25f32.to_radians(),
                    "{a} at {}",
                    m.positions[t[k] as usize]
                );
            }
        }
        let b = m.bounds();
        assert!(b.size().y > 0.3, "the neck reaches down: {:?}", b);
        assert!(m.contains(Vec3::ZERO) && m.contains(Vec3::new(0.0, -0.2, 0.0)));
    }

    #[test]
    fn body_is_closed() {
        let m = BodyParams::default().build();
        assert!(m.signed_volume() > 0.0);
        assert!(m.contains(Vec3::ZERO));
    }
}
