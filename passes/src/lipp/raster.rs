//! `lipp.raster`: Lipp §3.1, one workgroup per strand (indirect dispatch
//! from `lipp.lod`): cooperative strand assembly (Appendix B, Code 1) and DDA
//! line rasterization into the 64-bit centre and conservative G-buffer
//! layers with 64-bit `atomicMin` (§3.1.2, payload in [`super::payload`]).
//!
//! Strand assembly, per Code 1, in two passes over the 32 lanes:
//! 1. lane i < L loads layer i at the strand's (u, v) and takes its
//!    finite-difference tangent from its neighbours' positions, which it gets
//!    with `subgroupShuffleUp/Down` (Code 1 lines 17-26); the layers go to
//!    workgroup memory (`smLayer`).
//! 2. the C control points are split into strips of S = ceil((C − 1) / 32)
//!    per lane; each lane evaluates its strip once (Hermite subdivision and
//!    styling), gets the previous lane's last point and the next lane's first
//!    point and first tangent by shuffles, computes final tangents by finite
//!    differences and draws its segments (Code 1 lines 31-50). With
//!    `strip_rounds` (ours, the default) a lane holds one point at a time
//!    and pass 2 runs in rounds of 32 segments, which keeps fewer
//!    registers live through the walk ([`RasterParams::strip_rounds`]).
//!
//! Where a neighbour lies in another subgroup (a subgroup narrower than the
//! 32-lane workgroup, e.g. lavapipe's 8), the lane evaluates the neighbour
//! itself; the result is the same bits, so the strand does not depend on the
//! subgroup width. `cooperative_assembly: false` is the naive baseline of
//! §3.1: every lane recomputes its neighbours instead of shuffling.
//!
//! Rasterization: each segment is projected, snapped to a 1/256-pixel grid
//! (docs/architecture.md) and walked column by column along its major
//! axis (a DDA). The conservative layer receives every pixel the segment
//! crosses; the centre layer only pixels whose centre is within
//! `centre_diameter / 2` of the line. Depth is tested against `scene.depth`
//! and, for every groom after the first, against `hair_depth`: the depth the
//! earlier grooms' filter passes wrote (Lipp §3.5, "strands occluded by
//! previously rendered grooms are rejected early").
//! "we rasterize them as single-pixel-wide lines" (§3.1.2).
//!
//! MSAA reference mode (Lipp §3.3: "recording samples into multiple layers
//! of a uint64 image and resolving them later ... only as a reference"):
//! with `msaa` N in {2, 4, 8}, layer s < N of the G-buffer holds sample s at
//! the Direct3D standard sample position of that count, written where the
//! segment passes within `centre_diameter / 2` of the sample point; there is
//! no conservative layer. The graph must size the G-buffer for N layers
//! (`scenes/graphs/lipp_msaa.ron`); samples beyond its layers are dropped.

use super::assemble::{Assembly, Strands, assemble};
use super::payload::{Sample, pack};
use super::strand::{ControlPoint, strand_uv};
use super::walk::Dda;
use super::{RASTER_GROUP, frame, mix, normalize, transform};
use crate::common::clip::{at, near_clip};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{CounterValues, Ctx, Words};
use crate::layout::FrameData;
use crate::params::{Invalid, PassParams};

