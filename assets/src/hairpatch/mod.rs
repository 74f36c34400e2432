//! Polygonal hair patches after Scheuermann 2004, "Hair Rendering and Shading": the groom
//! as "several layers of patches to approximate volumetric qualities of hair", textured
//! ribbons with "ambient occlusion to approximate self-shadowing - per vertex", drawn in a
//! "static index buffer with inside to outside draw order, computed at preprocess time".
//!
//! The paper's patches were authored by hand; ours are generated from any strand groom so
//! the same scene feeds every pipeline: strands are clumped by k-means (as
//! [`crate::hairmesh::fit`] clusters bundles), each clump is split into layers by how far
//! its strands lie outward, and each layer becomes one strip along its strands' mean.

mod ao;
mod centre;
mod outward;
mod strand_shading;
mod strip;
pub mod texture;

use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::groom::Groom;
use crate::hairmesh::fit::kmeans;

pub use strand_shading::{StrandShading, strand_shading};
pub use texture::HairTexture;

/// Quads along every patch, root to tip (so 2 * (PATCH_SEGMENTS + 1) vertices per patch).
pub const PATCH_SEGMENTS: usize = 16;

/// How a groom's hair patches are generated.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PatchParams {
    /// Strands per clump (k-means clusters = strands / clump_strands, at least 1).
    pub clump_strands: u32,
    /// Layers per clump, inner to outer (at most the clump's strand count).
    pub layers: u32,
    /// Width of each strip as a multiple of the standard deviation of its strands across it.
    pub width_sigmas: f32,
    pub seed: u64,
}

impl Default for PatchParams {
    fn default() -> Self {
        PatchParams {
            clump_strands: 48,
            layers: 3,
            width_sigmas: 4.0,
            seed: 1,
        }
    }
}

impl PatchParams {
    /// What is wrong with the parameters, if anything; the message names the field.
    pub fn validate(&self) -> Result<(), String> {
        if !(1..=4096).contains(&self.clump_strands) {
            return Err(format!(
                "clump_strands must be in 1..=4096 (got {})",
                self.clump_strands
            ));
        }
        if !(1..=8).contains(&self.layers) {
            return Err(format!("layers must be in 1..=8 (got {})", self.layers));
        }
        if !(self.width_sigmas > 0.0 && self.width_sigmas <= 16.0) {
            return Err(format!(
                "width_sigmas must be in (0, 16] (got {})",
                self.width_sigmas
            ));
        }
        Ok(())
    }

    /// Out-of-range values pulled into range, so that `build` never misbehaves on
    /// parameters that skipped `validate`.
    fn sanitized(&self) -> PatchParams {
        let width_sigmas = if self.width_sigmas > 0.0 {
            self.width_sigmas.min(16.0)
        } else {
            PatchParams::default().width_sigmas
        };
        PatchParams {
            clump_strands: self.clump_strands.clamp(1, 4096),
            layers: self.layers.clamp(1, 8),
            width_sigmas,
            seed: self.seed,
        }
    }
}

/// One vertex of a patch.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PatchVertex {
    /// Groom space (same space as [`Groom::positions`]).
    pub position: Vec3,
    /// Unit, root → tip along the strip.
    pub tangent: Vec3,
    /// Unit, outward (away from the head), perpendicular to `tangent`: the strip's face normal.
    pub normal: Vec3,
    /// Texture u: left edge = variant / VARIANTS, right edge = (variant + 1) / VARIANTS.
    pub u: f32,
    /// 0 at the root, 1 at the tip (arc-length parameter of the strip's centre line).
    pub v: f32,
    /// Baked ambient occlusion in [0, 1], 1 = unoccluded.
    pub ao: f32,
    /// Texture texels across u per metre of strip width here:
    /// (HairTexture::WIDTH / VARIANTS) / strip width.
    pub texels_per_metre: f32,
}

/// One textured strip: a layer of a clump.
#[derive(Debug, Clone, PartialEq)]
pub struct Patch {
    /// 0 = innermost layer of its clump.
    pub layer: u32,
    pub clump: u32,
    /// 2 * (PATCH_SEGMENTS + 1) vertices: cross-section i has vertices 2i (left) and 2i + 1
    /// (right), i = 0 at the root. Left/right are chosen so that the triangles
    /// (2i, 2i+1, 2i+2) and (2i+1, 2i+3, 2i+2) are counter-clockwise seen from the +normal
    /// side (right = position + binormal * w/2 with binormal = normalize(cross(tangent, normal))).
    pub vertices: Vec<PatchVertex>,
}

