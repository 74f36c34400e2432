//! Hair-hair friction through a velocity grid (Petrovic, Henne, Anderson
//! 2005, "Volumetric Methods for Simulation and Rendering of Hair", §3):
//! each simulated vertex splats its velocity and a count into its groom's
//! voxel grid, and the solver pulls each vertex's velocity towards the
//! grid's average there, `v += f (v_grid − v)`, so neighbouring strands move
//! together as hair in contact does. Kulikov's simulation "outputs ...
//! density voxel grid" for hair collision; this is the velocity half of it
//! (the density half, splatted from the skinned positions, shadows the skin:
//! `kulikov.density`).
//!
//! - `sim.splat` / `sim.splat_chains`: one lane per strand (or bundle
//!   chain), every vertex the solver has written added to the cell it lies
//!   in: three velocity components and a count, as integers (fixed point,
//!   [`VELOCITY_SCALE`]), so the sums do not depend on the order of the
//!   atomics and every backend gets the same grid. A run of vertices in one
//!   cell is summed in the lane and added once (ours). It runs before the
//!   solver on last frame's state; a frame that resets the state splats
//!   nothing.
//! - The solver samples the grid trilinearly ([`sample`]): the weighted
//!   velocity sums over the weighted counts.
//!
//! The grid is [`RES`]³ cells in the groom's local space (it moves with
//! the head), a cube twice the groom's largest extent about its rest
//! bounds' centre ([`placement`]): hair swinging out stays inside. A vertex
//! outside adds nothing and feels no friction.

use super::chains::CORNERS;
use super::pbd::Simulated;
use super::{SimModel, model_of};
use crate::contract::flag;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::layout::{FrameData, read};
use crate::params::PassParams;
use glam::{Mat4, Vec3};
use strandgraph_assets::bounds::Aabb;
use strandgraph_graph::schema::Quantity;

/// Cells per side.
pub const RES: u32 = 32;
/// Words per groom: per cell, Σ velocity (x, y, z) and the count.
pub const GRID_WORDS: usize = (RES * RES * RES * 4) as usize;
/// Fixed-point units per metre per second of a splatted velocity.
pub const VELOCITY_SCALE: f32 = 4096.0;

const GROUP: u32 = 64;

/// The grid's cell (0, 0, 0) corner in groom-local space and its cells per
/// local unit (w), for a groom with rest bounds `b`.
pub fn placement(b: &Aabb) -> [f32; 4] {
    let (lo, hi) = (b.min, b.max);
    let side = 2.0 * (hi - lo).max_element().max(1e-3);
    let corner = (lo + hi) * 0.5 - Vec3::splat(side * 0.5);
    [corner.x, corner.y, corner.z, RES as f32 / side]
}

/// The cell holding groom-local point `q`; `None` outside the grid.
pub fn cell(grid_min: [f32; 4], q: Vec3) -> Option<usize> {
    let f = (q - Vec3::new(grid_min[0], grid_min[1], grid_min[2])) * grid_min[3];
    let inside = f.cmpge(Vec3::ZERO).all() && f.cmplt(Vec3::splat(RES as f32)).all();
    inside.then(|| {
        let i = f.as_uvec3();
        (i.x + RES * (i.y + RES * i.z)) as usize
    })
}

