//! A mesh to plant strands on: root sampling by region, interpolated normals
//! and, for the procedural shapes, a push-out along the distance field so
//! strands lie on the skin and never enter it.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::head::{BodyParams, EYE_CENTRE, EYE_RADIUS, HeadParams};
use super::sdf::gradient;
use crate::mesh::TriMesh;
use crate::smoothstep;

/// The analytic shape behind a procedural mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Shape {
    Head(HeadParams),
    Body(BodyParams),
}

impl Shape {
    /// Signed distance to the surface (the body's is radial: exact in sign,
    /// approximate in size, which is all push-out needs).
    pub fn distance(&self, p: Vec3) -> f32 {
        match self {
            Shape::Head(h) => h.sdf(p),
            Shape::Body(b) => {
                let len = p.length();
                if len < 1e-9 {
                    return -b.radial(Vec3::Y);
                }
                len - b.radial(p / len)
            }
        }
    }
    pub fn build(&self) -> TriMesh {
        match self {
            Shape::Head(h) => h.build(),
            Shape::Body(b) => b.build(),
        }
    }
}

/// Where on a mesh roots are planted, in the procedural head's frame (metres
/// from the head's centre; y up, +z the face). See [`HeadParams`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Region {
    /// Above a hairline: a forehead of a third of the face, temples, sideburns
    /// in front of the ears, above and behind the ears, down to the nape.
    Scalp,
    /// Moustache, cheeks below the cheekbones, jaw, chin and under the chin.
    Beard,
    /// Two arcs along the brow ridge.
    Eyebrows,
    /// The upper eyelids' rims.
    Eyelashes,
    /// The whole surface (fur).
    Everywhere,
}

/// Piecewise-linear interpolation in a table of (x, y) rows sorted by x.
fn lerp_table(table: &[(f32, f32)], x: f32) -> f32 {
    let i = table.partition_point(|r| r.0 < x).clamp(1, table.len() - 1);
    let ((x0, y0), (x1, y1)) = (table[i - 1], table[i]);
    let t = ((x - x0) / (x1 - x0)).clamp(0.0, 1.0);
    y0 + (y1 - y0) * t
}

/// The scalp's hairline height by azimuth (0 = the face's centre line, π =
/// the nape's): forehead, temple corners, sideburns, above the ear, nape.
const HAIRLINE: [(f32, f32); 11] = [
    (0.0, 0.07),
    (0.45, 0.078),
    (0.75, 0.05),
    (1.0, 0.0),
    (1.2, -0.028),
    (1.38, -0.024),
    (1.46, 0.036),
    (2.0, 0.036),
    (2.3, -0.03),
    (2.7, -0.08),
    (std::f32::consts::PI, -0.092),
];

/// The beard's upper edge by azimuth: the moustache, the cheeks, the sideburns.
const BEARDLINE: [(f32, f32); 5] = [
    (0.0, -0.043),
    (0.3, -0.046),
    (0.6, -0.04),
    (1.0, -0.02),
    (1.3, -0.025),
];

/// How far inside the beard's edges its density reaches full (ours): the
/// upper edge over 16 mm on the cheeks and 3 mm over the moustache (only
/// 4 mm tall: nose to lip), the sideburns' back edge over 0.18 rad of
/// azimuth (about 14 mm), the neck over 20 mm. A beard thins out towards
/// its edges rather than stopping at a line.
const BEARD_FADE_TOP: [(f32, f32); 2] = [(0.35, 0.003), (0.8, 0.016)];
const BEARD_FADE_SIDE: f32 = 0.18;
const BEARD_FADE_NECK: f32 = 0.02;
/// The beard's back edge (azimuth) and lowest root on the neck (y).
const BEARD_AZIMUTH: f32 = 1.3;
const BEARD_NECK: f32 = -0.135;

