//! `hw_strands.mesh`: the mesh-shader path of the hardware baseline, the
//! pipeline shape of Bhokare et al. 2024 that Lipp Table 1 measures against
//! (`shaders/hw_strands/mesh.wgsl`, VK_EXT_mesh_shader).
//!
//! - One task workgroup per hair-mesh bundle applies the bundle's LOD (the
//!   N_LOD strands of C control points `lipp.lod` chose, none when culled):
//!   it launches one mesh workgroup per strand and chunk of
//!   [`MESH_SEGMENTS`] segments.
//! - Each mesh workgroup (32 lanes) assembles its strand with Lipp Code 1,
//!   as `hw_strands.assemble` does, projects every control point and emits
//!   its chunk's segments as the quads `hw_strands.raster` draws (4
//!   vertices and 2 triangles each, `CORNERS` as indices). Nothing goes
//!   through memory between strand generation and rasterization.
//! - The fragment shader is `hw_strands.raster`'s (`hw_strands/quad.wgsl`):
//!   the same G-buffer layers, tests and payloads, so between
//!   `scenes/graphs/hw_strands.ron` and `hw_mesh.ron` only the geometry
//!   path differs.
//!
//! Deviations from Bhokare et al.: their task shader computes the LOD
//! itself; here `lipp.lod` computes it (the same formula, Lipp Eq. 1-5) so
//! every pipeline draws the same strands, and the task shader applies it.
//! A strand of more than [`MESH_SEGMENTS`] segments is split over mesh
//! workgroups, each assembling the whole strand and emitting its part
//! (an output is at most 256 vertices on the devices we target).
//!
//! The CPU kernel does the task and mesh stages' work in its prologue
//! (every bundle's kept strands, assembled by the same code, in launch
//! order) and rasterizes the quads with `hw_strands.raster`'s kernel.

use super::Segment;
use super::assemble::strand_segments;
use super::raster::{BANDS, QuadRaster, RasterParams, quads};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::lipp::assemble::{Assembly, Strands};
use crate::lipp::{BundleLod, BundleRecord, frame};
use crate::params::{Invalid, PassParams};
use crate::raster_state::{Geometry, RasterState};
use rayon::prelude::*;
use std::sync::RwLock;
use strandgraph_graph::Quantities;

/// Segments per mesh workgroup: 4 vertices and 2 triangles each, so 256
/// vertices and 128 triangles, within VK_EXT_mesh_shader's guaranteed
/// minimum of 256 for `maxMeshOutputVertices` and `maxMeshOutputPrimitives`.
pub const MESH_SEGMENTS: u32 = 64;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct MeshParams {
    /// Quad width in pixels (as `hw_strands.raster`'s).
    pub width: f32,
    /// The groom drawn, in the graph's per-model block.
    pub model_index: u32,
    /// Lipp Code 1's subgroup shuffles (as `hw_strands.assemble`'s switch).
    pub cooperative_assembly: bool,
    /// Curl, twist and noise (as `hw_strands.assemble`'s switch).
    pub styling: bool,
}

impl Default for MeshParams {
    fn default() -> Self {
        let raster = RasterParams::default();
        Self {
            width: raster.width,
            model_index: raster.model_index,
            cooperative_assembly: true,
            styling: true,
        }
    }
}

impl MeshParams {
    fn raster(&self) -> RasterParams {
        RasterParams {
            width: self.width,
            model_index: self.model_index,
        }
    }
}

impl PassParams for MeshParams {
    const READS_MODEL_INDEX: bool = true;

    fn validate(&self) -> Result<(), Invalid> {
        self.raster().validate()
    }
}

crate::gpu_block! {
    /// `MeshParams` in shaders/hw_strands/mesh.wgsl.
    pub struct MeshGpu {
        width_px: f32,
        width: u32,
        height: u32,
        model_index: u32,
        cooperative_assembly: u32,
        styling: u32,
        bundles: u32,
        _pad0: u32,
    }
}

pub static MESH: PassKind<MeshParams, MeshGpu> = PassKind {
    kind: "hw_strands.mesh",
    summary: "strands generated in mesh shaders (a task workgroup per bundle applying its LOD) and drawn as camera-facing quads at the attachment's MSAA",
    source: "Bhokare et al. 2024's mesh-shader pipeline via Lipp Table 1; Lipp §3.1.1 Code 1 (the strands)",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("raster_args"),
        Binding::read("bundle_lod"),
        Binding::read("hairmesh.bundles"),
        Binding::read("hairmesh.layers"),
        Binding::read("scene.depth"),
        Binding::read("hair_depth"),
        Binding::atomic("gbuffer"),
        Binding::write("strand_depth"),
    ]),
    workgroup_size: 1,
    dispatch: Dispatch::Fixed(BANDS),
    shader: Shader {
        file: "hw_strands/mesh.wgsl",
        entry: "ms_main",
        fragment: Some("fs_main"),
    },
    kernel: |p| Box::new(MeshKernel::new(*p)),
    gpu: |p, q| MeshGpu {
        width_px: p.width,
        width: q.width,
        height: q.height,
        model_index: p.model_index,
        cooperative_assembly: flag(p.cooperative_assembly),
        styling: flag(p.styling),
        bundles: count(q.bundles),
        ..MeshGpu::default()
    },
    raster: Some(draw),
};

/// One task workgroup per bundle.
fn draw(_: &MeshParams, q: &Quantities) -> RasterState {
    quads(Geometry::MeshTasks {
        task: "ts_main",
        groups: q.bundles,
    })
}

struct MeshKernel {
    p: MeshParams,
    quads: QuadRaster,
    /// The segments the mesh workgroups emitted this frame, in launch order.
    segments: RwLock<Vec<Segment>>,
}

impl MeshKernel {
    fn new(p: MeshParams) -> Self {
        Self {
            p,
            quads: QuadRaster::new(p.raster()),
            segments: RwLock::new(Vec::new()),
        }
    }

    /// The task and mesh stages: bundle by bundle, the strands its LOD
    /// keeps (none past `raster_args`' total, as the mesh shader checks),
    /// each assembled and projected into segments.
    fn generate(&self, ctx: &Ctx<'_>) -> Vec<Segment> {
        let view_proj = frame(ctx).view_proj;
        let strands = Strands::load(ctx);
        let opts = Assembly::new(ctx, self.p.cooperative_assembly, self.p.styling);
        // Launch order: bundle by bundle, strand by strand.
        // Only the drawn groom's bundles have this frame's records.
        strands
            .range
            .clone()
            .into_par_iter()
            .flat_map_iter(|b| {
                let lod = BundleLod::load(&strands.lods, b);
                let rec = BundleRecord::load(&strands.bundles, b);
                let mut out = Vec::new();
                let kept = (0..lod.strands).take_while(|k| lod.first_strand + k < strands.total);
                for k in kept {
                    let strand = (&lod, &rec, k);
                    strand_segments(&strands, &opts, &view_proj, strand, &mut |s| out.push(s));
                }
                out
            })
            .collect()
    }
}

impl CpuKernel for MeshKernel {
    fn prologue(&self, ctx: &Ctx<'_>) {
        let segments = self.generate(ctx);
        self.quads.bin(ctx, segments.len(), |i| segments[i]);
        *self.segments.write().unwrap_or_else(|e| e.into_inner()) = segments;
    }

    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let segments = self.segments.read().unwrap_or_else(|e| e.into_inner());
        self.quads.draw_band(group, ctx, |i| segments[i]);
    }
}
