//! The groom generator: guides grown on the head (`guides`), children
//! interpolated around them (`children`), with a style's defaults (`styles`)
//! and any of them overridden from the scene. Strands are grown in parallel,
//! each from its own seeded generator, so the output does not depend on
//! thread count.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::children::{self, Guide, RootGrid};
use super::guides;
use super::styles::Resolved;
pub use super::styles::Style;
pub use super::surface::Region;
use super::surface::{Surface, sample_triangle};
use crate::groom::Groom;
use crate::skinning::RootSkinningInfo;

/// Generator parameters; fields left `None` take the style's defaults
/// (`styles.rs`). Lengths are metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GroomParams {
    pub style: Style,
    pub strands: u32,
    pub points: u32,
    pub seed: u64,
    pub region: Option<Region>,
    pub length: Option<f32>,
    /// Up to this fraction shorter, at random (0.2 = 20%).
    pub length_variation: Option<f32>,
    /// Diameter at root and tip.
    pub root_thickness: Option<f32>,
    pub tip_thickness: Option<f32>,
    /// Curvature towards the ground, radians per metre (0 = stiff).
    pub gravity: Option<f32>,
    /// Wave amplitude and waves per metre.
    pub wave_amplitude: Option<f32>,
    pub wave_frequency: Option<f32>,
    /// Helix radius and turns per metre.
    pub curl_radius: Option<f32>,
    pub curl_frequency: Option<f32>,
    /// Random displacement at the tips.
    pub frizz: Option<f32>,
    /// Fraction of strands that leave their clump.
    pub stray_fraction: Option<f32>,
    /// Pull of children to their guide at the tip, 0..=1, and the profile's exponent.
    pub clump: Option<f32>,
    pub clump_profile: Option<f32>,
    /// Strands per guide (1 = every strand its own guide).
    pub strands_per_guide: Option<u32>,
    /// The parting's x (head frame) for the parted styles.
    pub parting: Option<f32>,
    /// Height (head frame) below which strands are cut.
    pub cut_height: Option<f32>,
    /// How high the hair stands off the skull.
    pub volume: Option<f32>,
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
            frizz: None,
            stray_fraction: None,
            clump: None,
            clump_profile: None,
            strands_per_guide: None,
            parting: None,
            cut_height: None,
            volume: None,
        }
    }
}

