//! Packs a scene's hair meshes into `hairmesh.bundles` and `hairmesh.layers`
//! (layouts in `scenes/graphs/lipp.ron` and [`super::BundleRecord`],
//! [`super::Corner`]) and the environment into `env.sh` and
//! `env.prefiltered` ([`super::probe`]).
//!
//! Layers are stored in world space (each groom's world matrix applied here
//! once), so the kernels need no per-bundle transform. Bundles are numbered
//! across grooms in scene order; a bundle's `model` is its groom's index in
//! `models` (upload.rs pushes one model per groom, in the same order).
//! Bundles taller than [`MAX_LAYERS`] are resampled to that many evenly
//! spaced layers (the graph sizes `hairmesh.layers` at 16 layers per bundle).

use super::{BUNDLE_WORDS, BundleRecord, LAYER_WORDS, MAX_LAYERS, pcg};
use crate::upload::Upload;
use glam::Mat3;
use strandgraph_assets::Scene;

/// Resource names.
pub const BUNDLES: &str = "hairmesh.bundles";
pub const LAYERS: &str = "hairmesh.layers";
pub const ENV_SH: &str = "env.sh";

/// The layers kept of a bundle of `n` layers: all, or 16 evenly spaced.
pub fn kept_layers(n: u32) -> Vec<u32> {
    if n <= MAX_LAYERS {
        return (0..n).collect();
    }
    (0..MAX_LAYERS)
        .map(|i| ((i as f32 * (n - 1) as f32 / (MAX_LAYERS - 1) as f32).round() as u32).min(n - 1))
        .collect()
}

/// Adds the Lipp resources to `up`. Grooms without a hair mesh add nothing.
pub fn pack(scene: &Scene, up: &mut Upload) {
    let mut bundles: Vec<u32> = Vec::new();
    let mut layers: Vec<u32> = Vec::new();
    let mut index = 0u32;
    for (model, g) in scene.grooms.iter().enumerate() {
        let Some(mesh) = &g.hair_mesh else { continue };
        let world = g.world;
        let normal = Mat3::from_mat4(world);
        let groom_points = g.groom.max_points_per_strand();
        for (b, bd) in mesh.bundles.iter().enumerate() {
            let src = mesh.bundle_layers(b);
            let kept = kept_layers(src.len() as u32);
            let record = BundleRecord {
                first_layer: (layers.len() / LAYER_WORDS) as u32,
                layer_count: kept.len() as u32,
                strands: bd.strands,
                model: model as u32,
                curl_radius: bd.style.curl_radius,
                curl_turns: bd.style.curl_turns,
                twist: bd.style.twist,
                noise: bd.style.noise,
                seed: pcg(index ^ pcg(model as u32 + 0x51ed_270b)),
                lod_lambda: if g.lod.enabled {
                    g.lod.lambda.max(0.0)
                } else {
                    0.0
                },
                groom_points,
            };
            for &k in &kept {
                let l = &src[k as usize];
                for c in 0..4 {
                    let p = world.transform_point3(l.positions[c]);
                    let t = (normal * l.tangents[c]).normalize_or_zero();
                    layers.extend(
                        [p.x, p.y, p.z, l.ao[c], t.x, t.y, t.z, l.uvw[c].z].map(f32::to_bits),
                    );
                }
            }
            bundles.extend(record.words());
            index += 1;
        }
    }
    debug_assert_eq!(bundles.len(), index as usize * BUNDLE_WORDS);
    up.set(BUNDLES, bundles);
    up.set(LAYERS, layers);
    up.set(ENV_SH, env_sh(scene));
    up.set(
        super::probe::PREFILTERED,
        super::probe::prefiltered_words(scene),
    );
}

/// `env.sh`: 9 L2 spherical-harmonic radiance coefficients (Ramamoorthi and
/// Hanrahan 2001), rgb + pad each: the environment map projected, or the
/// constant colour's L00 term (`L · 4π · Y00`) ([`super::probe::sh_words`]).
pub fn env_sh(scene: &Scene) -> Vec<u32> {
    super::probe::sh_words(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tall_bundles_keep_root_and_tip() {
        assert_eq!(kept_layers(8), (0..8).collect::<Vec<_>>());
        let k = kept_layers(40);
        assert_eq!(k.len(), 16);
        assert_eq!((k[0], k[15]), (0, 39));
        assert!(k.windows(2).all(|w| w[0] < w[1]));
    }
}
