//! `sim.pbd`: one lane per strand, every vertex simulated ("Every strand and
//! every strand vertex is simulated", Kulikov), by dynamic follow-the-leader
//! (Müller, Kim, Chentanez 2012, "Fast Simulation of Inextensible Hair and
//! Fur", Algorithm 1). Per substep and vertex, root to tip:
//!
//! 1. predict: `v += a Δt`, hair-hair friction `v += f (v_grid − v)` from
//!    the velocity grid ([`super::grid`], Petrovic et al. 2005), `p = x + v Δt`
//!    (the root is pinned to where the head joint carries its rest position);
//! 2. ours, TressFX's global shape constraint: `p += k (rest_now − p)`, so a
//!    styled groom returns to its style (`shape_stiffness`; 0 is Müller's
//!    pure FTL, under which hair only hangs);
//! 3. FTL (Müller §4): `p_i = p_{i−1} + l_i (p_i − p_{i−1}) / |p_i − p_{i−1}|`;
//! 4. head collision: a vertex nearer the head's SDF than it was at rest (or
//!    than `collision_margin`) is pushed out along the gradient and put back
//!    on the FTL sphere, up to `collision_iterations` times (4), each push
//!    longer; one still inside the head after that is pushed to its surface
//!    (or its rest depth, for one inside at rest), giving up a little length
//!    (Kulikov: "Prebuilt SDFs for head collisions");
//! 5. velocity with Müller's damping correction (§4.2, Eq. 9):
//!    `v_i = (p_i − x_i) / Δt − s_damping d_{i+1} / Δt`, `d` the correction
//!    FTL gave the next vertex; then friction on contact and air damping.
//!
//! The vertex loop is a stream: vertex i's velocity waits for d_{i+1}, so a
//! lane holds one vertex back and nothing else.
//!
//! Gravity: with `gravity_preload` (ours) the rest shape counts as balanced
//! under the rest pose's gravity, and the solver applies the difference
//! `g (down − R_joint · down_rest)`: a still head keeps its groom exactly,
//! a tilted one swings it. Off, full gravity pulls the style down.

use super::chains::CORNERS;
use super::grid;
use super::sdf::{FIELD_WORDS, sample};
use super::{SIM_COLLIDER, SIM_SIMULATE, SimModel, model_of, normalize};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::layout::{FrameData, ModelData, read};
use crate::params::{Invalid, PassParams, in_range, non_negative};
use glam::{Mat4, Vec3};
use strandgraph_graph::schema::Quantity;

const GROUP: u32 = 64;

crate::string_enum! {
    /// Which grooms the pass simulates; the others are copied unchanged.
    pub enum Simulated { Flagged, All, None }
}

