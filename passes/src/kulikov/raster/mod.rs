//! `kulikov.raster`: the conservative software rasterizer into the tiled
//! visibility atlas.
//!
//! Kulikov, "Rasterization" and "Visibility buffer": each lane takes one
//! segment, rasterizes it as a trapezoid, depth-tests every covered pixel
//! against the scene depth and writes a 32-bit payload (10-bit depth | 22-bit
//! segment) into 3 ordered layers with chained `atomicMin`, plus additive
//! coverage with `atomicAdd(coverage * 1024)`.
//!
//! Switches (pass parameters), so the talk's ablations can be measured:
//! - `loop_flattening`: one loop over all pixels instead of nested x/y loops;
//! - `last_layer_cull`: skip the layer atomics when the (non-atomic) last layer
//!   already holds something nearer ("up to 50%");
//! - `morton_sort`: order the workgroup's segments along a Morton curve;
//! - `pixel_request_stack`, `depth_test_stack`: the LDS request stacks.
//!
//! None of them changes which writes happen. The CPU kernel executes the
//! WGSL's control structure for every setting (which lane takes which
//! segment, the per-lane loops in lock step, the stacks and their drain:
//! [`order`], [`lanes`], [`stacks`]), so the instrumented lane utilisation
//! measures what each switch buys on a GPU of the emulated subgroup width.

pub mod geometry;
pub mod lanes;
pub mod order;
pub mod stacks;

use super::cull::{DrawnSegment, drawn_segment};
use super::payload::{COVERAGE_SCALE, EMPTY, linear_depth, pack, quantize_depth};
use super::tile_alloc::ModelTiles;
use super::{ModelLod, Scene, TILE, TILE_TEXELS};
use crate::common::clip::{NearClipped, near_clip};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, flag};
use crate::describe::PassKind;
use crate::kernel::{CounterValues, Ctx, Words};
use crate::params::{Invalid, PassParams};
use geometry::Trapezoid;
use stacks::{Request, Sink, Stacks};

/// Segments per workgroup (Kulikov: "Need large groups (256/512/1024 lanes)").
pub const GROUP: u32 = 256;
/// Ordered visibility layers.
pub const LAYERS: usize = 3;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RasterParams {
    pub loop_flattening: bool,
    pub pixel_request_stack: bool,
    pub depth_test_stack: bool,
    pub last_layer_cull: bool,
    pub morton_sort: bool,
    /// Kulikov: each pixel's coverage computed analytically from the
    /// trapezoid's edges, in registers; false clips the column slice per
    /// pixel (Sutherland-Hodgman), whose vertex arrays spill on a GPU.
    pub analytic_coverage: bool,
    /// Accepted only at its one value: the sort pass's dispatch uses it.
    pub workgroup_size: u32,
    /// Accepted only at its one value: composition decodes with it.
    pub coverage_scale: f32,
}

impl Default for RasterParams {
    fn default() -> Self {
        Self {
            loop_flattening: true,
            pixel_request_stack: true,
            depth_test_stack: true,
            last_layer_cull: true,
            morton_sort: true,
            analytic_coverage: true,
            workgroup_size: GROUP,
            coverage_scale: COVERAGE_SCALE,
        }
    }
}

impl PassParams for RasterParams {
    const VARIANT_ENTRIES: &'static [&'static str] = &["raster_no_stacks"];

    /// Both stacks off is an entry point of its own, with the stacks'
    /// code compiled out: as a uniform branch, their live values cost the
    /// kernel registers whichever side ran (H100, 1080p close view: raster
    /// 0.78 ms with both off by the uniform, 0.61 ms compiled out;
    /// benches/results/kulikov-raster-registers-h100.txt).
    fn entry(&self, default: &'static str) -> &'static str {
        if self.pixel_request_stack || self.depth_test_stack {
            default
        } else {
            "raster_no_stacks"
        }
    }

    fn validate(&self) -> Result<(), Invalid> {
        if self.workgroup_size != GROUP {
            return Err(Invalid::new(
                "workgroup_size",
                format!(
                    "the CPU kernel and the sort pass's dispatch use {GROUP}; got {}",
                    self.workgroup_size
                ),
            ));
        }
        if self.coverage_scale != COVERAGE_SCALE {
            return Err(Invalid::new(
                "coverage_scale",
                "composition decodes coverage with the talk's scale of 1024",
            ));
        }
        Ok(())
    }
}

crate::gpu_block! {
    /// `RasterParams`: the six switches, then the screen size.
    pub struct RasterGpu {
        loop_flattening: u32,
        pixel_request_stack: u32,
        depth_test_stack: u32,
        last_layer_cull: u32,
        morton_sort: u32,
        analytic_coverage: u32,
        width: u32,
        height: u32,
    }
}