/// A groom's hair patches.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HairPatches {
    /// In the static draw order: inside to outside (Scheuermann 2004: "Use static index
    /// buffer with inside to outside draw order, computed at preprocess time. Sort
    /// connected components (hair strand patches) instead of individual triangles").
    pub patches: Vec<Patch>,
    /// The centre the outward direction points away from: the head the roots sit on.
    pub centre: Vec3,
}

/// The groom resampled to `PATCH_SEGMENTS + 1` points per strand, and which strands are
/// usable (finite points).
struct Strands {
    groom: Groom,
    valid: Vec<u32>,
}

impl Strands {
    const N: usize = PATCH_SEGMENTS + 1;

    fn new(groom: &Groom) -> Strands {
        let groom = groom.resampled(Self::N);
        let valid = (0..groom.strand_count() as u32)
            .filter(|&s| {
                let r = s as usize * Self::N..(s as usize + 1) * Self::N;
                groom.positions[r.clone()].iter().all(|p| p.is_finite())
                    && groom.thickness[r].iter().all(|t| t.is_finite())
            })
            .collect();
        Strands { groom, valid }
    }
    fn points(&self, s: u32) -> &[Vec3] {
        let s = s as usize;
        &self.groom.positions[s * Self::N..(s + 1) * Self::N]
    }
    fn thickness(&self, s: u32) -> &[f32] {
        let s = s as usize;
        &self.groom.thickness[s * Self::N..(s + 1) * Self::N]
    }
}

impl HairPatches {
    /// Generates the patches of a groom: clumps, layers, strips, AO, draw order.
    pub fn build(groom: &Groom, params: &PatchParams) -> HairPatches {
        let params = params.sanitized();
        let strands = Strands::new(groom);
        let centre = centre::head_centre(&strands);
        let density = ao::density(&strands);
        let outward = outward::Outward {
            centre,
            grid: density.as_ref(),
        };
        let clumps = clumps(&strands, &params);
        let mut keyed: Vec<(f32, Patch)> = clumps
            .par_iter()
            .enumerate()
            .flat_map_iter(|(c, m)| strip::clump_patches(&strands, m, c as u32, &outward, &params))
            .collect();
        // Inner first; ties by clump then layer, so the order is deterministic.
        keyed.sort_by(|(ka, a), (kb, b)| {
            ka.total_cmp(kb)
                .then(a.clump.cmp(&b.clump))
                .then(a.layer.cmp(&b.layer))
        });
        let mut patches: Vec<Patch> = keyed.into_iter().map(|(_, p)| p).collect();
        if let Some(grid) = &density {
            ao::bake(&mut patches, grid);
        }
        HairPatches { patches, centre }
    }

    /// Two triangles per quad, PATCH_SEGMENTS quads per patch.
    pub fn triangle_count(&self) -> usize {
        self.patches.len() * 2 * PATCH_SEGMENTS
    }
}

