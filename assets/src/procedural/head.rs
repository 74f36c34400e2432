//! The procedural head, a signed-distance sculpt (skull, brow, eye sockets
//! with eyes, nose, lips, jaw, ears, neck and shoulders) meshed with Surface
//! Nets, and the furry body, a star-shaped deformed ellipsoid whose
//! `radial(direction)` gives its surface.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::sdf::{capsule, ellipsoid, mesh_sdf, smax, smin, sphere};
use crate::mesh::TriMesh;
use crate::transform::Transform;

/// Radius of the ellipsoid with semi-axes `s` along unit direction `d`.
fn ellipsoid_radial(d: Vec3, s: Vec3) -> f32 {
    1.0 / (d / s).length()
}

/// A human head in metres: y up, +z forward (the face), origin at the head's
/// centre (between the ears, at eye height); the crown is 0.12 m above it and
/// the chin 0.11 m below. Proportions follow the classical canon: eyes
/// halfway between crown and chin, the nose's base and the brow dividing the
/// face into thirds, ears between brow and nose base.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HeadParams {
    /// Surface Nets cells along the bust's height (0.555 m with shoulders,
    /// 0.395 m without): 192 gives cells of 2.9 mm.
    pub resolution: u32,
    /// Add a neck base, shoulders and upper chest for hair to fall onto.
    pub shoulders: bool,
    /// Linear albedo painted on the scalp under the hair, as games paint a
    /// hair cap so the skin between strands reads as hair (none: bare skin).
    pub scalp: Option<[f32; 3]>,
}

impl Default for HeadParams {
    fn default() -> Self {
        HeadParams {
            resolution: 192,
            shoulders: true,
            scalp: Some([0.07, 0.045, 0.032]),
        }
    }
}

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// Where the eyes are (the right one; the left mirrors x).
pub const EYE_CENTRE: Vec3 = Vec3::new(0.032, 0.004, 0.073);
pub const EYE_RADIUS: f32 = 0.0125;

