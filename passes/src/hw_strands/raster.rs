//! `hw_strands.raster`: the segment records of [`super::assemble`] drawn by
//! the hardware rasterizer (`shaders/hw_strands/raster.wgsl`), one
//! camera-facing quad per segment ([`quad_corner`]), six vertices pulled
//! from storage per segment, an indirect draw whose count the assembly
//! wrote.
//!
//! The draw rasterizes at the depth attachment's sample count (the graph's
//! `strand_depth.samples`: MSAA 1, 4, 8) with early depth tests (`Less`,
//! writes on) against the head (`scene.depth_attachment`) and the strands
//! drawn before. The fragment shader runs once per covered sample that
//! passes (sample-rate shading, `@builtin(sample_index)`), tests the
//! sample's depth as `lipp.raster` does (against `scene.depth`, and after
//! the first groom `hair_depth`) and writes its payload into the sample's
//! G-buffer layer with 64-bit `atomicMin`: Lipp's MSAA reference layout,
//! which `lipp.shade` and `lipp.filter` (its `msaa` set to the same count)
//! resolve. The nearest strand at each sample wins whatever the draw order.
//!
//! Deviation: a hardware MSAA pipeline shades once per pixel and reads the
//! coverage from `SampleMask`, but naga 30 declares that input as a scalar
//! where Vulkan requires an array (VUID-SampleMask-SampleMask-04359;
//! gfx-rs/wgpu#7311), which drivers may misread. Shading per sample is
//! valid everywhere; at MSAA 1 it is the same thing, at 4 and 8 it runs
//! more fragment invocations than a per-pixel shader would (bench notes
//! say so). The CPU kernel emulates it ([`Band::fragment`]) with
//! [`crate::hardware_raster`] at the standard sample locations.

use super::{CORNERS, SEGMENT_WORDS, Segment, VERTICES_PER_SEGMENT, quad_corner};
use crate::common::clip::near_clip;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::hardware_raster::{SampledFragment, Setup, standard_samples};
use crate::kernel::{CounterValues, Ctx, Words};
use crate::layout::{FrameData, read};
use crate::params::{Invalid, PassParams};
use crate::raster_state::{
    Blend, ColorLoad, Compare, Cull, DepthLoad, Draw, Geometry, IndirectDraw, RasterState,
};
use glam::{Vec2, Vec4};
use std::sync::RwLock;
use strandgraph_graph::Quantities;

/// Bands of rows the CPU kernel rasterizes in parallel.
pub(super) const BANDS: u32 = 64;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RasterParams {
    /// Quad width in pixels: `lipp.raster`'s `centre_diameter`, the width
    /// its MSAA reference mode draws strands at.
    pub width: f32,
    /// The groom drawn, in the graph's per-model block; grooms after the
    /// first also test `hair_depth` (Lipp §3.5).
    pub model_index: u32,
}

impl Default for RasterParams {
    fn default() -> Self {
        Self {
            width: 0.5,
            model_index: 0,
        }
    }
}

impl PassParams for RasterParams {
    const READS_MODEL_INDEX: bool = true;

    fn validate(&self) -> Result<(), Invalid> {
        if !(self.width > 0.0 && self.width <= 4.0) {
            return Err(Invalid::new("width", "expected a width in (0, 4] pixels"));
        }
        Ok(())
    }
}

crate::gpu_block! {
    /// `RasterParams` in shaders/hw_strands/raster.wgsl.
    pub struct RasterGpu {
        width_px: f32,
        width: u32,
        height: u32,
        model_index: u32,
        capacity: u32,
        _pad0: u32,
        _pad1: u32,
        _pad2: u32,
    }
}

pub static RASTER: PassKind<RasterParams, RasterGpu> = PassKind {
    kind: "hw_strands.raster",
    summary: "segments drawn by the hardware rasterizer as camera-facing quads at the attachment's MSAA, each covered sample into its G-buffer layer",
    source: "Lipp Table 1's hardware baseline (Bhokare et al. 2024), into Lipp §3.3's MSAA G-buffer layout",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("hw_segments"),
        Binding::read("hw_draw_args"),
        Binding::read("scene.depth"),
        Binding::read("hair_depth"),
        Binding::atomic("gbuffer"),
        Binding::write("strand_depth"),
    ]),
    workgroup_size: 1,
    dispatch: Dispatch::Fixed(BANDS),
    shader: Shader {
        file: "hw_strands/raster.wgsl",
        entry: "vs_main",
        fragment: Some("fs_main"),
    },
    kernel: |p| Box::new(RasterKernel(QuadRaster::new(*p))),
    gpu: |p, q| RasterGpu {
        width_px: p.width,
        width: q.width,
        height: q.height,
        model_index: p.model_index,
        capacity: crate::contract::count(super::assemble::capacity(q.mesh_strands)),
        ..RasterGpu::default()
    },
    raster: Some(draw),
};