/// Sub-pixel snap grid (as the Kulikov raster's `SNAP`).
pub const SNAP: f32 = 256.0;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RasterParams {
    pub cooperative_assembly: bool,
    pub styling: bool,
    /// Pixels; the centre-sample layer's acceptance diameter.
    pub centre_diameter: f32,
    pub conservative_layer: bool,
    /// MSAA reference mode: 2, 4 or 8 sample layers (0 or 1: off).
    pub msaa: u32,
    /// The groom this pass draws, in the graph's per-model block; grooms
    /// after the first also test `hair_depth`.
    pub model_index: u32,
    /// Ours: every sample of a segment stores the tangent at the segment's
    /// middle, packed once per segment, instead of the tangent interpolated
    /// to the sample and packed per sample. The octahedral tangent keeps 8
    /// bits per axis, which a segment of a 127-point strand rarely spans;
    /// measured on the H100 it takes most of the per-sample work and the
    /// registers that held both end tangents through the walk.
    pub segment_payload: bool,
    /// Ours: a segment is not walked when its nearer end lies behind the
    /// farthest scene depth of every 16×16 block its box, grown by a pixel,
    /// touches (`hiz`, from `kulikov.depth_downsample`; the test
    /// `kulikov.cull` makes). No sample of it could pass the depth test, so
    /// the G-buffer is the same. At close, on the CPU simulator at
    /// 1920×1080, 44,426 of 108,186 strands are behind the head and body
    /// in every segment, 37% of the pixels the walk visits.
    pub occlusion_cull: bool,
    /// Ours: a lane holds one of the strand's points at a time, and a
    /// strand of C points is assembled and drawn in ceil((C − 1) / 32)
    /// rounds of 32 segments ([`super::assemble::strip_rounds`]), where
    /// Code 1 gives each lane S = ceil((C − 1) / 32) points, up to 4, at
    /// once. Each entry point is compiled for its most points a lane, whose
    /// registers it holds through the walk, and a round carries nothing of
    /// the last one: it reads its bundle's record again and recomputes the
    /// strand's id and (u, v). On the H200 the raster takes 61 registers a
    /// lane instead of 80, and 32 of its workgroups fit on an SM (the most
    /// an SM holds) instead of 25. The same segments are drawn, so the
    /// G-buffer is the same.
    pub strip_rounds: bool,
}

impl Default for RasterParams {
    fn default() -> Self {
        Self {
            cooperative_assembly: true,
            styling: true,
            centre_diameter: 0.5,
            conservative_layer: true,
            msaa: 0,
            model_index: 0,
            segment_payload: true,
            occlusion_cull: true,
            strip_rounds: true,
        }
    }
}

impl RasterParams {
    /// Points a lane holds at most (`strip_rounds`).
    pub fn max_strip(&self) -> u32 {
        if self.strip_rounds { 1 } else { 4 }
    }
}

impl PassParams for RasterParams {
    const READS_MODEL_INDEX: bool = true;
    const VARIANT_ENTRIES: &'static [&'static str] = &[
        "raster_sample_payload",
        "raster_code1_strips",
        "raster_sample_payload_code1_strips",
    ];

    /// `segment_payload: false` is an entry point of its own: as a branch in
    /// one kernel, the per-sample side kept both end tangents live through
    /// the walk, 96 registers per lane against 80, and the raster took
    /// 2.69 ms instead of 2.40 at close on the H100. `strip_rounds: false`
    /// is one too, for the same reason.
    fn entry(&self, default: &'static str) -> &'static str {
        match (self.segment_payload, self.strip_rounds) {
            (true, true) => default,
            (false, true) => "raster_sample_payload",
            (true, false) => "raster_code1_strips",
            (false, false) => "raster_sample_payload_code1_strips",
        }
    }

    fn validate(&self) -> Result<(), Invalid> {
        if !(self.centre_diameter > 0.0 && self.centre_diameter <= 2.0) {
            return Err(Invalid::new(
                "centre_diameter",
                "expected a diameter in (0, 2] pixels",
            ));
        }
        if ![0, 1, 2, 4, 8].contains(&self.msaa) {
            return Err(Invalid::new(
                "msaa",
                "expected 0 or 1 (off), 2, 4 or 8 samples",
            ));
        }
        Ok(())
    }
}

crate::gpu_block! {
    /// `RasterParams` in shaders/lipp/raster.wgsl.
    pub struct RasterGpu {
        cooperative_assembly: u32,
        styling: u32,
        centre_diameter: f32,
        conservative_layer: u32,
        /// Scene quantities.
        bundles: u32,
        width: u32,
        height: u32,
        msaa: u32,
        model_index: u32,
        segment_payload: u32,
        occlusion_cull: u32,
        _pad: u32,
    }
}