impl Simulated {
    /// Whether a groom with `SimModel::flags` `flags` is simulated.
    pub fn includes(self, flags: u32) -> bool {
        match self {
            Simulated::Flagged => flags & SIM_SIMULATE != 0,
            Simulated::All => true,
            Simulated::None => false,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct PbdParams {
    /// `Flagged`: the grooms the scene marks `simulate: true` (Kulikov:
    /// "Enabled per asset by artists"); `All`; `None`.
    pub models: Simulated,
    /// Solver steps per frame.
    pub substeps: u32,
    /// Metres per second squared, along world −y.
    pub gravity: f32,
    /// Ours: the rest shape balances gravity along the rest pose's down.
    pub gravity_preload: bool,
    /// Müller's s_damping (Eq. 9): 1 is his "exact" PBD velocity, 0 plain FTL.
    pub ftl_damping: f32,
    /// Air drag: the fraction of velocity lost per second.
    pub damping: f32,
    /// Ours (TressFX's global shape constraint): the pull towards the
    /// skinned rest shape per substep, 0..=1.
    pub shape_stiffness: f32,
    /// Metres a vertex keeps from the head (less where it was nearer at rest).
    pub collision_margin: f32,
    /// The fraction of tangential velocity a contact removes.
    pub friction: f32,
    /// Hair-hair friction (Petrovic et al. 2005): the pull of a vertex's
    /// velocity towards the velocity grid's average there, per substep,
    /// 0..=1; 0 ignores the grid.
    pub hair_friction: f32,
    /// Collision iterations per vertex and substep: alternations of the
    /// push out of the head and the FTL projection, each push reaching
    /// further (step 4).
    pub collision_iterations: u32,
}

impl Default for PbdParams {
    fn default() -> Self {
        Self {
            models: Simulated::Flagged,
            substeps: 2,
            gravity: 9.81,
            gravity_preload: true,
            ftl_damping: 0.9,
            damping: 1.0,
            shape_stiffness: 0.04,
            collision_margin: 0.002,
            friction: 0.3,
            hair_friction: 0.1,
            collision_iterations: 4,
        }
    }
}

impl PassParams for PbdParams {
    fn validate(&self) -> Result<(), Invalid> {
        in_range("substeps", self.substeps, 1..=64)?;
        in_range("collision_iterations", self.collision_iterations, 1..=16)?;
        for (name, v) in [
            ("ftl_damping", self.ftl_damping),
            ("shape_stiffness", self.shape_stiffness),
            ("friction", self.friction),
            ("hair_friction", self.hair_friction),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(Invalid::new(name, format!("{v} is outside 0..=1")));
            }
        }
        non_negative("damping", self.damping)?;
        non_negative("collision_margin", self.collision_margin)?;
        if !self.gravity.is_finite() {
            return Err(Invalid::new("gravity", "must be finite"));
        }
        Ok(())
    }
}

crate::gpu_block! {
    /// `PbdParams` in shaders/sim/pbd.wgsl.
    pub struct PbdGpu {
        models: u32,
        substeps: u32,
        gravity: f32,
        gravity_preload: u32,
        ftl_damping: f32,
        damping: f32,
        shape_stiffness: f32,
        collision_margin: f32,
        friction: f32,
        strands: u32,
        hair_friction: f32,
        collision_iterations: u32,
    }
}

/// What the solver binds, under the names of Kulikov's graph; Lipp's binds
/// its chains' buffers under them (`as`).
const BINDINGS: &[Binding] = &[
    Binding::read("frame"),
    Binding::read("models"),
    Binding::read("sim.models"),
    Binding::read("sim.sdf"),
    Binding::read("sim.rest"),
    Binding::read("groom.strands"),
    Binding::write("sim.state"),
    Binding::write("groom.vertices"),
    Binding::read("sim.grid"),
];

/// The uniform block for `strands` strands.
fn gpu(p: &PbdParams, strands: u32) -> PbdGpu {
    PbdGpu {
        models: p.models as u32,
        substeps: p.substeps,
        gravity: p.gravity,
        gravity_preload: flag(p.gravity_preload),
        ftl_damping: p.ftl_damping,
        damping: p.damping,
        shape_stiffness: p.shape_stiffness,
        collision_margin: p.collision_margin,
        friction: p.friction,
        hair_friction: p.hair_friction,
        collision_iterations: p.collision_iterations,
        strands,
    }
}

pub static PBD: PassKind<PbdParams, PbdGpu> = PassKind {
    kind: "sim.pbd",
    summary: "PBD hair: dynamic follow-the-leader with damping correction, gravity, head joint, SDF collisions, friction",
    source: "Kulikov 2025, 'Simulation'; Müller et al. 2012",
    bindings: Some(BINDINGS),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Strands,
        per_group: GROUP,
    },
    shader: Shader::compute("sim/pbd.wgsl", "pbd"),
    kernel: |p| Box::new(PbdKernel(*p)),
    gpu: |p, q| gpu(p, count(q.strands)),
    raster: None,
};

/// The same solver on Lipp's hair meshes: its strands are the bundles'
/// corner chains ([`super::chains`]), four per bundle, so a dispatch
/// covers bundles rather than strands.
pub static PBD_CHAINS: PassKind<PbdParams, PbdGpu> = PassKind {
    kind: "sim.pbd_chains",
    summary: "sim.pbd on hair-mesh bundles: each bundle's four corner chains simulated as strands",
    source: "Kulikov 2025, 'Simulation'; Müller et al. 2012; Lipp et al. §2 (bundle layers)",
    bindings: Some(BINDINGS),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Bundles,
        per_group: GROUP / CORNERS,
    },
    shader: Shader::compute("sim/pbd.wgsl", "pbd"),
    kernel: |p| Box::new(PbdKernel(*p)),
    gpu: |p, q| gpu(p, CORNERS * count(q.bundles)),
    raster: None,
};

struct PbdKernel(PbdParams);

