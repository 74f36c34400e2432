//! Hair simulation: Kulikov's "PBD solver, based on 'Fast Simulation of
//! Inextensible Hair and Fur' [Müller12]", run before skinning on the
//! graphics queue.
//!
//! Kulikov: "Every strand and every strand vertex is simulated. Outputs
//! vertex positions, velocities and density voxel grid. Skinned to head
//! joint (no blend shapes). Prebuilt SDFs for head collisions (0.25MB per
//! head). ... Once simulation step is over we output local positions for
//! hair vertices and their velocities for following passes."
//!
//! - [`pbd`]: the solver pass `sim.pbd`, one lane per strand: dynamic
//!   follow-the-leader with Müller's damping correction, gravity, the head
//!   joint's motion, collisions with the parent mesh's SDF and friction. It
//!   writes the simulated strands' local positions over their rest pose in
//!   `groom.vertices` (reading the rest pose from `sim.rest`), so
//!   `kulikov.skin` runs root skinning on them as before and the grooms it
//!   does not simulate cost nothing; the density grid (`kulikov.density`) is
//!   splatted from the skinned, so simulated, positions.
//! - [`chains`] and [`follow`]: Lipp's hair meshes simulated by the same
//!   solver: each bundle's four corner chains (its layers' corners, root to
//!   tip) are strands to `sim.pbd_chains`, and `sim.follow_layers` writes
//!   the simulated corners and their turned tangents into
//!   `hairmesh.layers`, so the strands generated from the bundles follow.
//! - [`grid`]: hair-hair friction, `sim.splat` filling each groom's
//!   velocity grid from last frame's state for the solver to read.
//! - [`sdf`]: the field's sampling, shared by the solver and its tests.
//! - [`upload`]: `sim.models` (per groom: whether it is simulated, the
//!   inverse joint, rest gravity, the field's placement), `sim.sdf` (the
//!   baked fields) and `sim.rest`.

pub mod chains;
pub mod field_cache;
pub mod follow;
pub mod grid;
pub mod pbd;
pub mod sdf;
pub mod upload;

#[cfg(test)]
mod tests;

use crate::kernel::Words;
use crate::layout::read;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// `sim.models` flag: the groom is simulated (`GroomDesc::simulate`).
pub const SIM_SIMULATE: u32 = 1;
/// `sim.models` flag: the groom has a collision field in `sim.sdf`.
pub const SIM_COLLIDER: u32 = 2;

/// `sim.models`: what the solver needs per groom beyond `models` (32 words).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct SimModel {
    /// Column-major world → groom local at this frame (`models.world`'s inverse).
    pub inv_world: [f32; 16],
    /// The direction that was down in the rest pose, in groom-local space
    /// (w unused): the rest shape is taken to balance gravity along it.
    pub rest_down: [f32; 4],
    /// The collision field's grid point (0, 0, 0) in groom-local space, and
    /// its spacing in w.
    pub sdf_min: [f32; 4],
    /// World units per local unit (the transform's uniform scale).
    pub scale: f32,
    /// [`SIM_SIMULATE`] | [`SIM_COLLIDER`].
    pub flags: u32,
    /// The strands of this groom in the numbering of the solver's
    /// `groom.strands`: the groom's strands for Kulikov's graph, its hair
    /// mesh's corner chains for Lipp's ([`chains`]).
    pub strand_first: u32,
    pub strand_count: u32,
    /// The velocity grid's cell (0, 0, 0) corner in groom-local space, and
    /// its cells per local unit in w ([`grid::placement`]).
    pub grid_min: [f32; 4],
}

/// `sim.state`: one record per vertex, kept between frames.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct SimVertex {
    /// World position; w is 1 once written (a History buffer starts at 0).
    pub position: [f32; 4],
    /// World velocity in metres per second; w: how near the head the
    /// vertex may come (its rest distance, at most the margin; local units).
    pub velocity: [f32; 4],
}

/// The groom whose range in `sims` (`sim.models`, in the pass's strand
/// numbering) holds strand `g`, and its record; `None` for a strand of no
/// groom's.
pub(crate) fn model_of(sims: &Words<'_>, model_count: u32, g: usize) -> Option<(usize, SimModel)> {
    (0..model_count as usize)
        .map(|m| (m, read::<SimModel>(sims, m)))
        .find(|(_, d)| {
            g >= d.strand_first as usize && g < (d.strand_first + d.strand_count) as usize
        })
}

/// `v / |v|` as the WGSL writes it (one reciprocal); zero for a zero vector.
pub(crate) fn normalize(v: Vec3) -> Vec3 {
    let len = v.dot(v).sqrt();
    if len > 0.0 {
        v * (1.0 / len)
    } else {
        Vec3::ZERO
    }
}
