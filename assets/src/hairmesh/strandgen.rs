//! Strand generation from a hair mesh. Lipp §2: "each strand is assembled as a spline with
//! N control points uniformly spaced along the length of the strand w in [0, 1] ... its base
//! position is computed by using spline interpolation from the bilinear interpolation of
//! vertices and tangents in the bundle layers. Then, the final strand is obtained by
//! applying the styling function as a function of each control point's uvw coordinates."

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::{HairMesh, Layer};
use crate::groom::Groom;

/// The styling function's parameters (curl, twist and noise offsets).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StrandStyle {
    /// Helix radius in metres.
    pub curl_radius: f32,
    /// Helix turns over the strand's length.
    pub curl_turns: f32,
    /// Rotation of the strand's (u, v) about the bundle centre from root to tip, in turns.
    pub twist: f32,
    /// Amplitude of the per-strand noise offset in metres.
    pub noise: f32,
}

/// Bilinear interpolation of the four corner values at (u, v).
fn bilinear(c: &[Vec3; 4], uv: Vec2) -> Vec3 {
    let bottom = c[0].lerp(c[1], uv.x);
    let top = c[3].lerp(c[2], uv.x);
    bottom.lerp(top, uv.y)
}

/// A hash of (u, v) to [0, 1)³, the strand's identity for styling.
fn hash3(uv: Vec2) -> Vec3 {
    let h = |s: f32| {
        let x = (uv.x * 127.1 + uv.y * 311.7 + s).sin() * 43758.547;
        x - x.floor()
    };
    Vec3::new(h(0.0), h(1.3), h(2.7))
}

/// The base position and direction of strand (u, v) at layer `l`.
fn layer_point(l: &Layer, uv: Vec2) -> (Vec3, Vec3) {
    (bilinear(&l.positions, uv), bilinear(&l.tangents, uv))
}

/// The styled point of strand `uv` in bundle `b` at `w` in [0, 1]. This is the
/// strand-generation function the Lipp pipeline evaluates per control point.
pub fn strand_point(mesh: &HairMesh, b: usize, uv: Vec2, w: f32) -> Vec3 {
    let Some(bundle) = mesh.bundles.get(b) else {
        return Vec3::ZERO;
    };
    let layers = mesh.bundle_layers(b);
    let style = bundle.style;
    let w = w.clamp(0.0, 1.0);
    // Twist: rotate the strand's position in the bundle about the centre.
    let angle = style.twist * std::f32::consts::TAU * w;
    let c = uv - Vec2::splat(0.5);
    let uv_t = Vec2::new(
        c.x * angle.cos() - c.y * angle.sin(),
        c.x * angle.sin() + c.y * angle.cos(),
    ) + Vec2::splat(0.5);

    // Base spline: cubic Hermite between the two enclosing layers.
    let f = w * (layers.len() - 1) as f32;
    let i = (f.floor() as usize).min(layers.len() - 2);
    let t = f - i as f32;
    let (p0, d0) = layer_point(&layers[i], uv_t);
    let (p1, d1) = layer_point(&layers[i + 1], uv_t);
    let len = p0.distance(p1);
    let (t2, t3) = (t * t, t * t * t);
    let base = p0 * (2.0 * t3 - 3.0 * t2 + 1.0)
        + d0 * len * (t3 - 2.0 * t2 + t)
        + p1 * (-2.0 * t3 + 3.0 * t2)
        + d1 * len * (t3 - t2);

    // Styling offsets in the frame of the base direction, faded in from the root.
    let dir = d0.lerp(d1, t).normalize_or_zero();
    let b1 = dir.any_orthonormal_vector();
    let b2 = dir.cross(b1);
    let id = hash3(uv);
    let ramp = (w * 8.0).min(1.0);
    let mut off = Vec3::ZERO;
    if style.curl_radius > 0.0 {
        let a = std::f32::consts::TAU * (style.curl_turns * w + id.x);
        off += (b1 * a.cos() + b2 * a.sin()) * style.curl_radius;
    }
    if style.noise > 0.0 {
        let n = (id * 2.0 - Vec3::ONE) * style.noise;
        off += n * (std::f32::consts::PI * w * (1.0 + 2.0 * id.y)).sin();
    }
    base + off * ramp
}

/// Writes the `n` control points of strand `uv` of bundle `b` into `out`.
pub fn generate_strand(mesh: &HairMesh, b: usize, uv: Vec2, out: &mut [Vec3]) {
    let n = out.len();
    for (k, p) in out.iter_mut().enumerate() {
        *p = strand_point(mesh, b, uv, k as f32 / (n - 1).max(1) as f32);
    }
}

