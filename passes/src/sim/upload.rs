//! The simulation's imported resources: `sim.sdf`, each simulated groom's
//! collision field, baked once from its parent mesh in the groom's local
//! space (so the field moves with the head joint) and cached on disk
//! ([`super::field_cache`]); and `sim.models`, per
//! groom the inverse of this frame's world transform, the rest pose's down
//! direction and the field's placement, repacked every animated frame.

use super::field_cache;
use super::sdf::FIELD_WORDS;
use super::{SIM_COLLIDER, SIM_SIMULATE, SimModel};
use crate::layout::words_of;
use crate::upload::Upload;
use glam::{Mat4, Vec3};
use strandgraph_assets::Scene;

pub const MODELS: &str = "sim.models";
pub const SDF: &str = "sim.sdf";
/// The rest pose the solver keeps (a copy of `groom.vertices`, which it
/// overwrites with the simulated strands).
pub const REST: &str = "sim.rest";

/// Space around the head the field covers, in the mesh's units: hair
/// further out cannot reach it within a frame.
const FIELD_PADDING: f32 = 0.03;

/// Bakes a collision field for every groom with a parent mesh into
/// `sim.sdf` (grooms placed alike on one mesh share one bake), marks the
/// grooms the scene simulates in `sim.models`, keeps the rest pose as
/// `sim.rest`, and writes `sim.models`' pose part for the scene's pose.
/// Every groom gets its field, so the pass's `models: "All"` needs no
/// packing of its own.
pub fn pack(scene: &Scene, up: &mut Upload) {
    let start = std::time::Instant::now();
    let mut sdf = vec![0u32; FIELD_WORDS * scene.grooms.len()];
    let mut placement = vec![None; scene.grooms.len()];
    let mut baked: Vec<(usize, [u32; 16], usize)> = Vec::new();
    for (i, g) in scene.grooms.iter().enumerate() {
        let Some(parent) = g.parent else {
            continue;
        };
        let mesh = &scene.meshes[parent].mesh;
        // Groom local → mesh local: the groom's transform relative to its parent.
        let to_mesh = mesh.transform.matrix().inverse() * g.rest_world;
        let key = to_mesh.to_cols_array().map(f32::to_bits);
        if let Some(&(_, _, first)) = baked.iter().find(|b| b.0 == parent && b.1 == key) {
            sdf.copy_within(
                first * FIELD_WORDS..(first + 1) * FIELD_WORDS,
                i * FIELD_WORDS,
            );
            placement[i] = placement[first];
            continue;
        }
        let region = mesh.bounds().transformed(&to_mesh.inverse());
        let scale = to_mesh.x_axis.truncate().length();
        let cache = strandgraph_bake::cache_dir();
        let padding = FIELD_PADDING / scale;
        let Some(field) = field_cache::bake(mesh, to_mesh, region, padding, cache.as_deref())
        else {
            continue;
        };
        let words = &mut sdf[i * FIELD_WORDS..(i + 1) * FIELD_WORDS];
        for (w, v) in words.iter_mut().zip(&field.values) {
            *w = v.to_bits();
        }
        placement[i] = Some([field.min.x, field.min.y, field.min.z, 1.0 / field.voxel]);
        baked.push((parent, key, i));
    }
    if !baked.is_empty() {
        tracing::info!(
            fields = baked.len(),
            seconds = start.elapsed().as_secs_f32(),
            "baked head collision fields"
        );
    }
    let models: Vec<SimModel> = scene
        .grooms
        .iter()
        .enumerate()
        .map(|(i, g)| {
            let rest_down = g
                .rest_world
                .inverse()
                .transform_vector3(Vec3::NEG_Y)
                .normalize_or_zero();
            let mut flags = if g.simulate { SIM_SIMULATE } else { 0 };
            if placement[i].is_some() {
                flags |= SIM_COLLIDER;
            }
            let strands = up
                .models
                .get(i)
                .map_or((0, 0), |m| (m.strand_first, m.strand_count));
            SimModel {
                inv_world: Mat4::IDENTITY.to_cols_array(),
                rest_down: [rest_down.x, rest_down.y, rest_down.z, 0.0],
                sdf_min: placement[i].unwrap_or([0.0; 4]),
                scale: 1.0,
                flags,
                strand_first: strands.0,
                strand_count: strands.1,
                grid_min: super::grid::placement(&g.groom.bounds()),
            }
        })
        .collect();
    up.set(SDF, sdf);
    up.set(MODELS, words_of(&models));
    if let Some(rest) = up.resources.get("groom.vertices").cloned() {
        up.set(REST, rest);
    }
    repose(scene, up);
}

/// Rewrites `sim.models`' per-frame part (the inverse world transform and
/// scale) for the scene's current pose, and `sim.chain_models` from it
/// where the upload has one; nothing without `sim.models`.
pub fn repose(scene: &Scene, up: &mut Upload) {
    let Some(words) = up.resources.get_mut(MODELS) else {
        return;
    };
    let mut models: Vec<SimModel> = bytemuck::pod_collect_to_vec(words);
    for (m, g) in models.iter_mut().zip(&scene.grooms) {
        m.inv_world = g.world.inverse().to_cols_array();
        m.scale = g.world.x_axis.truncate().length();
    }
    *words = words_of(&models);
    // The hair meshes' chains take the same records with their own ranges.
    if up.resources.contains_key(super::chains::CHAIN_MODELS) {
        super::chains::repose(scene, up);
    }
}