pub static RASTER: PassKind<RasterParams, RasterGpu> = PassKind {
    kind: "kulikov.raster",
    summary: "conservative software rasterizer into a 3-layer 32-bit visibility atlas plus additive coverage",
    source: "Kulikov 2025, 'Rasterization', 'Divergence', 'Pixel request stack'",
    bindings: Some(&[
        Binding::read("raster_args"),
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("lod_models"),
        Binding::read("sorted_segments"),
        Binding::read("clip_positions"),
        Binding::read("groom.vertices"),
        Binding::read("atlas_tiles"),
        Binding::read("scene.depth"),
        Binding::atomic("vis_atlas"),
        Binding::atomic("coverage_atlas"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::Indirect {
        binding: "raster_args",
        word: 0,
    },
    shader: Shader::compute("kulikov/raster.wgsl", "raster"),
    kernel: |p| Box::new(RasterKernel(*p)),
    gpu: |p, q| RasterGpu {
        loop_flattening: flag(p.loop_flattening),
        pixel_request_stack: flag(p.pixel_request_stack),
        depth_test_stack: flag(p.depth_test_stack),
        last_layer_cull: flag(p.last_layer_cull),
        morton_sort: flag(p.morton_sort),
        analytic_coverage: flag(p.analytic_coverage),
        width: q.width,
        height: q.height,
    },
    raster: None,
};

struct RasterKernel(RasterParams);

/// One lane's segment, projected into its model's atlas grid.
struct Lane {
    trap: Trapezoid,
    local: u32,
    lod: ModelLod,
    tiles: ModelTiles,
    morton: u32,
}

/// Everything a pixel write needs, shared by the workgroup.
struct Targets<'a> {
    scene: &'a Scene,
    depth: Words<'a>,
    vis: Words<'a>,
    coverage: Words<'a>,
    layer_stride: usize,
    width: u32,
    height: u32,
}

/// The part of segment `v0`–`v1` in front of the near plane
/// ([`near_clip`]) as a trapezoid in its model's raster grid: the shape the
/// raster measures, and that composition evaluates again per pixel. Also returns the clipped part, whose ends
/// composition interpolates the vertex lighting between.
pub(crate) fn segment_trapezoid(
    scene: &Scene,
    ctx: &Ctx<'_>,
    tiles: &ModelTiles,
    lod: &ModelLod,
    v0: u32,
    v1: u32,
) -> Option<(Trapezoid, NearClipped)> {
    let (clip, verts) = (ctx.words("clip_positions"), ctx.words("groom.vertices"));
    let f = &scene.frame;
    let part = near_clip(
        clip.load_vec4(v0 as usize),
        clip.load_vec4(v1 as usize),
        f.near,
    )?;
    let d = tiles.downscale as f32;
    let (ox, oy) = (
        (tiles.origin_x * TILE) as f32,
        (tiles.origin_y * TILE) as f32,
    );
    let to_raster = |c: [f32; 4]| {
        let s = super::clip_to_screen(c, f.screen[0], f.screen[1]);
        [s[0] / d - ox, s[1] / d - oy]
    };
    // Strand width in raster pixels: world thickness × LOD compensation × projection.
    let thick = |v: u32| verts.load_f32(4 * v as usize + 3);
    let [ta, tb] = part.ends(thick(v0), thick(v1));
    let half = |t: f32, w: f32| 0.5 * t * lod.thickness_scale * f.pixels_per_unit / w / d;
    let (a, b) = (part.a, part.b);
    let trap = Trapezoid::new(
        to_raster(a),
        to_raster(b),
        half(ta, a[3]),
        half(tb, b[3]),
        a[3],
        b[3],
    )?;
    Some((trap, part))
}

impl RasterKernel {
    fn project(
        &self,
        scene: &Scene,
        ctx: &Ctx<'_>,
        seg: &DrawnSegment,
        lod: ModelLod,
        tiles: ModelTiles,
    ) -> Option<Lane> {
        if tiles.valid == 0 {
            return None;
        }
        let (trap, _) = segment_trapezoid(scene, ctx, &tiles, &lod, seg.v0, seg.v1)?;
        let mid = [0.5 * (trap.a[0] + trap.b[0]), 0.5 * (trap.a[1] + trap.b[1])];
        let morton = order::morton(mid[0].max(0.0) as u32, mid[1].max(0.0) as u32);
        Some(Lane {
            trap,
            local: seg.local,
            lod,
            tiles,
            morton,
        })
    }
}

impl Targets<'_> {
    /// Everything a pixel write decides before the depth test (the WGSL's
    /// `pixel_request`).
    fn pixel_request(&self, lane: &Lane, x: u32, y: u32, coverage: f32) -> Request {
        let tiles = &lane.tiles;
        let view_depth = lane.trap.depth_at(x as i32, y as i32);
        // Depth test at the screen pixel under this atlas texel's centre.
        let d = tiles.downscale;
        let sx = ((tiles.origin_x * TILE + x) * d + d / 2).min(self.width - 1);
        let sy = ((tiles.origin_y * TILE + y) * d + d / 2).min(self.height - 1);
        let (tx, ty) = (x / TILE, y / TILE);
        let texel = (tiles.first_tile + ty * tiles.grid_w + tx) * TILE_TEXELS
            + (y % TILE) * TILE
            + x % TILE;
        let payload = pack(
            quantize_depth(view_depth, lane.lod.depth_near, lane.lod.depth_far),
            lane.local,
        );
        Request {
            pos: sx | (sy << 16),
            view_depth,
            texel,
            payload,
            cov: (coverage * COVERAGE_SCALE).round() as u32,
        }
    }
}

/// The atlas end of the request path: depth test and write, tallied.
struct Atlas<'a> {
    t: &'a Targets<'a>,
    last_layer_cull: bool,
    tally: CounterValues,
}