/// The grid's average velocity about groom-local `q`, trilinear over the
/// cell centres (clamped to the grid's border cells); `None` outside the
/// grid or where no vertex was splatted. `fetch(i)` reads word `i` of the
/// groom's grid.
pub fn sample(fetch: impl Fn(usize) -> u32, grid_min: [f32; 4], q: Vec3) -> Option<Vec3> {
    let f = (q - Vec3::new(grid_min[0], grid_min[1], grid_min[2])) * grid_min[3];
    let last = RES as f32;
    if !(f.x >= 0.0 && f.x < last && f.y >= 0.0 && f.y < last && f.z >= 0.0 && f.z < last) {
        return None;
    }
    let g = (f - Vec3::splat(0.5)).clamp(Vec3::ZERO, Vec3::splat(last - 1.0));
    let i = g.floor().min(Vec3::splat(last - 2.0));
    let t = g - i;
    let i = i.as_uvec3();
    let (mut velocity, mut weight) = (Vec3::ZERO, 0.0f32);
    for corner in 0..8u32 {
        let (dx, dy, dz) = (corner & 1, (corner >> 1) & 1, corner >> 2);
        let w = (if dx == 1 { t.x } else { 1.0 - t.x })
            * (if dy == 1 { t.y } else { 1.0 - t.y })
            * (if dz == 1 { t.z } else { 1.0 - t.z });
        let c = 4 * (i.x + dx + RES * (i.y + dy + RES * (i.z + dz))) as usize;
        let sum = Vec3::new(
            fetch(c) as i32 as f32,
            fetch(c + 1) as i32 as f32,
            fetch(c + 2) as i32 as f32,
        );
        velocity += sum * w;
        weight += fetch(c + 3) as f32 * w;
    }
    (weight > 0.0).then(|| velocity * (1.0 / (weight * VELOCITY_SCALE)))
}

/// The splat's bindings, under Kulikov's names (Lipp's graphs bind its
/// chains' buffers under them, as for the solver).
const BINDINGS: &[Binding] = &[
    Binding::read("frame"),
    Binding::read("sim.models"),
    Binding::read("groom.strands"),
    Binding::read("sim.state"),
    Binding::atomic("sim.grid"),
];

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SplatParams {
    /// Off, the grid stays empty and costs nothing: what a graph sets with
    /// the solver's `hair_friction: 0`, the grid's only reader.
    pub enabled: bool,
    /// The grooms whose strands are splatted: set it as the solver's
    /// `models` (its default too). The others' strands are skipped before
    /// any of their state is read; at the distance views, where no groom is
    /// simulated, that took the pass from 0.022 to 0.011 ms on the H100, on
    /// the frame's critical path. (Strands the solver has never written
    /// are skipped at their root as well, whatever this says.)
    pub models: Simulated,
}

impl Default for SplatParams {
    fn default() -> Self {
        Self {
            enabled: true,
            models: Simulated::Flagged,
        }
    }
}

impl PassParams for SplatParams {}

crate::gpu_block! {
    /// `SplatParams` in shaders/sim/splat.wgsl.
    pub struct SplatGpu {
        strands: u32,
        enabled: u32,
        /// 0 Flagged, 1 All, 2 None (`Simulated`).
        models: u32,
        _pad: u32,
    }
}

pub static SPLAT: PassKind<SplatParams, SplatGpu> = PassKind {
    kind: "sim.splat",
    summary: "velocity grid: each simulated vertex's velocity and a count, per groom",
    source: "Petrovic et al. 2005, §3 (hair-hair friction); Kulikov 2025, 'Simulation'",
    bindings: Some(BINDINGS),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Strands,
        per_group: GROUP,
    },
    shader: Shader::compute("sim/splat.wgsl", "splat"),
    kernel: |p| Box::new(SplatKernel(*p)),
    gpu: |p, q| SplatGpu {
        strands: count(q.strands),
        enabled: flag(p.enabled),
        models: p.models as u32,
        ..SplatGpu::default()
    },
    raster: None,
};

/// [`SPLAT`] over Lipp's bundle chains, four per bundle.
pub static SPLAT_CHAINS: PassKind<SplatParams, SplatGpu> = PassKind {
    kind: "sim.splat_chains",
    summary: "velocity grid of the simulated bundle chains, per groom",
    source: "Petrovic et al. 2005, §3 (hair-hair friction)",
    bindings: Some(BINDINGS),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Bundles,
        per_group: GROUP / CORNERS,
    },
    shader: Shader::compute("sim/splat.wgsl", "splat"),
    kernel: |p| Box::new(SplatKernel(*p)),
    gpu: |p, q| SplatGpu {
        strands: CORNERS * count(q.bundles),
        enabled: flag(p.enabled),
        models: p.models as u32,
        ..SplatGpu::default()
    },
    raster: None,
};

struct SplatKernel(SplatParams);