impl GroomParams {
    fn resolve(&self) -> Resolved {
        let d = self.style.defaults();
        let or = |v: Option<f32>, default: f32| v.unwrap_or(default);
        let root_thickness = or(self.root_thickness, d.root_thickness);
        Resolved {
            region: self.region.unwrap_or(d.region),
            length: or(self.length, d.length),
            length_variation: or(self.length_variation, d.length_variation),
            root_thickness,
            tip_thickness: self
                .tip_thickness
                .unwrap_or(d.tip_thickness * root_thickness / d.root_thickness),
            gravity: or(self.gravity, d.gravity),
            wave_amplitude: or(self.wave_amplitude, d.wave_amplitude),
            wave_frequency: or(self.wave_frequency, d.wave_frequency),
            curl_radius: or(self.curl_radius, d.curl_radius),
            curl_frequency: or(self.curl_frequency, d.curl_frequency),
            frizz: or(self.frizz, d.frizz),
            stray_fraction: or(self.stray_fraction, d.stray_fraction),
            clump: or(self.clump, d.clump),
            clump_profile: or(self.clump_profile, d.clump_profile),
            strands_per_guide: self.strands_per_guide.unwrap_or(d.strands_per_guide),
            comb: match (d.comb, self.parting) {
                (super::styles::Comb::Parted(_), Some(x)) => super::styles::Comb::Parted(x),
                (c, _) => c,
            },
            cut_height: self.cut_height.or(d.cut_height),
            volume: or(self.volume, d.volume),
            ..d
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
        let total = u64::from(self.strands) * u64::from(self.points);
        if total > crate::loaders::MAX_POINTS {
            return Err(format!(
                "strands × points = {total} is more than the {} points any groom may have",
                crate::loaders::MAX_POINTS
            ));
        }
        let r = self.resolve();
        let checks = [
            ("length", r.length > 0.0 && r.length < 10.0),
            (
                "length_variation",
                (0.0..=0.95).contains(&r.length_variation),
            ),
            (
                "root_thickness",
                r.root_thickness > 0.0 && r.root_thickness < 0.01,
            ),
            (
                "tip_thickness",
                r.tip_thickness > 0.0 && r.tip_thickness < 0.01,
            ),
            ("gravity", (0.0..=1000.0).contains(&r.gravity)),
            ("wave_amplitude", (0.0..=0.2).contains(&r.wave_amplitude)),
            ("wave_frequency", (0.0..=1000.0).contains(&r.wave_frequency)),
            ("curl_radius", (0.0..=0.2).contains(&r.curl_radius)),
            ("curl_frequency", (0.0..=1000.0).contains(&r.curl_frequency)),
            ("frizz", (0.0..=0.1).contains(&r.frizz)),
            ("stray_fraction", (0.0..=1.0).contains(&r.stray_fraction)),
            ("clump", (0.0..=1.0).contains(&r.clump)),
            (
                "clump_profile",
                r.clump_profile > 0.0 && r.clump_profile <= 20.0,
            ),
            (
                "strands_per_guide",
                (1..=100_000).contains(&r.strands_per_guide),
            ),
            ("volume", (0.0..=0.2).contains(&r.volume)),
            ("parting", self.parting.is_none_or(f32::is_finite)),
            ("cut_height", r.cut_height.is_none_or(f32::is_finite)),
        ];
        match checks.iter().find(|(_, ok)| !ok) {
            // NaN fails every range check too.
            Some((name, _)) => Err(format!("{name} is out of range")),
            None => Ok(()),
        }
    }

    /// Grows `count` guides with `points` points each (the hair mesh's bundles).
    pub fn guides(&self, surface: &Surface, count: u32, points: u32) -> Groom {
        let r = self.resolve();
        let cdf = surface.region_cdf(r.region);
        let n = points.max(2) as usize;
        let grown: Vec<Vec<Vec3>> = (0..count as u64)
            .into_par_iter()
            .filter_map(|i| {
                let mut rng = strand_rng(self.seed ^ 0x6a09_e667, i);
                let (root, normal, _) = plant(surface, &cdf, &mut rng)?;
                Some(guides::grow(surface, &r, root, normal, &mut rng).resampled(n))
            })
            .collect();
        let thickness = (0..grown.len() * n)
            .map(|i| children::thickness(&r, (i % n) as f32 / (n - 1) as f32))
            .collect();
        Groom {
            strand_offsets: (0..=grown.len()).map(|s| (s * n) as u32).collect(),
            positions: grown.concat(),
            thickness,
            ..Default::default()
        }
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
        // Children's roots, planted first: with one strand per guide, each
        // root grows its own guide.
        let roots: Vec<_> = (0..count as u64)
            .into_par_iter()
            .map(|s| {
                let mut rng = strand_rng(self.seed, s);
                plant(surface, &cdf, &mut rng).map(|p| (p, rng))
            })
            .collect();
        let per_guide = r.strands_per_guide.max(1) as usize;
        let guide_count = if per_guide == 1 {
            count
        } else {
            (count / per_guide).max(16)
        };
        let guides: Vec<Guide> = (0..guide_count as u64)
            .into_par_iter()
            .map(|g| {
                let mut rng = strand_rng(self.seed ^ 0x6a09_e667, g);
                let planted = if per_guide == 1 {
                    roots[g as usize].as_ref().map(|(p, _)| *p)
                } else {
                    plant(surface, &cdf, &mut rng)
                };
                let (root, normal, _) = planted.unwrap_or((surface.center, Vec3::Y, (0, Vec3::X)));
                Guide {
                    path: guides::grow(surface, &r, root, normal, &mut rng),
                    phase: rng.random::<f32>() * std::f32::consts::TAU,
                }
            })
            .collect();
        // Guide spacing from the region's area (the CDF's total).
        let area = cdf.last().copied().unwrap_or(0.0);
        let spacing = (area / guide_count.max(1) as f32).sqrt().max(1e-4);
        let grid = RootGrid::new(
            guides.iter().map(|g| g.path.points[0]).collect(),
            spacing * 2.0,
        );
        let mut positions = vec![Vec3::ZERO; count * n];
        let mut skinning = vec![RootSkinningInfo::default(); count];
        positions
            .par_chunks_mut(n)
            .zip(skinning.par_iter_mut())
            .zip(roots.into_par_iter())
            .enumerate()
            .for_each(|(s, ((out, skin), planted))| {
                let Some(((root, _, (tri, bary)), mut rng)) = planted else {
                    return;
                };
                *skin = RootSkinningInfo::new(&surface.mesh, tri, bary);
                let g = if per_guide == 1 {
                    s as u32
                } else {
                    grid.nearest(root).unwrap_or(0)
                };
                children::grow(surface, &r, &guides[g as usize], root, &mut rng, out);
            });
        let thickness = (0..count * n)
            .map(|i| children::thickness(&r, (i % n) as f32 / (n - 1) as f32))
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

/// Strand `i`'s own generator.
fn strand_rng(seed: u64, i: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// A root planted in the region: position, smooth normal, (triangle, barycentrics).
type Planted = (Vec3, Vec3, (u32, Vec3));

fn plant(surface: &Surface, cdf: &[f32], rng: &mut Pcg64Mcg) -> Option<Planted> {
    let (tri, bary) = sample_triangle(cdf, rng.random(), rng.random(), rng.random())?;
    Some((
        surface.point(tri, bary),
        surface.normal(tri, bary),
        (tri, bary),
    ))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Bvh;
    use crate::procedural::head::{BodyParams, HeadParams};
    use crate::procedural::surface::{Region, Shape};

    fn head() -> Surface {
        Surface::procedural(Shape::Head(HeadParams {
            resolution: 128,
            ..Default::default()
        }))
    }

    /// Roots on the mesh; every later point outside the shape (by its
    /// distance field, to half the skin margin).
    fn planted_and_outside(surface: &Surface, g: &Groom) {
        let bvh = Bvh::new(&surface.mesh);
        let shape = surface.shape.unwrap();
        for s in (0..g.strand_count()).step_by(7) {
            let pts = g.strand(s);
            let hit = bvh.closest(pts[0]).unwrap();
            assert!(
                hit.distance_squared.sqrt() < 1e-5,
                "root {s} is off the surface"
            );
            for (i, &p) in pts.iter().enumerate().skip(1) {
                let d = shape.distance(p - surface.center);
                assert!(
                    d > 0.5 * guides::SKIN_MARGIN,
                    "strand {s} point {i} at {p} is {d} from the skin"
                );
            }
        }
    }

    const HEAD_STYLES: [Style; 11] = [
        Style::Straight,
        Style::Wavy,
        Style::Curly,
        Style::Long,
        Style::Bob,
        Style::Short,
        Style::Ponytail,
        Style::Bun,
        Style::Beard,
        Style::Eyebrows,
        Style::Eyelashes,
    ];

    #[test]
    fn every_style_starts_on_the_skin_and_stays_outside() {
        let head = head();
        for style in HEAD_STYLES {
            let p = GroomParams {
                style,
                strands: 700,
                points: 16,
                ..Default::default()
            };
            p.validate().unwrap();
            let g = p.generate(&head);
            assert_eq!(g.groom.strand_count(), 700, "{style:?}");
            g.groom.validate().unwrap();
            planted_and_outside(&head, &g.groom);
        }
        let body = Surface::procedural(Shape::Body(BodyParams::default()));
        let g = GroomParams {
            style: Style::Fur,
            strands: 2000,
            points: 6,
            ..Default::default()
        }
        .generate(&body);
        planted_and_outside(&body, &g.groom);
    }

    #[test]
    fn generation_is_deterministic_and_seeded() {
        let head = head();
        let p = GroomParams {
            strands: 300,
            ..Default::default()
        };
        assert_eq!(p.generate(&head).groom, p.generate(&head).groom);
        let q = GroomParams { seed: 2, ..p };
        assert_ne!(p.generate(&head).groom, q.generate(&head).groom);
    }

    fn grow(style: Style, strands: u32) -> Groom {
        GroomParams {
            style,
            strands,
            points: 16,
            ..Default::default()
        }
        .generate(&head())
        .groom
    }

    #[test]
    fn regions_are_where_they_should_be() {
        let beard = grow(Style::Beard, 500);
        assert!(beard.roots().iter().all(|r| r.z > 0.0 && r.y < -0.02));
        let brows = grow(Style::Eyebrows, 500);
        // Roots lie in triangles whose centres are in the region: allow a cell.
        assert!(
            brows
                .roots()
                .iter()
                .all(|r| r.z > 0.06 && r.y > 0.017 && r.y < 0.045)
        );
        let lashes = grow(Style::Eyelashes, 200);
        assert!(
            lashes
                .roots()
                .iter()
                .all(|r| r.z > 0.075 && (r.y - 0.01).abs() < 0.01)
        );
        // Scalp hair: none on the face (below the hairline, in front of the ears).
        let scalp = grow(Style::Short, 3000);
        assert!(
            !scalp.roots().iter().any(|r| r.z > 0.06 && r.y < 0.06),
            "hair on the forehead"
        );
    }

    #[test]
    fn a_beard_thins_out_and_shortens_towards_its_edges() {
        let surface = head();
        let beard = grow(Style::Beard, 6000);
        let fade = |p: Vec3| Region::Beard.fade(p - surface.center);
        // The region's area within the fading band, against its roots there.
        let (mut band, mut all) = (0.0, 0.0);
        for t in 0..surface.mesh.triangle_count() {
            let [a, b, c] = surface.mesh.corners(t);
            let centre = (a + b + c) / 3.0 - surface.center;
            if Region::Beard.contains(centre) {
                all += surface.mesh.face_area(t);
                if Region::Beard.fade(centre) < 0.5 {
                    band += surface.mesh.face_area(t);
                }
            }
        }
        let roots = beard.roots();
        let in_band = roots.iter().filter(|&&r| fade(r) < 0.5).count();
        let (area_share, root_share) = (band / all, in_band as f32 / roots.len() as f32);
        assert!(area_share > 0.1, "the band is {area_share} of the beard");
        assert!(
            root_share < 0.6 * area_share,
            "{root_share} of the roots in {area_share} of the area"
        );
        let length = |s: usize| -> f32 {
            beard
                .strand(s)
                .windows(2)
                .map(|w| w[0].distance(w[1]))
                .sum()
        };
        let mean = |keep: &dyn Fn(f32) -> bool| {
            let l: Vec<f32> = (0..beard.strand_count())
                .filter(|&s| keep(fade(beard.strand(s)[0])))
                .map(length)
                .collect();
            assert!(!l.is_empty());
            l.iter().sum::<f32>() / l.len() as f32
        };
        let (edge, inside) = (mean(&|f| f < 0.2), mean(&|f| f >= 1.0));
        assert!(
            edge < 0.6 * inside,
            "edge strands {edge} m, inside {inside} m"
        );
    }

    #[test]
    fn long_hair_frames_the_face_and_falls_onto_the_shoulders() {
        let g = grow(Style::Long, 3000);
        // Nothing hangs in front of the face: no point within the face's box.
        for p in &g.positions {
            let in_face = p.x.abs() < 0.04 && p.y < 0.04 && p.y > -0.11 && p.z > 0.05;
            assert!(!in_face, "{p} hangs in front of the face");
        }
        // Tips reach below the shoulders' top and some lie in front of them.
        let tips: Vec<Vec3> = (0..g.strand_count())
            .map(|s| *g.strand(s).last().unwrap())
            .collect();
        assert!(tips.iter().filter(|t| t.y < -0.3).count() > tips.len() / 3);
        assert!(
            tips.iter().any(|t| t.z > 0.03 && t.x.abs() > 0.1),
            "none over the shoulders"
        );
    }

    #[test]
    fn curls_coil_and_bobs_are_cut_level() {
        // Curly strands are much longer than the distance root to tip.
        let curly = grow(Style::Curly, 300);
        let ratio: f32 = (0..curly.strand_count())
            .map(|s| {
                let p = curly.strand(s);
                let arc: f32 = p.windows(2).map(|w| w[0].distance(w[1])).sum();
                arc / p[0].distance(*p.last().unwrap())
            })
            .sum::<f32>()
            / curly.strand_count() as f32;
        assert!(ratio > 1.3, "curls: arc/chord {ratio}");
        let bob = grow(Style::Bob, 1000);
        // Cut level: no tip far below the cut, most tips near it.
        let lowest = bob
            .positions
            .iter()
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min);
        assert!(lowest > -0.11, "bob below its cut: {lowest}");
        let level = (0..bob.strand_count())
            .filter(|&s| bob.strand(s).last().unwrap().y < -0.08)
            .count();
        assert!(level > bob.strand_count() / 2, "{level} tips at the cut");
    }

    #[test]
    fn bad_parameters_are_named() {
        let p = GroomParams {
            clump: Some(2.0),
            ..Default::default()
        };
        assert_eq!(p.validate().unwrap_err(), "clump is out of range");
        let p = GroomParams {
            length: Some(f32::NAN),
            ..Default::default()
        };
        assert_eq!(p.validate().unwrap_err(), "length is out of range");
    }

    #[test]
    fn lipp_sized_groom_130k_by_32() {
        let head = head();
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