/// An indirect draw of the assembled segments, early depth tests, no colour.
fn draw(_: &RasterParams, _: &Quantities) -> RasterState {
    quads(Geometry::Indirect(IndirectDraw {
        binding: "hw_draw_args",
        word: 0,
    }))
}

/// `geometry` drawn as quads: early depth tests, no colour (shared with
/// `hw_strands.mesh`).
pub(super) fn quads(geometry: Geometry) -> RasterState {
    RasterState {
        geometry,
        cull: Cull::None,
        color_load: ColorLoad::Load,
        depth_load: DepthLoad::Load,
        draws: vec![Draw {
            fragment: "fs_main",
            blend: Blend::Replace,
            color_writes: false,
            depth_compare: Compare::Less,
            depth_write: true,
        }],
    }
}

/// A triangle of a segment's quad, set up, with its corners' `t`.
struct Triangle {
    setup: Setup,
    t: [f32; 3],
    segment: Segment,
}

struct RasterKernel(QuadRaster);

impl CpuKernel for RasterKernel {
    fn prologue(&self, ctx: &Ctx<'_>) {
        let (records, args) = (ctx.words("hw_segments"), ctx.words("hw_draw_args"));
        let count = (args.load(0) / VERTICES_PER_SEGMENT) as usize;
        let count = count.min(records.len() / SEGMENT_WORDS);
        self.0.bin(ctx, count, |i| load_segment(&records, i));
    }

    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let records = ctx.words("hw_segments");
        self.0.draw_band(group, ctx, |i| load_segment(&records, i));
    }
}

/// The hardware rasterizer's work on the CPU, shared with `hw_strands.mesh`:
/// the quads of segments `0..count` (fetched by index), drawn in index order
/// in [`BANDS`] bands of rows.
pub(super) struct QuadRaster {
    p: RasterParams,
    /// Per band of rows, the segments whose quads may reach it, in draw
    /// order: the prologue's work, redone every frame. Bands set their
    /// segments' triangles up themselves (a close view has tens of millions).
    bands: RwLock<Vec<Vec<u32>>>,
}

impl QuadRaster {
    pub(super) fn new(p: RasterParams) -> Self {
        Self {
            p,
            bands: RwLock::new(Vec::new()),
        }
    }

    fn view(&self, ctx: &Ctx<'_>) -> View {
        let f: FrameData = read(&ctx.words("frame"), 0);
        View {
            near: f.near,
            half: 0.5 * self.p.width,
            width: ctx.quantities.width,
            height: ctx.quantities.height,
        }
    }

    /// The prologue: which bands each of segments `0..count` may reach.
    pub(super) fn bin(
        &self,
        ctx: &Ctx<'_>,
        count: usize,
        segment: impl Fn(usize) -> Segment + Sync,
    ) {
        use rayon::prelude::*;
        let view = self.view(ctx);
        let rows: Vec<Option<(u32, u32)>> = (0..count)
            .into_par_iter()
            .map(|i| view.rows(&segment(i)))
            .collect();
        let per_band = view.height.div_ceil(BANDS).max(1);
        let mut bands = vec![Vec::new(); BANDS as usize];
        for (i, r) in rows.iter().enumerate() {
            if let Some((y0, y1)) = r {
                for band in &mut bands[(y0 / per_band) as usize..=(y1 / per_band) as usize] {
                    band.push(i as u32);
                }
            }
        }
        *self.bands.write().unwrap_or_else(|e| e.into_inner()) = bands;
    }

    /// Workgroup `group`: its band's rows of every binned quad.
    pub(super) fn draw_band(&self, group: u32, ctx: &Ctx<'_>, segment: impl Fn(usize) -> Segment) {
        let bands = self.bands.read().unwrap_or_else(|e| e.into_inner());
        let view = self.view(ctx);
        let rows = view.height.div_ceil(BANDS);
        let (first, last) = (group * rows, ((group + 1) * rows).min(view.height));
        let Some(list) = bands.get(group as usize) else {
            return;
        };
        if first >= last {
            return;
        }
        let band = Band::load(ctx, &self.p);
        let samples = standard_samples(band.samples);
        let mut counters = CounterValues::default();
        for &i in list {
            for tri in view.triangles(&segment(i as usize)) {
                tri.setup.rasterize_samples(first, last - 1, &samples, |f| {
                    band.fragment(&tri, &f, &mut counters);
                });
            }
        }
        if ctx.instrument {
            ctx.counters.add(&counters);
        }
    }
}

