//! Parametric groom generators: straight, wavy, curly (helical), long with gravity,
//! short, ponytail, facial hair (beard, eyebrows) and fur. Strands are grown in parallel,
//! each from its own seeded generator, so the output does not depend on thread count.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use super::surface::Region;
use super::surface::{Surface, sample_triangle};
use crate::groom::Groom;
use crate::skinning::RootSkinningInfo;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Style {
    Straight,
    Wavy,
    Curly,
    Long,
    Short,
    Ponytail,
    Beard,
    Eyebrows,
    Fur,
}

/// Generator parameters; fields left `None` take the style's defaults.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GroomParams {
    pub style: Style,
    pub strands: u32,
    pub points: u32,
    pub seed: u64,
    pub region: Option<Region>,
    /// Strand length in metres.
    pub length: Option<f32>,
    /// Relative random variation of the length (0.2 = +-20%).
    pub length_variation: Option<f32>,
    /// Diameter at root and tip, metres.
    pub root_thickness: Option<f32>,
    pub tip_thickness: Option<f32>,
    /// 0 = strands grow along the normal, 1 = they fall straight down.
    pub gravity: Option<f32>,
    /// Wave amplitude (m) and waves per metre.
    pub wave_amplitude: Option<f32>,
    pub wave_frequency: Option<f32>,
    /// Helix radius (m) and turns per metre.
    pub curl_radius: Option<f32>,
    pub curl_frequency: Option<f32>,
    /// Random low-frequency offset amplitude (m).
    pub noise: Option<f32>,
}

impl Default for GroomParams {
    fn default() -> Self {
        GroomParams {
            style: Style::Straight,
            strands: 10_000,
            points: 32,
            seed: 1,
            region: None,
            length: None,
            length_variation: None,
            root_thickness: None,
            tip_thickness: None,
            gravity: None,
            wave_amplitude: None,
            wave_frequency: None,
            curl_radius: None,
            curl_frequency: None,
            noise: None,
        }
    }
}

/// Fully resolved parameters.
#[derive(Debug, Clone, Copy)]
struct Resolved {
    region: Region,
    length: f32,
    length_variation: f32,
    root_thickness: f32,
    tip_thickness: f32,
    gravity: f32,
    wave_amplitude: f32,
    wave_frequency: f32,
    curl_radius: f32,
    curl_frequency: f32,
    noise: f32,
}

impl GroomParams {
    fn resolve(&self) -> Resolved {
        use Style::*;
        // (region, length, gravity, wave amp, wave freq, curl r, curl freq, root thickness)
        let (region, length, gravity, wa, wf, cr, cf, th) = match self.style {
            Straight => (Region::Scalp, 0.25, 0.8, 0.0, 0.0, 0.0, 0.0, 70e-6),
            Wavy => (Region::Scalp, 0.3, 0.8, 0.012, 9.0, 0.0, 0.0, 70e-6),
            Curly => (Region::Scalp, 0.2, 0.5, 0.0, 0.0, 0.008, 25.0, 80e-6),
            Long => (Region::Scalp, 0.45, 1.0, 0.003, 4.0, 0.0, 0.0, 70e-6),
            Short => (Region::Scalp, 0.04, 0.35, 0.0, 0.0, 0.0, 0.0, 80e-6),
            Ponytail => (Region::Scalp, 0.4, 1.0, 0.004, 5.0, 0.0, 0.0, 70e-6),
            Beard => (Region::Beard, 0.025, 0.6, 0.0, 0.0, 0.002, 60.0, 100e-6),
            Eyebrows => (Region::Eyebrows, 0.011, 0.1, 0.0, 0.0, 0.0, 0.0, 90e-6),
            Fur => (Region::Everywhere, 0.02, 0.4, 0.0, 0.0, 0.0, 0.0, 60e-6),
        };
        let root_thickness = self.root_thickness.unwrap_or(th);
        Resolved {
            region: self.region.unwrap_or(region),
            length: self.length.unwrap_or(length),
            length_variation: self.length_variation.unwrap_or(0.15),
            root_thickness,
            tip_thickness: self.tip_thickness.unwrap_or(root_thickness * 0.3),
            gravity: self.gravity.unwrap_or(gravity),
            wave_amplitude: self.wave_amplitude.unwrap_or(wa),
            wave_frequency: self.wave_frequency.unwrap_or(wf),
            curl_radius: self.curl_radius.unwrap_or(cr),
            curl_frequency: self.curl_frequency.unwrap_or(cf),
            noise: self.noise.unwrap_or(0.002),
        }
    }

