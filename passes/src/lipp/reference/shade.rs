//! `lipp.reference_shade`: `lipp.shade`'s shading ([`shade_point`], the
//! same parameters) at every control point `lipp.reference_strands` wrote,
//! into `vertex_lighting` for `reference.resolve` to interpolate. Each
//! point's material is its strand's groom (the point record's model), where
//! `lipp.shade` is run once per groom.

use super::super::{ARGS_ALL, ARGS_KEPT};
use super::{PointRecord, SLOTS};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::kulikov::debug_resolve::store_rgba16f;
use crate::layout::{LightData, ModelData, read};
use crate::lipp::frame;
use crate::lipp::shade::{
    Inputs, Point, ShadeGpu, ShadeParams, depth_correction, shade_gpu, shade_point,
};
use strandgraph_graph::schema::Quantity;

/// Lanes of a workgroup, and the point slots it shades: 16 strands' worth,
/// so a dispatch stays under 65,535 workgroups up to a million strands.
pub const SHADE_LANES: u32 = 256;
pub const SLOTS_PER_GROUP: u32 = 16 * SLOTS;

pub static SHADE: PassKind<ShadeParams, ShadeGpu> = PassKind {
    kind: "lipp.reference_shade",
    summary: "Lipp's shading (Chiang lobes, DOM shadows, probe lighting) at every control point of the ground truth's strands",
    source: "Lipp §3.4, at strand points for the ground-truth reference (docs/reference.md)",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("lights"),
        Binding::read("env.sh"),
        Binding::read("reference_points"),
        Binding::read("raster_args"),
        Binding::read("dom_depth"),
        Binding::read("dom_layers"),
        Binding::write("vertex_lighting"),
        Binding::read("env.prefiltered"),
    ]),
    workgroup_size: SHADE_LANES,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::MeshStrands,
        per_group: SLOTS_PER_GROUP / SLOTS,
    },
    shader: Shader::compute("lipp/reference_shade.wgsl", "reference_shade"),
    kernel: |p| Box::new(ShadeKernel(*p)),
    gpu: |p, q| shade_gpu(p, q, count(q.mesh_strands).saturating_mul(SLOTS)),
    raster: None,
};

struct ShadeKernel(ShadeParams);

impl CpuKernel for ShadeKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let f = frame(ctx);
        let mw = ctx.words("models");
        let models: Vec<ModelData> = (0..mw.len() / 64).map(|i| read(&mw, i)).collect();
        let Some(first_model) = models.first() else {
            return;
        };
        let lw = ctx.words("lights");
        let lights: Vec<LightData> = (0..f.light_count as usize).map(|i| read(&lw, i)).collect();
        let args = ctx.words("raster_args");
        let delta = if self.0.lod_depth_correction {
            depth_correction(args.load(ARGS_KEPT), args.load(ARGS_ALL))
        } else {
            0.0
        };
        let inp = Inputs::load(ctx, &f, first_model, &lights, &self.0, delta);
        let (points, out) = (ctx.words("reference_points"), ctx.words("vertex_lighting"));
        let slots = (ctx.quantities.mesh_strands * u64::from(SLOTS)).min(out.len() as u64 / 2);
        let first = u64::from(group * SLOTS_PER_GROUP);
        for slot in first..(first + u64::from(SLOTS_PER_GROUP)).min(slots) {
            let Some(p) = PointRecord::load(&points, slot as usize) else {
                continue;
            };
            let point = Point {
                pos: p.pos,
                tangent: p.tangent,
                strand: p.strand,
                ao: p.ao,
            };
            let model = &models[(p.model as usize).min(models.len() - 1)];
            let c = shade_point(&inp, model, &point);
            store_rgba16f(&out, slot as usize, [c[0], c[1], c[2], 1.0]);
        }
    }
}
