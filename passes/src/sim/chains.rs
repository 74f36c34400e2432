//! Lipp's hair meshes as strands for the solver. A bundle is a stack of
//! layers, each a quad of four corners (Lipp §2); the corner `c` of every
//! layer, root to tip, is a polyline, a *chain*. `sim.pbd_chains` simulates
//! the four chains of every bundle as strands, rooted at the scalp layer, and
//! `sim.follow_layers` ([`super::follow`]) writes them back into
//! `hairmesh.layers`: the strands Lipp's Eq. 1 generates inside a bundle
//! follow its corners.
//!
//! Numbering follows `lipp::upload::pack` exactly: bundles across grooms in
//! scene order, each bundle's kept layers ([`kept_layers`]) from its
//! `first_layer`. Chain `4 b + c` of bundle `b` holds its `n` points at
//! `4 first_layer + c n ..`, so the points of a bundle fill the same span
//! (four per layer) as its corners in `hairmesh.layers`.
//!
//! Deviation: Lipp et al. animate hair meshes by their bundles but do not
//! say how; simulating the corners as Müller's FTL chains with the solver
//! Kulikov's strands use keeps one algorithm for both pipelines. The four
//! chains of a bundle are independent; the shape constraint and their equal
//! forces keep its cross-section close to rest.

use super::SimModel;
use super::upload::MODELS;
use crate::layout::words_of;
use crate::lipp::upload::kept_layers;
use crate::upload::Upload;
use strandgraph_assets::Scene;

/// Chains per bundle: one per layer corner.
pub const CORNERS: u32 = 4;

/// Per chain: its first point and point count (the solver's `groom.strands`).
pub const CHAINS: &str = "sim.chains";
/// Per point: the rest position in groom-local space, w 0 (its `sim.rest`).
pub const REST: &str = "sim.chain_rest";
/// Per point: the simulated position in groom-local space (its
/// `groom.vertices`), uploaded as the rest pose.
pub const POINTS: &str = "sim.chain_points";
/// Per point: the rest tangent in groom-local space, w 0.
pub const TANGENTS: &str = "sim.chain_tangents";
/// [`SimModel`] per groom, its range over the chains (its `sim.models`).
pub const CHAIN_MODELS: &str = "sim.chain_models";

/// Adds the chains of every groom's hair mesh to `up`, and their
/// `sim.chain_models` from `sim.models` (which must be packed first).
pub fn pack(scene: &Scene, up: &mut Upload) {
    let (mut chains, mut rest, mut tangents) = (Vec::new(), Vec::new(), Vec::new());
    for g in &scene.grooms {
        let Some(mesh) = &g.hair_mesh else { continue };
        for b in 0..mesh.bundles.len() {
            let src = mesh.bundle_layers(b);
            let kept = kept_layers(src.len() as u32);
            let first = (rest.len() / 4) as u32;
            let n = kept.len() as u32;
            for c in 0..CORNERS as usize {
                chains.extend([first + c as u32 * n, n]);
                for &k in &kept {
                    let l = &src[k as usize];
                    rest.extend(l.positions[c].extend(0.0).to_array().map(f32::to_bits));
                    tangents.extend(l.tangents[c].extend(0.0).to_array().map(f32::to_bits));
                }
            }
        }
    }
    up.set(CHAINS, chains);
    up.set(POINTS, rest.clone());
    up.set(REST, rest);
    up.set(TANGENTS, tangents);
    repose(scene, up);
}

/// `sim.chain_models`: `sim.models` as it is this frame, each groom's
/// range moved to its chains. Nothing without `sim.models`.
pub fn repose(scene: &Scene, up: &mut Upload) {
    let Some(words) = up.resources.get(MODELS) else {
        return;
    };
    let mut models: Vec<SimModel> = bytemuck::pod_collect_to_vec(words);
    let mut first = 0;
    for (m, g) in models.iter_mut().zip(&scene.grooms) {
        let count = g.hair_mesh.as_ref().map_or(0, |h| h.bundles.len() as u32) * CORNERS;
        (m.strand_first, m.strand_count) = (first, count);
        first += count;
    }
    up.set(CHAIN_MODELS, words_of(&models));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lipp::LAYER_WORDS;

    /// Every chain point is its corner in `hairmesh.layers`, carried to
    /// world space by the groom's transform.
    #[test]
    fn chains_are_the_layers_corners() {
        let scene = crate::sim::tests::long_hair_scene(60);
        let mut up = crate::upload::upload(&scene, 64, 64);
        super::super::upload::pack(&scene, &mut up);
        pack(&scene, &mut up);
        let (chains, rest) = (&up.resources[CHAINS], &up.resources[REST]);
        let layers = &up.resources[crate::lipp::upload::LAYERS];
        let bundles = &up.resources[crate::lipp::upload::BUNDLES];
        let bundle_count = bundles.len() / crate::lipp::BUNDLE_WORDS;
        assert!(bundle_count > 0);
        assert_eq!(chains.len(), 2 * CORNERS as usize * bundle_count);
        assert_eq!(rest.len(), layers.len() / LAYER_WORDS * 4 * 4);
        let world = scene.grooms[0].world;
        let f = |w: &[u32], i: usize| f32::from_bits(w[i]);
        for chain in 0..chains.len() / 2 {
            let (b, c) = (chain / 4, chain % 4);
            let first_layer = bundles[b * crate::lipp::BUNDLE_WORDS] as usize;
            let (first, n) = (chains[2 * chain] as usize, chains[2 * chain + 1] as usize);
            assert_eq!(first, 4 * first_layer + c * n);
            for l in 0..n {
                let p = glam::Vec3::new(
                    f(rest, 4 * (first + l)),
                    f(rest, 4 * (first + l) + 1),
                    f(rest, 4 * (first + l) + 2),
                );
                let o = (first_layer + l) * LAYER_WORDS + c * 8;
                let corner = glam::Vec3::new(f(layers, o), f(layers, o + 1), f(layers, o + 2));
                assert!(world.transform_point3(p).distance(corner) < 1e-5);
            }
        }
        let models: Vec<SimModel> = bytemuck::pod_collect_to_vec(&up.resources[CHAIN_MODELS]);
        assert_eq!(
            (models[0].strand_first, models[0].strand_count),
            (0, (chains.len() / 2) as u32)
        );
    }
}