impl Sink for Atlas<'_> {
    fn depth_passes(&mut self, pos: u32, view_depth: f32) -> bool {
        let (sx, sy) = (pos & 0xFFFF, pos >> 16);
        let z = self.t.depth.load_f32((sy * self.t.width + sx) as usize);
        let f = &self.t.scene.frame;
        // Written so that a NaN depth passes, as the WGSL's `!(a >= b)`.
        !(view_depth >= linear_depth(z, f.near, f.far))
    }

    /// Kulikov's WritePixelToVisBuffer: last-layer cull, then chained
    /// `atomicMin` with the evicted value moving down; additive coverage in
    /// any case.
    fn write(&mut self, texel: u32, mut payload: u32, cov: u32) {
        let (t, texel) = (self.t, texel as usize);
        self.tally.pixels_written += 1;
        // Kulikov, "Last layer culling": a plain load of the last layer.
        let culled =
            self.last_layer_cull && t.vis.load(texel + (LAYERS - 1) * t.layer_stride) < payload;
        if !culled {
            for layer in 0..LAYERS {
                let prev = t.vis.fetch_min(texel + layer * t.layer_stride, payload);
                self.tally.atomics += 1;
                if prev == EMPTY {
                    break;
                }
                payload = payload.max(prev);
            }
        }
        t.coverage.fetch_add(texel, cov);
        self.tally.atomics += 1;
    }
}

impl lanes::Pixels for Atlas<'_> {
    fn request(&self, lane: &Lane, x: u32, y: u32, coverage: f32) -> Request {
        self.t.pixel_request(lane, x, y, coverage)
    }
}

impl CpuKernel for RasterKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let count = ctx.words("raster_args").load(3);
        let sorted = ctx.words("sorted_segments");
        let lods = scene.lods(ctx);
        let tiles = scene.tiles(ctx);
        // Invocation `i` of the group projects sorted segment `first + i`.
        let mut lanes: Vec<Option<Lane>> = (group * GROUP..((group + 1) * GROUP).min(count))
            .map(|i| {
                let seg = drawn_segment(&scene, &lods, sorted.load(i as usize))?;
                self.project(&scene, ctx, &seg, lods[seg.model], tiles[seg.model])
            })
            .collect();
        if self.0.morton_sort {
            lanes = order::morton_sort(lanes, |l| l.morton);
        }
        let vis = ctx.words("vis_atlas");
        let targets = Targets {
            scene: &scene,
            depth: ctx.words("scene.depth"),
            layer_stride: vis.len() / LAYERS,
            vis,
            coverage: ctx.words("coverage_atlas"),
            width: ctx.quantities.width,
            height: ctx.quantities.height,
        };
        let mut atlas = Atlas {
            t: &targets,
            last_layer_cull: self.0.last_layer_cull,
            tally: CounterValues::default(),
        };
        let width = ctx.subgroup_width.max(1) as usize;
        let mut tally = stacks::LaneTally::default();
        // Subgroup `k` is invocations k·width.. (the WGSL's `subgroup_id`).
        for (k, sub) in lanes.chunks(width).enumerate() {
            let fit = stacks::stacks_fit(width, k, targets.layer_stride);
            let mut st = Stacks::new(
                width,
                self.0.depth_test_stack && fit,
                self.0.pixel_request_stack && fit,
            );
            let sub: Vec<Option<&Lane>> = sub.iter().map(Option::as_ref).collect();
            lanes::raster(
                &sub,
                self.0.loop_flattening,
                self.0.analytic_coverage,
                &mut st,
                &mut atlas,
            );
            tally.add(&st.tally);
        }
        if ctx.instrument {
            let lanes = tally.sum();
            atlas.tally.active_lanes = lanes.active;
            atlas.tally.total_lanes = lanes.total;
            ctx.counters.add(&atlas.tally);
        }
    }
}

#[cfg(test)]
mod tests;