/// Metres per second as the grid's fixed point (nearest, halves up, as
/// the WGSL's `floor(x + 0.5)`), saturating far beyond any hair's speed.
fn fixed(v: f32) -> u32 {
    (v * VELOCITY_SCALE + 0.5).floor().clamp(-1e9, 1e9) as i32 as u32
}

impl CpuKernel for SplatKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let frame: FrameData = read(&ctx.words("frame"), 0);
        if !self.0.enabled || frame.sim_reset != 0 {
            return;
        }
        let (sims, strands, state, grid) = (
            ctx.words("sim.models"),
            ctx.words("groom.strands"),
            ctx.words("sim.state"),
            ctx.words("sim.grid"),
        );
        for lane in 0..GROUP {
            let g = (group * GROUP + lane) as usize;
            if g >= strands.len() / 2 {
                break;
            }
            let Some((m, sim)) = model_of(&sims, frame.model_count, g) else {
                continue;
            };
            if !self.0.models.includes(sim.flags) {
                continue;
            }
            let (first, n) = (
                strands.load(2 * g) as usize,
                strands.load(2 * g + 1) as usize,
            );
            splat_strand(&state, &grid, m * GRID_WORDS, &sim, first, n);
        }
    }
}

/// Adds the written vertices `first..first + n` of `state` to the grid at
/// `base`. Consecutive vertices of a strand often share a cell: a lane sums
/// them and adds once per run (the sums are integers, so this changes no
/// result, only how many atomics contend for a cell).
fn splat_strand(
    state: &Words<'_>,
    grid: &Words<'_>,
    base: usize,
    sim: &SimModel,
    first: usize,
    n: usize,
) {
    // A strand the solver has never written (its groom is not simulated)
    // is skipped at its root.
    if n == 0 || state.load_vec4(2 * first)[3] == 0.0 {
        return;
    }
    let inv_world = Mat4::from_cols_array(&sim.inv_world);
    let flush = |run: Option<(usize, [u32; 4])>| {
        if let Some((c, sum)) = run {
            for (k, v) in sum.into_iter().enumerate() {
                grid.fetch_add(base + 4 * c + k, v);
            }
        }
    };
    let mut run: Option<(usize, [u32; 4])> = None;
    for v in first..first + n {
        let x = state.load_vec4(2 * v);
        let q = inv_world.transform_point3(Vec3::new(x[0], x[1], x[2]));
        let cell = (x[3] != 0.0).then(|| cell(sim.grid_min, q)).flatten();
        let Some(c) = cell else {
            continue;
        };
        let u = state.load_vec4(2 * v + 1);
        let add = [fixed(u[0]), fixed(u[1]), fixed(u[2]), 1];
        match &mut run {
            Some((rc, sum)) if *rc == c => {
                for (s, a) in sum.iter_mut().zip(add) {
                    *s = s.wrapping_add(a);
                }
            }
            _ => {
                flush(run.take());
                run = Some((c, add));
            }
        }
    }
    flush(run);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A uniform flow is returned as it is, anywhere inside; an empty grid
    /// or a point outside gives nothing.
    #[test]
    fn the_grid_averages_what_was_splatted() {
        let b = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        let grid_min = placement(&b);
        let mut words = vec![0u32; GRID_WORDS];
        let flow = Vec3::new(0.5, -1.25, 2.0);
        for c in 0..GRID_WORDS / 4 {
            for k in 0..3 {
                words[4 * c + k] = fixed(flow[k] * 3.0);
            }
            words[4 * c + 3] = 3;
        }
        for q in [Vec3::splat(0.5), Vec3::new(-0.4, 1.4, 0.01)] {
            let v = sample(|i| words[i], grid_min, q).unwrap();
            assert!(v.distance(flow) < 1e-3, "{q}: {v}");
        }
        assert!(sample(|i| words[i], grid_min, Vec3::splat(9.0)).is_none());
        assert!(sample(|_| 0, grid_min, Vec3::splat(0.5)).is_none());
        assert_eq!(cell(grid_min, Vec3::splat(-0.5)), Some(0));
        assert_eq!(cell(grid_min, Vec3::splat(-0.6)), None);
    }
}