fn v3(v: [f32; 4]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

/// What one lane needs about its groom this frame.
struct Strand<'a> {
    world: Mat4,
    sim: SimModel,
    sdf: &'a Words<'a>,
    sdf_base: usize,
    grid: &'a Words<'a>,
    grid_base: usize,
    rest: &'a Words<'a>,
    state: &'a Words<'a>,
    first: usize,
}

impl Strand<'_> {
    fn rest_local(&self, v: usize) -> Vec3 {
        v3(self.rest.load_vec4(self.first + v))
    }
    fn local(&self, p: Vec3) -> Vec3 {
        Mat4::from_cols_array(&self.sim.inv_world).transform_point3(p)
    }
    fn field(&self, q: Vec3) -> Option<(f32, [f32; 3])> {
        if self.sim.flags & SIM_COLLIDER == 0 {
            return None;
        }
        let fetch = |i: usize| self.sdf.load_f32(self.sdf_base + i);
        sample(fetch, self.sim.sdf_min, q.to_array())
    }
    /// The velocity grid's average about world point `x` (hair-hair friction).
    fn flow(&self, x: Vec3) -> Option<Vec3> {
        let fetch = |i: usize| self.grid.load(self.grid_base + i);
        grid::sample(fetch, self.sim.grid_min, self.local(x))
    }
    /// Position, velocity and collision threshold of vertex `v`.
    fn load(&self, v: usize) -> (Vec3, Vec3, f32) {
        let i = 2 * (self.first + v);
        let u = self.state.load_vec4(i + 1);
        (v3(self.state.load_vec4(i)), v3(u), u[3])
    }
    fn store(&self, v: usize, x: Vec3, u: Vec3, limit: f32) {
        let i = 2 * (self.first + v);
        self.state.store_vec4(i, [x.x, x.y, x.z, 1.0]);
        self.state.store_vec4(i + 1, [u.x, u.y, u.z, limit]);
    }

    /// Step 4: `p` pushed out of the head to `threshold` (local units), and
    /// the world contact normal; `None` when it is clear.
    fn collide(&self, p: Vec3, threshold: f32, reach: f32) -> Option<(Vec3, Vec3)> {
        let q = self.local(p);
        let (d, g) = self.field(q)?;
        if !(d < threshold) {
            return None;
        }
        let n = normalize(Vec3::from(g));
        if n == Vec3::ZERO {
            return None;
        }
        let pushed = self
            .world
            .transform_point3(q + n * ((threshold - d) * reach));
        Some((pushed, normalize(self.world.transform_vector3(n))))
    }

    /// How near the head vertex `v` may come: its distance at rest, at most
    /// `margin` (local units); negative for a vertex inside the head at rest
    /// (a hair mesh's corner near the scalp), which may stay as deep.
    /// Computed when the state starts and kept in its velocity's w, as it
    /// never changes.
    fn threshold(&self, v: usize, margin: f32) -> f32 {
        self.field(self.rest_local(v))
            .map_or(0.0, |(d, _)| d)
            .min(margin)
    }
}

/// The pending vertex of the stream: its position at the start and the end
/// of the substep, its contact normal and collision threshold.
struct Held {
    v: usize,
    x: Vec3,
    p: Vec3,
    contact: Option<Vec3>,
    /// Its collision threshold ([`Strand::threshold`]).
    limit: f32,
}

impl PbdKernel {
    /// Step 5 for the held vertex, `d_next` the correction of the one after it.
    fn release(&self, s: &Strand<'_>, h: &Held, d_next: Vec3, dt: f32) {
        let p = &self.0;
        let inv_dt = 1.0 / dt;
        let mut u = (h.p - h.x) * inv_dt - d_next * (p.ftl_damping * inv_dt);
        if let Some(n) = h.contact {
            let un = u.dot(n);
            let tangential = u - n * un;
            u = tangential * (1.0 - p.friction) + n * un.max(0.0);
        }
        u *= (1.0 - p.damping * dt).max(0.0);
        s.store(h.v, h.p, u, h.limit);
    }