impl Region {
    /// Whether the surface point `p` (head frame, metres) is in the region.
    pub fn contains(self, p: Vec3) -> bool {
        let q = Vec3::new(p.x.abs(), p.y, p.z);
        let azimuth = q.x.atan2(q.z);
        let on_head = p.length() < 0.16;
        match self {
            Region::Scalp => {
                let ear = ((q - Vec3::new(0.08, -0.004, -0.012)) / Vec3::new(0.025, 0.044, 0.032))
                    .length()
                    < 1.0;
                on_head && !ear && p.y > -0.1 && p.y > lerp_table(&HAIRLINE, azimuth)
            }
            Region::Beard => {
                let lips = q.x < 0.029 && p.y < -0.047 && p.y > -0.078 && p.z > 0.07;
                on_head
                    && azimuth < BEARD_AZIMUTH
                    && !lips
                    && p.y > BEARD_NECK
                    && p.y < lerp_table(&BEARDLINE, azimuth)
            }
            Region::Eyebrows => {
                let x = q.x;
                let centre = 0.029
                    + 0.006 * (std::f32::consts::PI * ((x - 0.012) / 0.045).clamp(0.0, 1.0)).sin();
                p.z > 0.06 && (0.012..0.054).contains(&x) && (p.y - centre).abs() < 0.0045
            }
            Region::Eyelashes => {
                let r = (q - EYE_CENTRE).length();
                r > EYE_RADIUS - 0.001
                    && r < EYE_RADIUS + 0.0045
                    && p.y > EYE_CENTRE.y + 0.003
                    && p.z > EYE_CENTRE.z + 0.004
            }
            Region::Everywhere => true,
        }
    }

    /// How densely strands grow at `p` relative to the region's inside, and
    /// how long they grow (ours; [`Surface::region_cdf`], `guides::grow`):
    /// 1 everywhere but near the beard's upper edge, its sideburns' back
    /// edge and its lower edge on the neck, where it falls smoothly to 0 at
    /// the edge. The other regions keep hard edges (the scalp's hairline is
    /// hidden by the hair it grows; eyebrows and lashes are narrow).
    pub fn fade(self, p: Vec3) -> f32 {
        match self {
            Region::Beard => {
                let q = Vec3::new(p.x.abs(), p.y, p.z);
                let azimuth = q.x.atan2(q.z);
                let top = lerp_table(&BEARDLINE, azimuth) - p.y;
                smoothstep(0.0, lerp_table(&BEARD_FADE_TOP, azimuth), top)
                    * smoothstep(0.0, BEARD_FADE_SIDE, BEARD_AZIMUTH - azimuth)
                    * smoothstep(0.0, BEARD_FADE_NECK, p.y - BEARD_NECK)
            }
            _ => 1.0,
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

    /// Moves `p` out of the analytic shape to at least `margin` above its
    /// surface, along the distance field's gradient.
    pub fn push_out(&self, p: Vec3, margin: f32) -> Vec3 {
        let Some(shape) = self.shape else { return p };
        let mut q = p - self.center;
        // Newton steps: the field is a distance bound, not exact, near blends,
        // so one step can fall short.
        for _ in 0..6 {
            let d = shape.distance(q);
            if d >= margin {
                break;
            }
            q += gradient(|x| shape.distance(x), q, 2e-4) * (margin - d);
        }
        self.center + q
    }

    /// The distance field's outward normal at `p` (the mesh's nearest face
    /// normal is not known here; without an analytic shape, +y).
    pub fn field_normal(&self, p: Vec3) -> Vec3 {
        match self.shape {
            Some(shape) => gradient(|x| shape.distance(x), p - self.center, 2e-4),
            None => Vec3::Y,
        }
    }

    /// Cumulative distribution over the triangles in `region`, each weighted
    /// by its area and the region's [`Region::fade`] at its centre.
    pub fn region_cdf(&self, region: Region) -> Vec<f32> {
        let mut acc = 0.0;
        (0..self.mesh.triangle_count())
            .map(|t| {
                let [a, b, c] = self.mesh.corners(t);
                let centre = (a + b + c) / 3.0 - self.center;
                if region.contains(centre) {
                    acc += self.mesh.face_area(t) * region.fade(centre);
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