/// The (u, v) of strand `k` of a bundle: the R2 low-discrepancy sequence, so strand
/// prefixes cover the bundle evenly (useful for LOD by strand count, Lipp §3.2.1).
pub fn strand_uv(k: u32) -> Vec2 {
    const A1: f64 = 0.754_877_666_246_692_7;
    const A2: f64 = 0.569_840_290_998_053_3;
    let k = k as f64;
    Vec2::new((0.5 + A1 * k).fract() as f32, (0.5 + A2 * k).fract() as f32)
}

impl HairMesh {
    /// Expands every bundle into explicit strands of `points` control points.
    pub fn to_groom(&self, points: usize, thickness: f32) -> Groom {
        let n = points.max(2);
        let mut first = Vec::with_capacity(self.bundles.len() + 1);
        let mut acc = 0usize;
        for b in &self.bundles {
            first.push(acc);
            acc += b.strands as usize;
        }
        let total = acc;
        let mut positions = vec![Vec3::ZERO; total * n];
        let mut uvs = vec![Vec2::ZERO; total];
        positions
            .par_chunks_mut(n)
            .zip(uvs.par_iter_mut())
            .enumerate()
            .for_each(|(s, (out, uv_out))| {
                let b = first.partition_point(|&f| f <= s) - 1;
                let uv = strand_uv((s - first[b]) as u32);
                *uv_out = uv;
                generate_strand(self, b, uv, out);
            });
        Groom {
            positions,
            thickness: vec![thickness; total * n],
            strand_uvs: Some(uvs),
            strand_offsets: (0..=total).map(|s| (s * n) as u32).collect(),
            transform: self.transform,
            ..Default::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_bundle(style: StrandStyle) -> HairMesh {
        let mut m = HairMesh::default();
        let corners: Vec<[Vec3; 4]> = (0..4)
            .map(|i| {
                let y = -(i as f32) * 0.1;
                [
                    Vec3::new(0.0, y, 0.0),
                    Vec3::new(0.02, y, 0.0),
                    Vec3::new(0.02, y, 0.02),
                    Vec3::new(0.0, y, 0.02),
                ]
            })
            .collect();
        m.push_bundle(&corners, 50, style);
        m
    }

    #[test]
    fn corners_and_layers_are_interpolated_exactly() {
        let m = one_bundle(StrandStyle::default());
        m.validate().unwrap();
        assert_eq!(strand_point(&m, 0, Vec2::ZERO, 0.0), Vec3::ZERO);
        let tip = strand_point(&m, 0, Vec2::ONE, 1.0);
        assert!(tip.distance(Vec3::new(0.02, -0.3, 0.02)) < 1e-6);
        // Between layers of a straight bundle the spline stays on the straight line.
        let mid = strand_point(&m, 0, Vec2::splat(0.5), 0.5);
        assert!(mid.distance(Vec3::new(0.01, -0.15, 0.01)) < 1e-5, "{mid}");
        assert_eq!(m.layers[1].uvw[2], Vec3::new(1.0, 1.0, 1.0 / 3.0));
    }

    #[test]
    fn styling_offsets_curl_twist_and_noise() {
        let plain = one_bundle(StrandStyle::default());
        let curly = one_bundle(StrandStyle {
            curl_radius: 0.005,
            curl_turns: 6.0,
            ..Default::default()
        });
        let uv = Vec2::new(0.3, 0.6);
        // Roots stay put; further along the curl offset is its radius.
        assert_eq!(
            strand_point(&plain, 0, uv, 0.0),
            strand_point(&curly, 0, uv, 0.0)
        );
        let d = strand_point(&plain, 0, uv, 0.5).distance(strand_point(&curly, 0, uv, 0.5));
        assert!((d - 0.005).abs() < 1e-4, "{d}");
        let twisted = one_bundle(StrandStyle {
            twist: 0.5,
            ..Default::default()
        });
        // Half a turn of twist: the strand at (0, 0) ends at the (1, 1) corner.
        let tip = strand_point(&twisted, 0, Vec2::ZERO, 1.0);
        assert!(tip.distance(Vec3::new(0.02, -0.3, 0.02)) < 1e-5, "{tip}");
        let noisy = one_bundle(StrandStyle {
            noise: 0.01,
            ..Default::default()
        });
        let g = noisy.to_groom(8, 1e-4);
        assert_eq!(g.strand_count(), 50);
        assert_ne!(g, plain.to_groom(8, 1e-4));
    }

    #[test]
    fn strand_uvs_cover_the_bundle() {
        let uvs: Vec<Vec2> = (0..64).map(strand_uv).collect();
        for q in 0..4 {
            let (u0, v0) = ((q % 2) as f32 * 0.5, (q / 2) as f32 * 0.5);
            let n = uvs
                .iter()
                .filter(|p| p.x >= u0 && p.x < u0 + 0.5 && p.y >= v0 && p.y < v0 + 0.5)
                .count();
            assert!((12..=20).contains(&n), "quadrant {q}: {n}");
        }
    }
}