pub static RASTER: PassKind<RasterParams, RasterGpu> = PassKind {
    kind: "lipp.raster",
    summary: "cooperative strand assembly (Code 1) and DDA line rasterization into centre and conservative 64-bit G-buffers",
    source: "Lipp §3.1, Appendix B Code 1",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("raster_args"),
        Binding::read("bundle_lod"),
        Binding::read("hairmesh.bundles"),
        Binding::read("hairmesh.layers"),
        Binding::read("scene.depth"),
        Binding::read("hair_depth"),
        Binding::atomic("gbuffer"),
        Binding::read("hiz"),
    ]),
    workgroup_size: RASTER_GROUP,
    dispatch: Dispatch::Indirect {
        binding: "raster_args",
        word: 0,
    },
    shader: Shader::compute("lipp/raster.wgsl", "raster"),
    kernel: |p| Box::new(RasterKernel(*p)),
    gpu: |p, q| RasterGpu {
        cooperative_assembly: flag(p.cooperative_assembly),
        styling: flag(p.styling),
        centre_diameter: p.centre_diameter,
        conservative_layer: flag(p.conservative_layer),
        bundles: count(q.bundles),
        width: q.width,
        height: q.height,
        msaa: p.msaa,
        model_index: p.model_index,
        segment_payload: flag(p.segment_payload),
        occlusion_cull: flag(p.occlusion_cull),
        ..RasterGpu::default()
    },
    raster: None,
};

struct RasterKernel(RasterParams);

/// A projected, snapped segment end with its attributes.
#[derive(Debug, Clone, Copy)]
struct End {
    x: f32,
    y: f32,
    z: f32,
    tangent: [f32; 3],
    w: f32,
    ao: f32,
}

/// Everything one workgroup writes with.
struct Target<'a> {
    f: &'a FrameData,
    width: u32,
    height: u32,
    depth: Words<'a>,
    /// Earlier grooms' depth, tested only after the first groom.
    hair_depth: Option<Words<'a>>,
    gbuffer: Words<'a>,
    /// The scene's Hi-Z, with `occlusion_cull`.
    hiz: Option<Words<'a>>,
    params: &'a RasterParams,
    uv: [f32; 2],
    /// The tangent every sample of the current segment stores
    /// (`segment_payload`); `None`: interpolated per sample.
    segment_tangent: Option<[f32; 3]>,
    local: &'a mut CounterValues,
}

fn snap(v: f32) -> f32 {
    (v * SNAP + 0.5).floor() / SNAP
}