impl HeadParams {
    /// The sculpt's signed distance (metres, negative inside).
    pub fn sdf(&self, p: Vec3) -> f32 {
        // Mirror for the paired features (ears, eyes, cheeks, jaw).
        let q = v(p.x.abs(), p.y, p.z);
        // Cranium and the face's mass.
        let mut d = ellipsoid(p - v(0.0, 0.024, -0.012), v(0.077, 0.096, 0.1));
        d = smin(
            d,
            ellipsoid(p - v(0.0, -0.035, 0.02), v(0.063, 0.08, 0.075)),
            0.03,
        );
        // Jaw: from the angle below the ear to the chin, and the chin itself.
        d = smin(
            d,
            capsule(q, v(0.056, -0.05, -0.008), v(0.02, -0.1, 0.058), 0.014),
            0.025,
        );
        d = smin(
            d,
            ellipsoid(p - v(0.0, -0.098, 0.06), v(0.025, 0.018, 0.018)),
            0.016,
        );
        // Cheekbones and the brow ridge.
        d = smin(
            d,
            ellipsoid(q - v(0.047, -0.014, 0.058), v(0.02, 0.014, 0.02)),
            0.02,
        );
        d = smin(
            d,
            capsule(q, v(0.0, 0.03, 0.087), v(0.05, 0.027, 0.071), 0.01),
            0.016,
        );
        // Eye sockets, carved, with the eyeballs set in them.
        d = smax(
            d,
            -ellipsoid(q - v(0.032, 0.005, 0.094), v(0.02, 0.013, 0.017)),
            0.008,
        );
        d = d.min(sphere(q - EYE_CENTRE, EYE_RADIUS));
        // Eyelids: shells over the eyeball above and below an almond opening.
        let shell = sphere(q - EYE_CENTRE, EYE_RADIUS + 0.0016);
        let opening = 0.0028 + 0.0015 * (1.0 - ((q.x - EYE_CENTRE.x) / 0.012).powi(2)).max(0.0);
        let upper =
            shell.max(EYE_CENTRE.y + opening - q.y + 0.002 * (q.z - EYE_CENTRE.z) / EYE_RADIUS);
        let lower = shell.max(q.y - (EYE_CENTRE.y - opening - 0.0015));
        d = smin(d, upper.min(lower), 0.002);
        // Nose: bridge, tip and wings.
        let mut nose = capsule(p, v(0.0, 0.014, 0.089), v(0.0, -0.026, 0.108), 0.0075);
        nose = smin(nose, sphere(p - v(0.0, -0.03, 0.104), 0.0115), 0.008);
        nose = smin(nose, sphere(q - v(0.0125, -0.035, 0.096), 0.0085), 0.006);
        d = smin(d, nose, 0.008);
        // Lips, with the mouth's line pressed between them.
        let lips = ellipsoid(p - v(0.0, -0.055, 0.09), v(0.024, 0.0075, 0.012)).min(ellipsoid(
            p - v(0.0, -0.067, 0.087),
            v(0.021, 0.0085, 0.012),
        ));
        d = smin(d, lips, 0.008);
        d = smax(
            d,
            -ellipsoid(p - v(0.0, -0.0607, 0.104), v(0.023, 0.0012, 0.01)),
            0.002,
        );
        // Ears, with a hollow (the concha).
        let ear = ellipsoid(q - v(0.078, -0.002, -0.012), v(0.011, 0.031, 0.019));
        d = smin(d, ear, 0.006);
        d = smax(d, -sphere(q - v(0.091, -0.006, -0.007), 0.0085), 0.004);
        // Neck.
        d = smin(
            d,
            capsule(p, v(0.0, -0.06, -0.025), v(0.0, -0.24, -0.02), 0.054),
            0.03,
        );
        if self.shoulders {
            // Trapezius, deltoids and the chest, cut flat as a bust.
            let mut torso = ellipsoid(p - v(0.0, -0.33, -0.015), v(0.185, 0.1, 0.11));
            torso = smin(
                torso,
                capsule(q, v(0.0, -0.215, -0.03), v(0.15, -0.265, -0.03), 0.045),
                0.05,
            );
            torso = smin(torso, sphere(q - v(0.18, -0.315, -0.02), 0.055), 0.05);
            d = smin(d, torso, 0.05);
            d = d.max(-(p.y + 0.41));
        } else {
            d = d.max(-(p.y + 0.25));
        }
        d
    }

    /// The bust's box, a few cells larger than the sculpt.
    fn bounds(&self) -> (Vec3, Vec3) {
        let low = if self.shoulders { -0.42 } else { -0.26 };
        let half_width = if self.shoulders { 0.25 } else { 0.11 };
        (v(-half_width, low, -0.13), v(half_width, 0.135, 0.13))
    }

    pub fn build(&self) -> TriMesh {
        let (min, max) = self.bounds();
        let cell = (max.y - min.y) / self.resolution.clamp(16, 1024) as f32;
        let pad = Vec3::splat(2.0 * cell);
        let mut mesh = mesh_sdf(|p| self.sdf(p), min - pad, max + pad, cell);
        mesh.colors = mesh.positions.iter().map(|&p| self.albedo(p)).collect();
        mesh
    }
}

/// Linear albedo of light skin (measured skin reflectance is about sRGB
/// (224, 172, 150)), lips, and the eyes' sclera, iris and pupil.
const SKIN: Vec3 = Vec3::new(0.62, 0.4, 0.31);
const LIPS: Vec3 = Vec3::new(0.45, 0.19, 0.17);
const SCLERA: Vec3 = Vec3::new(0.6, 0.55, 0.52);
const IRIS: Vec3 = Vec3::new(0.11, 0.065, 0.035);
const PUPIL: Vec3 = Vec3::new(0.01, 0.01, 0.01);