/// The strands of each clump (non-empty clumps only). Clustered like
/// [`crate::hairmesh::fit`]: on the root and the point a third of the way along, so
/// strands planted side by side but combed apart (at a parting) land in different clumps.
fn clumps(strands: &Strands, params: &PatchParams) -> Vec<Vec<u32>> {
    let features: Vec<Vec3> = strands
        .valid
        .iter()
        .map(|&s| {
            let p = strands.points(s);
            (p[0] + p[p.len() / 3]) * 0.5
        })
        .collect();
    let k = features.len().div_ceil(params.clump_strands as usize);
    let assign = kmeans(&features, k, 10, params.seed, 20_000);
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); k];
    for (&s, &a) in strands.valid.iter().zip(&assign) {
        members[a as usize].push(s);
    }
    members.retain(|m| !m.is_empty());
    members
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::procedural::surface::{Shape, Surface};
    use crate::procedural::{GroomParams, HeadParams, Style};

    /// Strands planted on the upper half of a sphere of radius 0.1 about the origin,
    /// combed down over it and hanging below, in `shells` radial layers 6 mm apart.
    pub(super) fn sphere_groom(shells: usize) -> Groom {
        let mut strands = Vec::new();
        for shell in 0..shells {
            for a in 0..48 {
                for p in 0..8 {
                    let az = (a as f32 + 0.3 * shell as f32) * std::f32::consts::TAU / 48.0;
                    let theta0 = 0.15 + p as f32 * 0.14;
                    let lift = 0.004 + 0.006 * shell as f32;
                    let pts: Vec<Vec3> = (0..24)
                        .map(|i| {
                            let s = i as f32 / 23.0;
                            let theta = theta0 + s * (1.7 - theta0);
                            let r = 0.1 + lift * (s * 8.0).min(1.0);
                            let d = Vec3::new(
                                az.cos() * theta.sin(),
                                theta.cos(),
                                az.sin() * theta.sin(),
                            );
                            d * r
                        })
                        .collect();
                    strands.push(pts);
                }
            }
        }
        Groom::from_strands(strands, 80e-6)
    }

    fn head_groom(strands: u32) -> Groom {
        let head = Surface::procedural(Shape::Head(HeadParams::default()));
        GroomParams {
            style: Style::Long,
            strands,
            points: 24,
            ..Default::default()
        }
        .generate(&head)
        .groom
    }

    /// The invariants the GPU side relies on.
    fn check_structure(h: &HairPatches) {
        assert!(!h.patches.is_empty());
        assert_eq!(h.triangle_count(), h.patches.len() * 2 * PATCH_SEGMENTS);
        for p in &h.patches {
            let v = &p.vertices;
            assert_eq!(v.len(), 2 * (PATCH_SEGMENTS + 1));
            for x in v {
                assert!((x.normal.length() - 1.0).abs() < 1e-4, "{x:?}");
                assert!((x.tangent.length() - 1.0).abs() < 1e-4, "{x:?}");
                assert!(x.normal.dot(x.tangent).abs() < 1e-3, "{x:?}");
                assert!((0.0..=1.0).contains(&x.ao) && (0.0..=1.0).contains(&x.v));
                assert!(x.texels_per_metre > 0.0 && x.texels_per_metre.is_finite());
            }
            assert!(v[0].v == 0.0 && v[2 * PATCH_SEGMENTS].v == 1.0);
            for i in 0..PATCH_SEGMENTS {
                let (a, b, c, d) = (v[2 * i], v[2 * i + 1], v[2 * i + 2], v[2 * i + 3]);
                // Root to tip.
                let step = (c.position + d.position - a.position - b.position) * 0.5;
                assert!(
                    a.tangent.dot(step) > 0.0,
                    "patch {} {}: {i}",
                    p.clump,
                    p.layer
                );
                // Counter-clockwise from the +normal side, both triangles.
                let n1 = (b.position - a.position).cross(c.position - a.position);
                let n2 = (d.position - b.position).cross(c.position - b.position);
                assert!(
                    n1.dot(a.normal) > 0.0 && n2.dot(b.normal) > 0.0,
                    "patch {} {}: {i}",
                    p.clump,
                    p.layer
                );
                assert!(a.u < b.u && a.u == c.u && b.u == d.u);
            }
        }
    }

    #[test]
    fn patches_are_well_formed() {
        let g = sphere_groom(3);
        let h = HairPatches::build(&g, &PatchParams::default());
        check_structure(&h);
        assert!(h.centre.length() < 1e-3, "{}", h.centre);
        let clumps = g.strand_count().div_ceil(48);
        assert!(h.patches.len() > clumps && h.patches.len() <= 3 * clumps);
        check_structure(&HairPatches::build(
            &head_groom(3000),
            &PatchParams::default(),
        ));
        // Deterministic.
        assert_eq!(h, HairPatches::build(&g, &PatchParams::default()));
    }

    #[test]
    fn inner_layers_draw_first_and_are_darker() {
        let h = HairPatches::build(&sphere_groom(3), &PatchParams::default());
        let key = |p: &Patch| {
            let v = &p.vertices;
            (0..v.len() / 2)
                .map(|i| {
                    ((v[2 * i].position + v[2 * i + 1].position) * 0.5 - h.centre)
                        .dot(v[2 * i].normal)
                })
                .sum::<f32>()
                / (v.len() / 2) as f32
        };
        for w in h.patches.windows(2) {
            assert!(key(&w[0]) <= key(&w[1]) + 1e-6);
        }
        // Within every clump, layer l draws before layer l + 1.
        let mut seen = std::collections::HashMap::new();
        for p in &h.patches {
            let last = seen.insert(p.clump, p.layer);
            assert!(last.is_none_or(|l| l < p.layer), "clump {}", p.clump);
        }
        let ao = |layer: u32| {
            let v: Vec<f32> = h
                .patches
                .iter()
                .filter(|p| p.layer == layer)
                .flat_map(|p| p.vertices.iter().map(|v| v.ao))
                .collect();
            v.iter().sum::<f32>() / v.len() as f32
        };
        let (inner, outer) = (ao(0), ao(2));
        assert!(inner + 0.1 < outer, "{inner} vs {outer}");
    }

    #[test]
    fn strips_cover_their_strands() {
        let g = sphere_groom(3);
        let params = PatchParams::default();
        let strands = Strands::new(&g);
        let centre = centre::head_centre(&strands);
        let density = ao::density(&strands);
        let outward = outward::Outward {
            centre,
            grid: density.as_ref(),
        };
        let (mut inside, mut total) = (0, 0);
        for (c, m) in clumps(&strands, &params).iter().enumerate() {
            let layers = strip::clump_layers(&strands, m, &outward, params.layers).unwrap();
            for (l, group) in layers.groups.iter().enumerate() {
                let (_, p) = strip::strip(
                    &strands, group, &layers.n, c as u32, l as u32, centre, &params,
                )
                .unwrap();
                let i = PATCH_SEGMENTS / 2;
                let (a, b) = (p.vertices[2 * i].position, p.vertices[2 * i + 1].position);
                let (mid, half) = ((a + b) * 0.5, a.distance(b) * 0.5);
                for &s in group {
                    total += 1;
                    inside += usize::from(
                        ((strands.points(s)[i] - mid).dot((b - a) / (2.0 * half))).abs() <= half,
                    );
                }
            }
        }
        assert_eq!(total, g.strand_count());
        assert!(inside as f32 > 0.85 * total as f32, "{inside} of {total}");
    }

    #[test]
    fn odd_grooms_do_not_panic() {
        let p = PatchParams::default();
        let empty = HairPatches::build(&Groom::default(), &p);
        assert!(empty.patches.is_empty() && empty.triangle_count() == 0);
        let one = Groom::from_strands([[Vec3::ZERO, Vec3::new(0.0, -0.1, 0.01)]], 1e-4);
        let h = HairPatches::build(&one, &p);
        assert_eq!(h.patches.len(), 1);
        check_structure(&h);
        // Points, a zero-length strand, a NaN strand and a normal one; bad parameters.
        let odd = Groom::from_strands(
            vec![
                vec![Vec3::ONE],
                vec![Vec3::X; 3],
                vec![Vec3::NAN, Vec3::ONE],
                vec![Vec3::ZERO, Vec3::Y],
            ],
            1e-4,
        );
        let bad = PatchParams {
            clump_strands: 0,
            layers: 0,
            width_sigmas: f32::NAN,
            seed: 0,
        };
        let h = HairPatches::build(&odd, &bad);
        assert!(
            h.patches
                .iter()
                .all(|p| p.vertices.iter().all(|v| v.position.is_finite()))
        );
        // Hair pointing straight out of the centre.
        let spikes = Groom::from_strands(
            (0..5).map(|i| [Vec3::Y * (1.0 + i as f32 * 1e-3), Vec3::Y * 2.0]),
            1e-4,
        );
        check_structure(&HairPatches::build(&spikes, &p));
    }

    #[test]
    fn params_validate_and_parse() {
        assert!(PatchParams::default().validate().is_ok());
        for layers in [0, 9] {
            let e = PatchParams {
                layers,
                ..Default::default()
            }
            .validate()
            .unwrap_err();
            assert!(e.contains("layers"), "{e}");
        }
        let e = PatchParams {
            clump_strands: 5000,
            ..Default::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.contains("clump_strands"), "{e}");
        for w in [0.0, 17.0, f32::NAN] {
            let e = PatchParams {
                width_sigmas: w,
                ..Default::default()
            }
            .validate()
            .unwrap_err();
            assert!(e.contains("width_sigmas"), "{e}");
        }
        let p: PatchParams = ron::from_str("(layers: 2)").unwrap();
        assert_eq!(
            p,
            PatchParams {
                layers: 2,
                ..Default::default()
            }
        );
        assert!(ron::from_str::<PatchParams>("(layer: 2)").is_err());
    }
}
