//! `sim.follow_layers`: the simulated bundle chains ([`super::chains`])
//! written back into Lipp's `hairmesh.layers`, so the strands generated
//! inside each bundle (Lipp Eq. 1) follow the simulation.
//!
//! One lane per layer of a bundle (16 lanes a bundle, four bundles a
//! workgroup). Each of the layer's four corners takes:
//! - its position: the chain point, groom local, carried to world space by
//!   this frame's `models.world` (as `lipp::upload::pack` places layers);
//! - its tangent: the rest tangent turned by the rotation that takes the
//!   chain's rest direction at the point (central differences) to its
//!   simulated one, then to world space. A chain at rest turns nothing, so
//!   a groom the solver leaves alone draws exactly as uploaded;
//! - its ambient occlusion and uvw.w: kept.
//!
//! Every bundle is written, simulated or not: the pass reads only the
//! chains and the rest data, never the layers it writes, so nothing drifts
//! between frames whatever the uploads skip.

use super::chains::{CORNERS, POINTS, REST, TANGENTS};
use super::normalize;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::layout::{ModelData, read};
use crate::lipp::{BundleRecord, LAYER_WORDS, MAX_LAYERS, bundle_count};
use crate::params::NoParams;
use glam::{Mat3, Mat4, Vec3};
use strandgraph_graph::schema::Quantity;

const GROUP: u32 = 64;
/// Bundles per workgroup: a lane per layer.
const BUNDLES_PER_GROUP: u32 = GROUP / MAX_LAYERS;

crate::gpu_block! {
    /// `FollowParams` in shaders/sim/follow.wgsl.
    pub struct FollowGpu {
        bundles: u32,
        _pad0: u32,
        _pad1: u32,
        _pad2: u32,
    }
}

pub static FOLLOW: PassKind<NoParams, FollowGpu> = PassKind {
    kind: "sim.follow_layers",
    summary: "hair-mesh layers from the simulated bundle chains: corners moved, tangents turned",
    source: "Lipp et al. §2 (bundle layers); ours (the chains' write-back)",
    bindings: Some(&[
        Binding::read("models"),
        Binding::read("hairmesh.bundles"),
        Binding::read(POINTS),
        Binding::read(REST),
        Binding::read(TANGENTS),
        Binding::write("hairmesh.layers"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Bundles,
        per_group: BUNDLES_PER_GROUP,
    },
    shader: Shader::compute("sim/follow.wgsl", "follow"),
    kernel: |_| Box::new(FollowKernel),
    gpu: |_, q| FollowGpu {
        bundles: count(q.bundles),
        ..FollowGpu::default()
    },
    raster: None,
};

struct FollowKernel;

/// `t` turned by the rotation taking unit `a` to unit `b` (Rodrigues with
/// `v = a × b`, `c = a · b`); unturned when either is zero or they oppose.
pub fn turn(t: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let c = a.dot(b);
    if a == Vec3::ZERO || b == Vec3::ZERO || c <= -0.9999 {
        return t;
    }
    let v = a.cross(b);
    t * c + v.cross(t) + v * (v.dot(t) * (1.0 / (1.0 + c)))
}

/// The chain's direction at point `l` of `n`: central differences, one-sided at the ends.
fn direction(points: &Words<'_>, first: usize, l: usize, n: usize) -> Vec3 {
    let at = |i: usize| {
        let p = points.load_vec4(first + i);
        Vec3::new(p[0], p[1], p[2])
    };
    normalize(at((l + 1).min(n - 1)) - at(l.saturating_sub(1)))
}

impl CpuKernel for FollowKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let (models, bundles, layers) = (
            ctx.words("models"),
            ctx.words("hairmesh.bundles"),
            ctx.words("hairmesh.layers"),
        );
        let (points, rest, tangents) = (ctx.words(POINTS), ctx.words(REST), ctx.words(TANGENTS));
        for lane in 0..GROUP {
            let b = (group * BUNDLES_PER_GROUP + lane / MAX_LAYERS) as usize;
            let l = (lane % MAX_LAYERS) as usize;
            if b >= bundle_count(ctx) {
                break;
            }
            let rec = BundleRecord::load(&bundles, b);
            let n = rec.layer_count as usize;
            if l >= n {
                continue;
            }
            let model: ModelData = read(&models, rec.model as usize);
            let world = Mat4::from_cols_array(&model.world);
            let normal = Mat3::from_mat4(world);
            let layer = rec.first_layer as usize + l;
            for c in 0..CORNERS as usize {
                let first = CORNERS as usize * rec.first_layer as usize + c * n;
                let p = points.load_vec4(first + l);
                let t = tangents.load_vec4(first + l);
                let t = turn(
                    Vec3::new(t[0], t[1], t[2]),
                    direction(&rest, first, l, n),
                    direction(&points, first, l, n),
                );
                let p = world.transform_point3(Vec3::new(p[0], p[1], p[2]));
                let t = normalize(normal * t);
                let o = layer * LAYER_WORDS + c * 8;
                for (i, v) in [p.x, p.y, p.z].into_iter().enumerate() {
                    layers.store_f32(o + i, v);
                }
                for (i, v) in [t.x, t.y, t.z].into_iter().enumerate() {
                    layers.store_f32(o + 4 + i, v);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::turn;
    use glam::Vec3;

    #[test]
    fn turn_is_the_rotation_between_directions() {
        let t = Vec3::new(0.3, 0.4, 0.5);
        assert_eq!(turn(t, Vec3::X, Vec3::X), t);
        let r = turn(Vec3::Y, Vec3::X, Vec3::Y);
        assert!(r.distance(-Vec3::X) < 1e-6, "{r}");
        let r = turn(Vec3::Z, Vec3::X, Vec3::Y);
        assert!(r.distance(Vec3::Z) < 1e-6, "{r}");
        assert_eq!(turn(t, Vec3::ZERO, Vec3::Y), t);
    }
}