/// What the vertex stage and primitive setup need.
struct View {
    near: f32,
    half: f32,
    width: u32,
    height: u32,
}

impl View {
    /// Segment `s`'s two triangles (the vertex shader, then setup): the quad
    /// of its part in front of the near plane, as `lipp.raster` draws it.
    fn triangles(&self, s: &Segment) -> impl Iterator<Item = Triangle> + '_ {
        let part = near_clip(s.a.to_array(), s.b.to_array(), self.near);
        let size = Vec2::new(self.width as f32, self.height as f32);
        let s = *s;
        CORNERS.chunks(3).filter_map(move |tri| {
            let part = part?;
            let (a, b) = (Vec4::from_array(part.a), Vec4::from_array(part.b));
            let clip: [Vec4; 3] = [0, 1, 2].map(|k| quad_corner(a, b, tri[k], self.half, size));
            let setup = Setup::from_clip_multisampled(
                clip,
                self.near,
                self.width,
                self.height,
                Cull::None,
            )?;
            Some(Triangle {
                setup,
                t: [0, 1, 2].map(|k| if tri[k] & 1 != 0 { part.tb } else { part.ta }),
                segment: s,
            })
        })
    }

    /// The rows segment `s`'s quad may reach: its clipped ends' rows, `half`
    /// a pixel and one row of margin either side.
    fn rows(&self, s: &Segment) -> Option<(u32, u32)> {
        let part = near_clip(s.a.to_array(), s.b.to_array(), self.near)?;
        let y = |c: [f32; 4]| (0.5 - c[1] / c[3] * 0.5) * self.height as f32;
        let (ya, yb) = (y(part.a), y(part.b));
        let (lo, hi) = (ya.min(yb), ya.max(yb));
        let margin = self.half + 1.0;
        if !(hi + margin >= 0.0 && lo - margin < self.height as f32) {
            return None;
        }
        let clamp = |v: f32| v.clamp(0.0, (self.height - 1) as f32) as u32;
        Some((clamp(lo - margin), clamp(hi + margin)))
    }
}

fn load_segment(records: &Words<'_>, i: usize) -> Segment {
    let words: [u32; SEGMENT_WORDS] = std::array::from_fn(|k| records.load(i * SEGMENT_WORDS + k));
    Segment::from_words(&words)
}

/// What every fragment of a band reads and writes.
struct Band<'a> {
    scene_depth: Words<'a>,
    hair_depth: Option<Words<'a>>,
    gbuffer: Words<'a>,
    /// The attachment, `samples` words per pixel.
    depth: Words<'a>,
    samples: u32,
    layers: usize,
    width: u32,
    pixels: usize,
}

impl<'a> Band<'a> {
    fn load(ctx: &Ctx<'a>, p: &RasterParams) -> Self {
        let q = &ctx.quantities;
        let pixels = q.width as usize * q.height as usize;
        let depth = ctx.words("strand_depth");
        let gbuffer = ctx.words("gbuffer");
        Self {
            scene_depth: ctx.words("scene.depth"),
            hair_depth: (p.model_index > 0).then(|| ctx.words("hair_depth")),
            layers: (gbuffer.len_u64() / pixels.max(1)).min(8),
            gbuffer,
            samples: (depth.len() / pixels.max(1)).clamp(1, 8) as u32,
            depth,
            width: q.width,
            pixels,
        }
    }

    /// Per covered sample: the early depth test and depth write, then the
    /// sample-rate fragment shader where the sample passed.
    fn fragment(&self, tri: &Triangle, f: &SampledFragment, counters: &mut CounterValues) {
        let i = f.y as usize * self.width as usize + f.x as usize;
        let n = self.samples as usize;
        for s in (0..n).filter(|s| f.mask & (1 << s) != 0) {
            let z = f.depth[s];
            // Depth clipping, then the test (Less) and the write.
            if !((0.0..=1.0).contains(&z) && z < self.depth.load_f32(i * n + s)) {
                continue;
            }
            self.depth.store_f32(i * n + s, z);
            counters.pixels_written += 1;
            if z >= 1.0 || z >= self.scene_depth.load_f32(i) || s >= self.layers {
                continue;
            }
            if self.hair_depth.as_ref().is_some_and(|d| z >= d.load_f32(i)) {
                continue;
            }
            // `@interpolate(linear, sample)`: screen-space barycentrics.
            let t = (0..3).map(|k| f.screen[s][k] * tri.t[k]).sum::<f32>();
            let payload = tri.segment.payload(t.clamp(0.0, 1.0), z);
            self.gbuffer.fetch_min_u64(s * self.pixels + i, payload);
            counters.atomics += 1;
        }
    }
}
