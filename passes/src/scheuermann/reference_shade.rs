//! `scheuermann.reference_shade`: Scheuermann 2004's shading
//! ([`hair_lighting`], the parameters of `scheuermann.hair`'s stages) at
//! every vertex of the groom's own strands, into `vertex_lighting` for
//! `reference.resolve` to interpolate (scenes/graphs/scheuermann_reference.ron,
//! docs/reference.md).
//!
//! What a patch vertex carries, each strand vertex gets from
//! `scheuermann.strand_shading` (passes/src/scheuermann/upload.rs): the
//! outward normal and ambient occlusion baked as for patches, and the
//! texture column of one of the hair texture's strands, sampled at level 0
//! at the vertex's place along the strand. The tangent is the strand's own
//! (central difference). Alpha is the geometry's: the ribbons' coverage.

use super::hair::{HairGpu, HairParams, Stage, gpu_block};
use super::shading::{Surface, hair_lighting};
use super::texture::sample_level;
use super::upload::STRAND_SHADING_WORDS;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::kulikov::debug_resolve::store_rgba16f;
use crate::layout::{FrameData, LightData, ModelData, read};
use glam::{Vec2, Vec3, Vec4Swizzles};
use strandgraph_assets::octahedral::unpack_unit_vector;
use strandgraph_graph::schema::Quantity;

pub const SHADE_LANES: u32 = 256;

pub static REFERENCE_SHADE: PassKind<HairParams, HairGpu> = PassKind {
    kind: "scheuermann.reference_shade",
    summary: "Scheuermann's shading (two shifted Kajiya-Kay highlights, tweaked diffuse, baked AO) at every vertex of the ground truth's strands",
    source: "Scheuermann 2004, 'Hair Lighting', at strand vertices for the ground-truth reference (docs/reference.md)",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("lights"),
        Binding::read("groom.vertices"),
        Binding::read("scheuermann.strand_shading"),
        Binding::read("patches.texture"),
        Binding::write("vertex_lighting"),
    ]),
    workgroup_size: SHADE_LANES,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Vertices,
        per_group: SHADE_LANES,
    },
    shader: Shader::compute("scheuermann/reference_shade.wgsl", "reference_shade"),
    kernel: |p| Box::new(ShadeKernel(*p)),
    gpu: |p, q| gpu_block(Stage::Opaque, p, q),
    raster: None,
};

/// The model vertex `v` belongs to: the last one (with strands) starting at
/// or before it.
fn model_of(models: &[ModelData], v: u32) -> usize {
    (1..models.len())
        .rev()
        .find(|&k| models[k].vertex_first <= v && models[k].strand_count > 0)
        .unwrap_or(0)
}

struct ShadeKernel(HairParams);

impl CpuKernel for ShadeKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let f: FrameData = read(&ctx.words("frame"), 0);
        let mw = ctx.words("models");
        let models: Vec<ModelData> = (0..mw.len() / 64).map(|i| read(&mw, i)).collect();
        if models.is_empty() {
            return;
        }
        let lw = ctx.words("lights");
        let stored = lw.len() / (std::mem::size_of::<LightData>() / 4);
        let lights: Vec<LightData> = (0..(f.light_count as usize).min(stored))
            .map(|i| read(&lw, i))
            .collect();
        let (verts, inputs) = (
            ctx.words("groom.vertices"),
            ctx.words("scheuermann.strand_shading"),
        );
        let texture = ctx.words("patches.texture");
        let fetch = |i: usize| texture.load(i);
        let out = ctx.words("vertex_lighting");
        let count = (verts.len() / 4).min(inputs.len() / STRAND_SHADING_WORDS) as u32;
        let camera = Vec3::from_slice(&f.camera_pos[..3]);
        let shading = self.0.shading();
        let first = group * SHADE_LANES;
        for v in first..(first + SHADE_LANES).min(count) {
            let m = model_of(&models, v);
            let model = &models[m];
            let world_of = |v: u32| {
                let p = Vec3::new(
                    verts.load_f32(4 * v as usize),
                    verts.load_f32(4 * v as usize + 1),
                    verts.load_f32(4 * v as usize + 2),
                );
                glam::Mat4::from_cols_array(&model.world).transform_point3(p)
            };
            let n = model.points_per_strand.max(2);
            let i = (v - model.vertex_first) % n;
            let before = world_of(v - i.min(1));
            let after = world_of(if i + 1 >= n { v } else { v + 1 });
            let w = STRAND_SHADING_WORDS * v as usize;
            let uv = Vec2::new(inputs.load_f32(w + 2), inputs.load_f32(w + 3));
            let tex = sample_level(&fetch, 0, uv);
            let at = Surface {
                world: world_of(v),
                tangent: after - before,
                normal: unpack_unit_vector(inputs.load(w)),
                ao: inputs.load_f32(w + 1),
            };
            let c = Vec3::from_slice(&model.color[..3]);
            let lit = hair_lighting(&shading, &at, tex, c, camera, &lights).xyz();
            store_rgba16f(&out, v as usize, [lit.x, lit.y, lit.z, 1.0]);
        }
    }
}