    /// One substep of strand `s` with `count` vertices.
    fn substep(&self, s: &Strand<'_>, count: usize, dt: f32, accel: Vec3) {
        let p = &self.0;
        let root = s.world.transform_point3(s.rest_local(0));
        let (x0, _, _) = s.load(0);
        let mut held = Held {
            v: 0,
            x: x0,
            p: root,
            contact: None,
            limit: 0.0,
        };
        for v in 1..count {
            let (x, u, limit) = s.load(v);
            let mut u = u + accel * dt;
            // Hair-hair friction (Petrovic et al. 2005, §3).
            if p.hair_friction > 0.0
                && let Some(flow) = s.flow(x)
            {
                u += (flow - u) * p.hair_friction;
            }
            let mut q = x + u * dt;
            let rest_now = s.world.transform_point3(s.rest_local(v));
            q += (rest_now - q) * p.shape_stiffness;
            let length = (s.rest_local(v) - s.rest_local(v - 1)).length() * s.sim.scale;
            let ftl = |q: Vec3| held.p + normalize(q - held.p) * length;
            let mut fixed = ftl(q);
            let mut contact = None;
            // Out of the head and back on the FTL sphere, alternately, each
            // push reaching further (a vertex wedged in a crease, under the
            // jaw, escapes along the sphere); what the last projection
            // leaves inside is pushed out regardless.
            for pass in 0..p.collision_iterations {
                let reach = (pass + 1) as f32;
                let Some((pushed, n)) = s.collide(fixed, limit, reach) else {
                    break;
                };
                fixed = ftl(pushed);
                contact = Some(n);
            }
            if let Some((pushed, n)) = s.collide(fixed, limit.min(0.0), 1.0) {
                fixed = pushed;
                contact = Some(n);
            }
            let d = fixed - q;
            self.release(s, &held, d, dt);
            held = Held {
                v,
                x,
                p: fixed,
                contact,
                limit,
            };
        }
        self.release(s, &held, Vec3::ZERO, dt);
    }
}

impl CpuKernel for PbdKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let frame: FrameData = read(&ctx.words("frame"), 0);
        let (models, sims, sdf, grid) = (
            ctx.words("models"),
            ctx.words("sim.models"),
            ctx.words("sim.sdf"),
            ctx.words("sim.grid"),
        );
        let (rest, strands, state, out) = (
            ctx.words("sim.rest"),
            ctx.words("groom.strands"),
            ctx.words("sim.state"),
            ctx.words("groom.vertices"),
        );
        let total = strands.len() / 2;
        for lane in 0..GROUP {
            let g = (group * GROUP + lane) as usize;
            if g >= total {
                break;
            }
            let Some((m, sim)) = model_of(&sims, frame.model_count, g) else {
                continue;
            };
            let model: ModelData = read(&models, m);
            // The others keep their rest pose in `groom.vertices`.
            if !self.0.models.includes(sim.flags) {
                continue;
            }
            let (first, count) = (
                strands.load(2 * g) as usize,
                strands.load(2 * g + 1) as usize,
            );
            let s = Strand {
                world: Mat4::from_cols_array(&model.world),
                sim,
                sdf: &sdf,
                sdf_base: m * FIELD_WORDS,
                grid: &grid,
                grid_base: m * grid::GRID_WORDS,
                rest: &rest,
                state: &state,
                first,
            };
            self.strand(&s, count, &frame);
            for v in 0..count {
                let (x, _, _) = s.load(v);
                let l = s.local(x);
                out.store_vec4(first + v, [l.x, l.y, l.z, rest.load_vec4(first + v)[3]]);
            }
        }
    }
}

impl PbdKernel {
    /// A frame of strand `s`: reset when asked (or never written), then the substeps.
    fn strand(&self, s: &Strand<'_>, count: usize, frame: &FrameData) {
        let fresh = s.state.load_vec4(2 * s.first)[3] == 0.0;
        if frame.sim_reset != 0 || fresh {
            let margin = self.0.collision_margin * (1.0 / s.sim.scale);
            for v in 0..count {
                let x = s.world.transform_point3(s.rest_local(v));
                s.store(v, x, Vec3::ZERO, s.threshold(v, margin));
            }
        }
        if !(frame.delta_time > 0.0) {
            return;
        }
        let p = &self.0;
        let down = Vec3::NEG_Y;
        let preload = if p.gravity_preload {
            normalize(s.world.transform_vector3(v3(s.sim.rest_down)))
        } else {
            Vec3::ZERO
        };
        let accel = (down - preload) * p.gravity;
        let dt = frame.delta_time * (1.0 / p.substeps as f32);
        for _ in 0..p.substeps {
            self.substep(s, count, dt, accel);
        }
    }
}
