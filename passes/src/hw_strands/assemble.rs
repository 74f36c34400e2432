//! `hw_strands.assemble`: the strands `lipp.raster` draws, assembled by the
//! same code (Lipp Code 1: one 32-lane workgroup per strand the LOD keeps,
//! indirect over `raster_args`), projected once per control point and
//! written as [`Segment`] records for the hardware rasterizer.
//!
//! The first lane reserves the strand's C − 1 records with one `atomicAdd`
//! on the indirect draw's vertex count (six per segment), so a strand's
//! records are contiguous and the draw spans exactly those written; the
//! first workgroup sets the instance count to 1. Which strand gets which
//! records depends on the order workgroups run; the G-buffer's
//! `atomicMin` does not (early depth tests may drop a fragment that a
//! different draw order would keep at one sample: see [`super::raster`]).

use super::{MAX_SEGMENTS, SEGMENT_WORDS, Segment, VERTICES_PER_SEGMENT};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::layout::FrameData;
use crate::lipp::assemble::{Assembly, Strands, assemble};
use crate::lipp::payload::quantize;
use crate::lipp::strand::{ControlPoint, strand_uv};
use crate::lipp::{
    BundleLod, BundleRecord, RASTER_GROUP, frame, mix, normalize, oct_encode, transform,
};
use crate::params::{Invalid, PassParams};
use glam::Vec4;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct AssembleParams {
    /// Lipp Code 1's subgroup shuffles (as `lipp.raster`'s switch).
    pub cooperative_assembly: bool,
    /// Curl, twist and noise (as `lipp.raster`'s switch).
    pub styling: bool,
}

impl Default for AssembleParams {
    fn default() -> Self {
        Self {
            cooperative_assembly: true,
            styling: true,
        }
    }
}

impl PassParams for AssembleParams {
    fn validate(&self) -> Result<(), Invalid> {
        Ok(())
    }
}

crate::gpu_block! {
    /// `AssembleParams` in shaders/hw_strands/assemble.wgsl.
    pub struct AssembleGpu {
        cooperative_assembly: u32,
        styling: u32,
        bundles: u32,
        capacity: u32,
    }
}

/// Records `hw_segments` must hold: every strand of every hair mesh at the
/// most control points the LOD allows.
pub fn capacity(mesh_strands: u64) -> u64 {
    mesh_strands * u64::from(MAX_SEGMENTS)
}

pub static ASSEMBLE: PassKind<AssembleParams, AssembleGpu> = PassKind {
    kind: "hw_strands.assemble",
    summary: "Lipp's cooperative strand assembly, projected once per control point into segment records and an indirect draw",
    source: "Lipp §3.1.1, Appendix B Code 1 (the strands); Bhokare et al. 2024 via Lipp Table 1 (the baseline)",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("raster_args"),
        Binding::read("bundle_lod"),
        Binding::read("hairmesh.bundles"),
        Binding::read("hairmesh.layers"),
        Binding::write("hw_segments"),
        Binding::atomic("hw_draw_args"),
    ]),
    workgroup_size: RASTER_GROUP,
    dispatch: Dispatch::Indirect {
        binding: "raster_args",
        word: 0,
    },
    shader: Shader::compute("hw_strands/assemble.wgsl", "assemble"),
    kernel: |p| Box::new(AssembleKernel(*p)),
    gpu: |p, q| AssembleGpu {
        cooperative_assembly: flag(p.cooperative_assembly),
        styling: flag(p.styling),
        bundles: count(q.bundles),
        capacity: count(capacity(q.mesh_strands)),
    },
    raster: None,
};

struct AssembleKernel(AssembleParams);

/// Strand `k` of bundle `rec` (LOD `lod`) assembled by Lipp Code 1 and
/// projected: `emit` receives its segments in order. Shared with
/// `hw_strands.mesh`, whose mesh shaders emit the same segments as quads.
pub(super) fn strand_segments(
    strands: &Strands<'_>,
    opts: &Assembly,
    view_proj: &[f32; 16],
    (lod, rec, k): (&BundleLod, &BundleRecord, u32),
    emit: &mut dyn FnMut(Segment),
) {
    let uv = strand_uv(k);
    assemble(&strands.layers, rec, lod, k, opts, &mut |a, ta, b, tb| {
        emit(record(view_proj, (a, ta), (b, tb), uv));
    });
}

/// The record of segment (a, b) with end tangents ta, tb (the WGSL's
/// `write_segment`): the tangent at the middle, packed once per segment
/// as `lipp.raster` packs it with `segment_payload` on.
fn record(
    view_proj: &[f32; 16],
    (a, ta): (&ControlPoint, [f32; 3]),
    (b, tb): (&ControlPoint, [f32; 3]),
    uv: [f32; 2],
) -> Segment {
    // lipp.raster's projection, operation for operation (the WGSL's transform).
    let clip = |p: [f32; 3]| Vec4::from_array(transform(view_proj, [p[0], p[1], p[2], 1.0]));
    let e = oct_encode(normalize(mix(ta, tb, 0.5)));
    Segment {
        a: clip(a.pos),
        b: clip(b.pos),
        bits_a: (quantize(e[1] * 0.5 + 0.5, 255.0) << 24)
            | (quantize(uv[0], 63.0) << 18)
            | (quantize(uv[1], 63.0) << 12)
            | (quantize(a.w, 63.0) << 6)
            | quantize(a.ao, 63.0),
        bits_b: quantize(e[0] * 0.5 + 0.5, 255.0)
            | (quantize(b.w, 63.0) << 8)
            | (quantize(b.ao, 63.0) << 14),
    }
}

fn store(out: &Words<'_>, r: usize, s: &Segment) {
    for (k, w) in s.words().into_iter().enumerate() {
        out.store(r * SEGMENT_WORDS + k, w);
    }
}

impl CpuKernel for AssembleKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let f: FrameData = frame(ctx);
        let view_proj = f.view_proj;
        let strands = Strands::load(ctx);
        let (out, args) = (ctx.words("hw_segments"), ctx.words("hw_draw_args"));
        let capacity = out.len() / SEGMENT_WORDS;
        if group == 0 {
            args.fetch_max(1, 1);
        }
        let opts = Assembly::new(ctx, self.0.cooperative_assembly, self.0.styling);
        let mut s = group;
        while s < strands.total {
            let (lod, rec, k) = strands.strand(s);
            let c = lod.control_points.clamp(2, crate::lipp::MAX_CONTROL_POINTS);
            let first = args.fetch_add(0, (c - 1) * VERTICES_PER_SEGMENT) / VERTICES_PER_SEGMENT;
            let mut next = first as usize;
            let strand = (&lod, &rec, k);
            strand_segments(&strands, &opts, &view_proj, strand, &mut |segment| {
                if next < capacity {
                    store(&out, next, &segment);
                }
                next += 1;
            });
            s += ctx.workgroups.max(1);
        }
    }
}