/// The head's painted albedo at surface point `p`.
fn paint(p: Vec3) -> Vec3 {
    let q = v(p.x.abs(), p.y, p.z);
    let e = q - EYE_CENTRE;
    if e.length() < EYE_RADIUS + 0.001 {
        // Looking straight ahead: the iris is a cap about +z.
        let c = e.normalize_or(Vec3::Z).z;
        return if c > 11f32.to_radians().cos() {
            PUPIL
        } else if c > 27f32.to_radians().cos() {
            IRIS
        } else {
            SCLERA
        };
    }
    let lips = ellipsoid(p - v(0.0, -0.055, 0.09), v(0.024, 0.0075, 0.012)).min(ellipsoid(
        p - v(0.0, -0.067, 0.087),
        v(0.021, 0.0085, 0.012),
    ));
    let t = (1.0 - lips / 0.004).clamp(0.0, 1.0);
    // A little more blood in the cheeks.
    let cheek = (1.0 - (q - v(0.045, -0.03, 0.07)).length() / 0.03).clamp(0.0, 1.0);
    let skin = SKIN + v(0.03, -0.02, -0.015) * cheek;
    skin.lerp(LIPS, t * t * (3.0 - 2.0 * t))
}

impl HeadParams {
    /// The painted albedo at surface point `p`: skin, lips and eyes, and
    /// the scalp's cap faded in over a few millimetres of the hairline.
    pub fn albedo(&self, p: Vec3) -> Vec3 {
        let skin = paint(p);
        let Some(cap) = self.scalp else { return skin };
        let inside = |d: Vec3| super::surface::Region::Scalp.contains(p + d);
        let taps = [
            Vec3::ZERO,
            Vec3::X * 0.004,
            -Vec3::X * 0.004,
            Vec3::Y * 0.004,
            -Vec3::Y * 0.004,
        ];
        let w = taps.iter().filter(|&&d| inside(d)).count() as f32 / taps.len() as f32;
        skin.lerp(Vec3::from(cap), w)
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

    /// Watertight: every edge has an even number of triangles (two, or four
    /// where Surface Nets pinches a thin feature into a non-manifold edge).
    fn closed(m: &TriMesh) -> bool {
        let mut edges = std::collections::HashMap::new();
        for t in &m.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        edges.values().all(|&c| c % 2 == 0)
    }

    #[test]
    fn head_is_closed_outward_and_on_its_distance_field() {
        let p = HeadParams {
            resolution: 128,
            ..Default::default()
        };
        let m = p.build();
        m.validate().unwrap();
        assert!(m.signed_volume() > 0.0);
        assert!(
            closed(&m),
            "every edge is shared by an even number of triangles"
        );
        let cell = 0.555 / 128.0;
        for q in m.positions.iter().step_by(13) {
            assert!(p.sdf(*q).abs() < 0.5 * cell, "{q}: {}", p.sdf(*q));
        }
        let b = m.bounds();
        assert!(b.size().x > 0.4, "shoulders: {b:?}");
        assert!(m.contains(Vec3::ZERO) && m.contains(Vec3::new(0.0, -0.2, -0.02)));
    }

    #[test]
    fn the_face_has_its_features_where_a_face_has_them() {
        let h = HeadParams::default();
        let inside = |x, y, z| h.sdf(v(x, y, z)) < 0.0;
        // The nose's tip stands proud of the cheeks and the lips in front of the chin.
        assert!(inside(0.0, -0.03, 0.112));
        assert!(!inside(0.03, -0.03, 0.104));
        assert!(inside(0.0, -0.055, 0.099) && !inside(0.0, -0.1, 0.085));
        // The eyes sit in sockets: the eyeball's front is behind the brow's front.
        assert!(inside(0.032, 0.004, 0.084) && !inside(0.032, 0.004, 0.09));
        assert!(inside(0.032, 0.03, 0.086) && !inside(0.032, 0.03, 0.095));
        // Ears stick out at the sides; the neck is narrower than the head.
        assert!(inside(0.086, 0.0, -0.012) && !inside(0.086, 0.06, -0.012));
        assert!(!inside(0.07, -0.17, -0.02) && inside(0.0, -0.17, -0.02));
        // Shoulders only when asked.
        assert!(inside(0.17, -0.3, -0.02));
        let bare = HeadParams {
            shoulders: false,
            ..h
        };
        assert!(bare.sdf(v(0.17, -0.3, -0.02)) > 0.0);
    }

    #[test]
    fn body_is_closed() {
        let m = BodyParams::default().build();
        assert!(m.signed_volume() > 0.0);
        assert!(m.contains(Vec3::ZERO));
    }
}