    /// Checks that the parameters make sense; returns what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        if self.strands == 0 {
            return Err("strands must be at least 1".into());
        }
        if self.strands > 20_000_000 {
            return Err(format!("strands = {} is absurd", self.strands));
        }
        if !(2..=1024).contains(&self.points) {
            return Err(format!("points = {} must be in 2..=1024", self.points));
        }
        let r = self.resolve();
        if !(r.length > 0.0 && r.length.is_finite()) {
            return Err("length must be positive".into());
        }
        Ok(())
    }

    /// Grows the groom on `surface` in the surface's local space.
    pub fn generate(&self, surface: &Surface) -> GeneratedGroom {
        let r = self.resolve();
        let n = self.points.max(2) as usize;
        let cdf = surface.region_cdf(r.region);
        let count = if cdf.last().copied().unwrap_or(0.0) > 0.0 {
            self.strands as usize
        } else {
            0
        };
        let mut positions = vec![Vec3::ZERO; count * n];
        let mut skinning = vec![RootSkinningInfo::default(); count];
        let seed = self.seed;
        let style = self.style;
        positions
            .par_chunks_mut(n)
            .zip(skinning.par_iter_mut())
            .enumerate()
            .for_each(|(s, (out, skin))| {
                let mut rng =
                    Pcg64Mcg::seed_from_u64(seed ^ (s as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
                let Some((tri, bary)) =
                    sample_triangle(&cdf, rng.random(), rng.random(), rng.random())
                else {
                    return;
                };
                *skin = RootSkinningInfo::new(&surface.mesh, tri, bary);
                let root = surface.point(tri, bary);
                let normal = surface.normal(tri, bary);
                grow(surface, style, &r, root, normal, &mut rng, out);
            });
        let thickness = (0..count * n)
            .map(|i| {
                let t = (i % n) as f32 / (n - 1) as f32;
                r.root_thickness + (r.tip_thickness - r.root_thickness) * t
            })
            .collect();
        GeneratedGroom {
            groom: Groom {
                positions,
                thickness,
                strand_offsets: (0..=count).map(|s| (s * n) as u32).collect(),
                ..Default::default()
            },
            skinning,
        }
    }
}

/// A generated groom and the skinning record of every root on its parent mesh.
pub struct GeneratedGroom {
    pub groom: Groom,
    pub skinning: Vec<crate::skinning::RootSkinningInfo>,
}

/// Two unit vectors perpendicular to `t` and each other.
pub fn perpendiculars(t: Vec3) -> (Vec3, Vec3) {
    let a = t.any_orthonormal_vector();
    (a, t.cross(a))
}

/// Grows one strand into `out` (first point = root, exactly on the surface).
fn grow(
    surface: &Surface,
    style: Style,
    r: &Resolved,
    root: Vec3,
    normal: Vec3,
    rng: &mut Pcg64Mcg,
    out: &mut [Vec3],
) {
    let n = out.len();
    let length = r.length * (1.0 + r.length_variation * (2.0 * rng.random::<f32>() - 1.0));
    let step = length / (n - 1) as f32;
    let down = -Vec3::Y;
    // Comb direction: tangential, towards the back and down, or towards the temples for brows.
    let comb_world = match style {
        Style::Eyebrows => Vec3::new((root - surface.center).x.signum(), 0.25, 0.0),
        Style::Beard => Vec3::new(0.0, -1.0, 0.2),
        _ => Vec3::new(0.0, -0.6, -1.0),
    };
    let comb = comb_world.reject_from(normal).normalize_or_zero();
    let lift = match style {
        Style::Eyebrows => 0.25,
        Style::Fur | Style::Short => 0.7,
        Style::Beard => 0.5,
        _ => 0.9,
    };
    let tie = surface.center + Vec3::new(0.0, 0.04, -0.125);
    let tie_offset = {
        let (a, b) = perpendiculars(Vec3::new(0.0, -0.9, -0.4).normalize());
        let (ang, rad) = (
            rng.random::<f32>() * std::f32::consts::TAU,
            rng.random::<f32>().sqrt() * 0.018,
        );
        (a * ang.cos() + b * ang.sin()) * rad
    };
    let phase = rng.random::<f32>() * std::f32::consts::TAU;
    let noise_dir = Vec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - Vec3::ONE;
    let noise_freq = 3.0 + 4.0 * rng.random::<f32>();
    let margin = 0.0015;

    // Base path: direction blends from the lifted normal to gravity along the strand.
    let mut base = Vec::with_capacity(n);
    base.push(root);
    let mut p = root;
    let to_tie = (tie - root).length();
    for i in 1..n {
        let t = i as f32 / (n - 1) as f32;
        let s = t * length;
        let dir = if style == Style::Ponytail && s < to_tie {
            (tie + tie_offset - p).normalize_or_zero() * 0.7 + normal * 0.3 * (1.0 - s / to_tie)
        } else if style == Style::Ponytail {
            Vec3::new(0.0, -0.9, -0.35)
        } else {
            let g = (r.gravity * (0.35 + t)).min(1.0);
            let start = (normal * lift + comb * (1.0 - lift)).normalize_or_zero();
            start.lerp(down, g)
        };
        p += dir.normalize_or_zero() * step;
        p = surface.push_out(p, margin * (1.0 + 2.0 * t));
        base.push(p);
    }

    // Styling offsets perpendicular to the path, ramped in from the root.
    out[0] = root;
    for i in 1..n {
        let t = i as f32 / (n - 1) as f32;
        let s = t * length;
        let tangent = (base[i] - base[i - 1]).normalize_or_zero();
        let (b1, b2) = perpendiculars(tangent);
        let ramp = (s / (0.1 * length).max(1e-4)).min(1.0);
        let mut off = Vec3::ZERO;
        if r.wave_amplitude > 0.0 {
            off += b1
                * (r.wave_amplitude * (std::f32::consts::TAU * r.wave_frequency * s + phase).sin());
        }
        if r.curl_radius > 0.0 {
            let a = std::f32::consts::TAU * r.curl_frequency * s + phase;
            off += (b1 * a.cos() + b2 * a.sin()) * r.curl_radius;
        }
        off += noise_dir * (r.noise * (noise_freq * s + phase).sin() * t);
        out[i] = surface.push_out(base[i] + off * ramp, margin);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Bvh;
    use crate::procedural::head::{BodyParams, HeadParams};
    use crate::procedural::surface::Shape;

    fn outside_mesh_everywhere(surface: &Surface, g: &Groom) {
        let bvh = Bvh::new(&surface.mesh);
        for s in (0..g.strand_count()).step_by(7) {
            let pts = g.strand(s);
            // The root lies on the mesh surface...
            let hit = bvh.closest(pts[0]).unwrap();
            assert!(
                hit.distance_squared.sqrt() < 1e-5,
                "root {s} is off the surface"
            );
            // ...and no later point is inside the mesh.
            for (i, &p) in pts.iter().enumerate().skip(1) {
                let h = bvh.closest(p).unwrap();
                let n = surface.mesh.face_normal(h.triangle as usize);
                let outside = (p - h.point).dot(n) >= -1e-6;
                assert!(outside, "strand {s} point {i} is inside the mesh");
            }
        }
    }

    #[test]
    fn every_style_starts_on_the_surface_and_stays_outside() {
        let head = Surface::procedural(Shape::Head(HeadParams::default()));
        for style in [
            Style::Straight,
            Style::Wavy,
            Style::Curly,
            Style::Long,
            Style::Short,
            Style::Ponytail,
            Style::Beard,
            Style::Eyebrows,
        ] {
            let p = GroomParams {
                style,
                strands: 700,
                points: 16,
                ..Default::default()
            };
            let g = p.generate(&head);
            assert_eq!(g.groom.strand_count(), 700, "{style:?}");
            g.groom.validate().unwrap();
            outside_mesh_everywhere(&head, &g.groom);
        }
        let body = Surface::procedural(Shape::Body(BodyParams::default()));
        let g = GroomParams {
            style: Style::Fur,
            strands: 2000,
            points: 6,
            ..Default::default()
        }
        .generate(&body);
        outside_mesh_everywhere(&body, &g.groom);
    }

    #[test]
    fn generation_is_deterministic_and_seeded() {
        let head = Surface::procedural(Shape::Head(HeadParams::default()));
        let p = GroomParams {
            strands: 300,
            ..Default::default()
        };
        assert_eq!(p.generate(&head).groom, p.generate(&head).groom);
        let q = GroomParams { seed: 2, ..p };
        assert_ne!(p.generate(&head).groom, q.generate(&head).groom);
    }

    #[test]
    fn regions_are_where_they_should_be() {
        let head = Surface::procedural(Shape::Head(HeadParams::default()));
        let beard = GroomParams {
            style: Style::Beard,
            strands: 500,
            points: 4,
            ..Default::default()
        }
        .generate(&head);
        assert!(beard.groom.roots().iter().all(|r| r.z > 0.0 && r.y < 0.0));
        let brows = GroomParams {
            style: Style::Eyebrows,
            strands: 500,
            points: 4,
            ..Default::default()
        }
        .generate(&head);
        assert!(brows.groom.roots().iter().all(|r| r.z > 0.05 && r.y > 0.0));
        let scalp = GroomParams {
            strands: 500,
            points: 4,
            ..Default::default()
        }
        .generate(&head);
        // Long strands fall below the roots.
        let b = scalp.groom.bounds();
        assert!(b.min.y < -0.05, "{b:?}");
    }

    #[test]
    fn lipp_sized_groom_130k_by_32() {
        let head = Surface::procedural(Shape::Head(HeadParams::default()));
        let t = std::time::Instant::now();
        let g = GroomParams {
            style: Style::Long,
            strands: 130_000,
            points: 32,
            ..Default::default()
        }
        .generate(&head);
        eprintln!("130k x 32 groom generated in {:?}", t.elapsed());
        assert_eq!(g.groom.strand_count(), 130_000);
        assert_eq!(g.groom.point_count(), 130_000 * 32);
        g.groom.validate().unwrap();
    }
}