impl Target<'_> {
    /// Segment (a, b)'s ends on screen: the part in front of the near plane,
    /// its attributes interpolated to a cut end.
    fn project(
        &self,
        a: &ControlPoint,
        ta: [f32; 3],
        b: &ControlPoint,
        tb: [f32; 3],
    ) -> Option<(End, End)> {
        let clip = |cp: &ControlPoint| {
            transform(&self.f.view_proj, [cp.pos[0], cp.pos[1], cp.pos[2], 1.0])
        };
        let part = near_clip(clip(a), clip(b), self.f.near)?;
        let end = |c: [f32; 4], t: f32| {
            let s = crate::kulikov::clip_to_screen(c, self.f.screen[0], self.f.screen[1]);
            End {
                x: snap(s[0]),
                y: snap(s[1]),
                z: s[2],
                tangent: [0, 1, 2].map(|k| at(ta[k], tb[k], t)),
                w: at(a.w, b.w, t),
                ao: at(a.ao, b.ao, t),
            }
        };
        Some((end(part.a, part.ta), end(part.b, part.tb)))
    }

    /// Writes into pixel (x, y) the sample at parameter `tc` of segment
    /// (a, b) to layer `layer` (if `centre`) and the conservative layer's
    /// sample at `tm` (if `cons`), both tested against one read of the
    /// scene's depth (and, after the first groom, `hair_depth`).
    fn write_pixel(
        &mut self,
        (a, b): (&End, &End),
        (x, y): (i32, i32),
        centre: Option<(f32, usize)>,
        cons: Option<f32>,
    ) {
        if x < 0 || y < 0 || x >= self.width as i32 || y >= self.height as i32 {
            return;
        }
        let pixel = (y as u32 * self.width + x as u32) as usize;
        let mut limit = self.depth.load_f32(pixel);
        if let Some(h) = &self.hair_depth {
            limit = limit.min(h.load_f32(pixel));
        }
        let samples = centre.into_iter().chain(cons.map(|tm| (tm, 1)));
        for (t, layer) in samples {
            let z = a.z + (b.z - a.z) * t;
            if (0.0..1.0).contains(&z) && z < limit {
                self.put(a, b, t, z, pixel, layer);
            }
        }
    }

    /// payload::pack of a depth-tested sample at `t`, `atomicMin` into its layer.
    fn put(&mut self, a: &End, b: &End, t: f32, z: f32, pixel: usize, layer: usize) {
        let sample = Sample {
            depth: z,
            tangent: self
                .segment_tangent
                .unwrap_or_else(|| normalize(mix(a.tangent, b.tangent, t))),
            uvw: [self.uv[0], self.uv[1], a.w + (b.w - a.w) * t],
            ao: a.ao + (b.ao - a.ao) * t,
        };
        let slot = layer * (self.width * self.height) as usize + pixel;
        self.gbuffer.fetch_min_u64(slot, pack(&sample));
        self.local.atomics += 1;
        self.local.pixels_written += 1;
    }

    /// MSAA reference mode: every sample of every pixel the segment touches
    /// within `centre_diameter / 2` of the segment goes to its sample layer.
    fn segment_msaa(&mut self, a: &End, b: &End, n: u32, layers: usize) {
        let samples = sample_positions(n);
        let half = self.params.centre_diameter * 0.5;
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let len2 = dx * dx + dy * dy;
        let mut pixels = Vec::new();
        walk_pixels(a, b, self.width, self.height, &mut |x, y| {
            pixels.push((x, y))
        });
        for (x, y) in pixels {
            for (s, o) in samples.iter().enumerate().take(layers) {
                let (px, py) = (x as f32 + 0.5 + o[0], y as f32 + 0.5 + o[1]);
                let t = if len2 > 0.0 {
                    (((px - a.x) * dx + (py - a.y) * dy) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let (ex, ey) = (a.x + dx * t - px, a.y + dy * t - py);
                if ex * ex + ey * ey <= half * half {
                    self.write_pixel((a, b), (x, y), Some((t, s)), None);
                }
            }
        }
    }

    /// DDA over the segment's major axis, one pixel column (or row) at a time.
    /// `occlusion_cull`: whether every pixel segment (a, b) can write lies
    /// behind the scene. The walk's rows reach a pixel past the segment's
    /// box (the centre rows around the line), hence the box grown by one.
    fn hidden(&self, hiz: &Words<'_>, a: &End, b: &End) -> bool {
        let (w, h) = (self.width, self.height);
        let clamp = |v: f32, size: u32| v.clamp(0.0, (size - 1) as f32) as u32;
        let bounds = [
            clamp(a.x.min(b.x) - 1.0, w),
            clamp(a.y.min(b.y) - 1.0, h),
            clamp(a.x.max(b.x) + 1.0, w),
            clamp(a.y.max(b.y) + 1.0, h),
        ];
        // A sample passes only nearer than the scene's depth, which is no
        // farther than its block's.
        crate::kulikov::depth_downsample::farthest(hiz, w, bounds)
            .is_some_and(|far| a.z.min(b.z) >= far)
    }

    fn segment(&mut self, a: &End, b: &End) {
        if let Some(hiz) = &self.hiz
            && self.hidden(hiz, a, b)
        {
            self.local.culled += 1;
            return;
        }
        self.segment_tangent = self
            .params
            .segment_payload
            .then(|| normalize(mix(a.tangent, b.tangent, 0.5)));
        if self.params.msaa > 1 {
            let layers = self.gbuffer.len_u64() / (self.width * self.height).max(1) as usize;
            self.segment_msaa(a, b, self.params.msaa, layers);
            return;
        }
        let dda = Dda::new([a.x, a.y], [b.x, b.y]);
        let Dda {
            ma, na, mb, dm, dn, ..
        } = dda;
        let half = self.params.centre_diameter * 0.5;
        // |cos| of the angle between the line and the major axis.
        let len = (dm * dm + dn * dn).sqrt();
        let cos = if len > 0.0 { dm.abs() / len } else { 1.0 };
        dda.columns(dda.limit(self.width, self.height), |col, t0, t1| {
            // Centre layer: the column centre within the segment (half-open,
            // so shared ends are drawn once), rows r and r + 1 around the line,
            // kept where the pixel centre is near it.
            let centre = col + 0.5;
            let (mut c_rows, mut tc, mut nc) = ((1, 0), 0.0, 0.0);
            if dm != 0.0 && centre >= ma.min(mb) && centre < ma.max(mb) {
                tc = (centre - ma) / dm;
                nc = na + dn * tc;
                let r = (nc - 0.5).floor() as i32;
                c_rows = (r, r + 1);
            }
            // Conservative layer: every row the segment touches in the column.
            let (r0, r1) = dda.rows(t0, t1);
            let cons_rows = if self.params.conservative_layer {
                (r0 as i32, r1 as i32)
            } else {
                (1, 0)
            };
            let tm = 0.5 * (t0 + t1);
            let inside = |(lo, hi): (i32, i32), row: i32| lo <= row && row <= hi;
            let (lo, hi) = column_rows(c_rows, cons_rows);
            for row in lo..=hi {
                let cen = inside(c_rows, row) && ((nc - (row as f32 + 0.5)) * cos).abs() <= half;
                let con = inside(cons_rows, row);
                if cen || con {
                    let pixel = dda.pixel(col as i32, row);
                    self.write_pixel((a, b), pixel, cen.then_some((tc, 0)), con.then_some(tm));
                }
            }
        });
    }
}

/// The rows a column visits: the union of the centre layer's and the
/// conservative layer's row ranges (each `(lo, hi)`, empty when lo > hi),
/// so that a pixel in both is read and tested once.
fn column_rows(centre: (i32, i32), cons: (i32, i32)) -> (i32, i32) {
    match (centre.0 <= centre.1, cons.0 <= cons.1) {
        (false, _) => cons,
        (true, false) => centre,
        (true, true) => (centre.0.min(cons.0), centre.1.max(cons.1)),
    }
}

/// Direct3D's standard sample positions for 2, 4 and 8 samples (Vulkan's
/// standard locations), in pixels from the pixel centre (1/16-pixel grid).
pub fn sample_positions(n: u32) -> Vec<[f32; 2]> {
    let unit = (1 << crate::hardware_raster::SUBPIXEL_BITS) as f32;
    crate::hardware_raster::standard_samples(n)
        .iter()
        .map(|o| [o[0] as f32 / unit, o[1] as f32 / unit])
        .collect()
}

/// The pixels a segment touches (the conservative walk), the major axis
/// clipped to the screen.
fn walk_pixels(a: &End, b: &End, width: u32, height: u32, visit: &mut dyn FnMut(i32, i32)) {
    let dda = Dda::new([a.x, a.y], [b.x, b.y]);
    dda.columns(dda.limit(width, height), |col, t0, t1| {
        dda.column_pixels(col, t0, t1, &mut *visit);
    });
}

impl CpuKernel for RasterKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let f = frame(ctx);
        let strands = Strands::load(ctx);
        let mut local = CounterValues::default();
        let mut target = Target {
            f: &f,
            width: ctx.quantities.width,
            height: ctx.quantities.height,
            depth: ctx.words("scene.depth"),
            hair_depth: (self.0.model_index > 0).then(|| ctx.words("hair_depth")),
            gbuffer: ctx.words("gbuffer"),
            hiz: self.0.occlusion_cull.then(|| ctx.words("hiz")),
            params: &self.0,
            uv: [0.0; 2],
            segment_tangent: None,
            local: &mut local,
        };
        let stride = ctx.workgroups.max(1);
        let opts = Assembly {
            max_strip: self.0.max_strip(),
            ..Assembly::new(ctx, self.0.cooperative_assembly, self.0.styling)
        };
        let mut s = group;
        while s < strands.total {
            let (lod, rec, k) = strands.strand(s);
            target.uv = strand_uv(k);
            let layers = &strands.layers;
            let (active, lanes) = assemble(layers, &rec, &lod, k, &opts, &mut |a, ta, b, tb| {
                if let Some((pa, pb)) = target.project(a, ta, b, tb) {
                    target.segment(&pa, &pb);
                }
            });
            target.local.active_lanes += active;
            target.local.total_lanes += lanes;
            s += stride;
        }
        if ctx.instrument {
            ctx.counters.add(&local);
        }
    }
}

#[cfg(test)]
#[path = "raster_tests.rs"]
pub(crate) mod tests;
