//! Builds every groom's hair patches ([`HairPatches`]) and packs them into
//! `patches.vertices`, `patches.models` and `patches.texture` (layouts in
//! `scenes/graphs/scheuermann.ron` and `shaders/scheuermann/hair.wgsl`).
//!
//! Patches are stored in world space (each groom's world matrix applied here
//! once). Grooms follow in scene order, each groom's patches in its static
//! inside-to-outside order; a patch's model is its groom's index in `models`
//! (upload.rs pushes one model per groom, in the same order). The paper sorts
//! one hair model; across grooms the order is the scene's, not the view's.

use super::hair::VERTEX_WORDS;
use super::texture;
use crate::upload::Upload;
use glam::{Mat3, Vec3};
use strandgraph_assets::Scene;
use strandgraph_assets::hairpatch::{HairPatches, HairTexture, PatchVertex, strand_shading};
use strandgraph_assets::octahedral::pack_unit_vector;

/// Resource names.
pub const VERTICES: &str = "patches.vertices";
pub const MODELS: &str = "patches.models";
pub const TEXTURE: &str = "patches.texture";
/// Per groom vertex, Scheuermann's shading inputs on the strands
/// themselves, for his ground truth (scenes/graphs/scheuermann_reference.ron).
pub const STRAND_SHADING: &str = "scheuermann.strand_shading";

/// Words per vertex of [`STRAND_SHADING`]: octahedral world normal, AO,
/// texture u, texture v (0 at the root, 1 at the tip).
pub const STRAND_SHADING_WORDS: usize = 4;

/// Adds [`STRAND_SHADING`] for every vertex of `groom.vertices` (in its
/// order: grooms in scene order, each as `upload` resamples it) and, if
/// missing, the hair texture.
pub fn pack_strand_shading(scene: &Scene, up: &mut Upload) {
    let mut words: Vec<u32> = Vec::new();
    for g in &scene.grooms {
        let started = std::time::Instant::now();
        let groom = crate::upload::uniform_groom(g);
        let place = Placement::new(g.world);
        let shading = strand_shading(&groom, g.patches.seed);
        tracing::info!(
            groom = %g.name,
            points = shading.len(),
            ms = started.elapsed().as_secs_f64() * 1e3,
            "strand shading inputs built"
        );
        for s in 0..groom.strand_count() {
            let range = groom.strand_range(s);
            let last = range.len().saturating_sub(1).max(1) as f32;
            for (i, p) in range.enumerate() {
                let x = &shading[p];
                let n = pack_unit_vector((place.directions * x.normal).normalize_or(Vec3::Y));
                words.extend([
                    n,
                    x.ao.to_bits(),
                    x.u.to_bits(),
                    (i as f32 / last).to_bits(),
                ]);
            }
        }
    }
    up.set(STRAND_SHADING, words);
    if !up.resources.contains_key(TEXTURE) {
        let seed = scene.grooms.first().map_or(1, |g| g.patches.seed);
        up.set(TEXTURE, texture::words(&HairTexture::generate(seed)));
    }
}

/// Builds the patches of every groom and adds them, the hair texture and
/// the patch count to `up`.
pub fn pack(scene: &Scene, up: &mut Upload) {
    let mut vertices: Vec<u32> = Vec::new();
    let mut models: Vec<u32> = Vec::new();
    for (model, g) in scene.grooms.iter().enumerate() {
        let started = std::time::Instant::now();
        let patches = HairPatches::build(&g.groom, &g.patches);
        tracing::info!(
            groom = %g.name,
            patches = patches.patches.len(),
            ms = started.elapsed().as_secs_f64() * 1e3,
            "hair patches built"
        );
        let place = Placement::new(g.world);
        for p in &patches.patches {
            models.push(model as u32);
            for v in &p.vertices {
                vertices.extend(place.vertex(v));
            }
        }
    }
    up.quantities.patches = models.len() as u64;
    let seed = scene.grooms.first().map_or(1, |g| g.patches.seed);
    up.set(VERTICES, vertices);
    up.set(MODELS, models);
    up.set(TEXTURE, texture::words(&HairTexture::generate(seed)));
}

/// A groom's world transform, for positions and directions.
pub(crate) struct Placement {
    world: glam::Mat4,
    directions: Mat3,
    /// How much the transform scales lengths (texel densities are per metre).
    scale: f32,
}

impl Placement {
    pub(crate) fn new(world: glam::Mat4) -> Self {
        let directions = Mat3::from_mat4(world);
        let scale = directions.determinant().abs().cbrt().max(1e-12);
        Self {
            world,
            directions,
            scale,
        }
    }

    /// The 8 words of one vertex: world position, AO, octahedral tangent and
    /// normal, u | v << 16 as unorm16, texels per metre.
    pub(crate) fn vertex(&self, v: &PatchVertex) -> [u32; VERTEX_WORDS] {
        let p = self.world.transform_point3(v.position);
        let dir = |d: Vec3| pack_unit_vector((self.directions * d).normalize_or(Vec3::Y));
        let unorm = |x: f32| (x.clamp(0.0, 1.0) * 65535.0).round() as u32;
        [
            p.x.to_bits(),
            p.y.to_bits(),
            p.z.to_bits(),
            v.ao.to_bits(),
            dir(v.tangent),
            dir(v.normal),
            unorm(v.u) | (unorm(v.v) << 16),
            (v.texels_per_metre / self.scale).to_bits(),
        ]
    }
}
