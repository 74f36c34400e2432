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
//! - `pixel_request_stack`, `depth_test_stack`: the LDS request stacks. They
//!   change how a GPU schedules the same writes, not which writes happen, so
//!   the CPU kernel accepts and reports them; the WGSL implements them.

pub mod geometry;
pub mod lanes;

use super::cull::{DrawnSegment, drawn_segment};
use super::payload::{COVERAGE_SCALE, EMPTY, linear_depth, pack, quantize_depth};
use super::tile_alloc::ModelTiles;
use super::{ModelLod, Scene, TILE, TILE_TEXELS};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, flag};
use crate::describe::PassKind;
use crate::kernel::{CounterValues, Ctx, Words};
use crate::params::{Invalid, PassParams};
use geometry::Trapezoid;

/// Segments per workgroup (Kulikov: "Need large groups (256/512/1024 lanes)").
pub const GROUP: u32 = 256;
/// Ordered visibility layers.
pub const LAYERS: usize = 3;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RasterParams {
    pub loop_flattening: bool,
    pub pixel_request_stack: bool,
    pub depth_test_stack: bool,
    pub last_layer_cull: bool,
    pub morton_sort: bool,
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
            workgroup_size: GROUP,
            coverage_scale: COVERAGE_SCALE,
        }
    }
}

impl PassParams for RasterParams {
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
    /// `RasterParams`: the five switches, then the screen size.
    pub struct RasterGpu {
        loop_flattening: u32,
        pixel_request_stack: u32,
        depth_test_stack: u32,
        last_layer_cull: u32,
        morton_sort: u32,
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

fn morton(x: u32, y: u32) -> u32 {
    let spread = |mut v: u32| {
        v &= 0xFFFF;
        v = (v | (v << 8)) & 0x00FF_00FF;
        v = (v | (v << 4)) & 0x0F0F_0F0F;
        v = (v | (v << 2)) & 0x3333_3333;
        (v | (v << 1)) & 0x5555_5555
    };
    spread(x) | (spread(y) << 1)
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

/// Segment `v0`–`v1`'s trapezoid in its model's raster grid: the shape the
/// raster measures, and that composition and `kulikov.pixel_motion`
/// evaluate again per pixel.
pub(crate) fn segment_trapezoid(
    scene: &Scene,
    ctx: &Ctx<'_>,
    tiles: &ModelTiles,
    lod: &ModelLod,
    v0: u32,
    v1: u32,
) -> Option<Trapezoid> {
    let (clip, verts) = (ctx.words("clip_positions"), ctx.words("groom.vertices"));
    let f = &scene.frame;
    let (c0, c1) = (clip.load_vec4(v0 as usize), clip.load_vec4(v1 as usize));
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
    let half = |v: u32, w: f32| {
        0.5 * verts.load_f32(4 * v as usize + 3) * lod.thickness_scale * f.pixels_per_unit / w / d
    };
    Trapezoid::new(
        to_raster(c0),
        to_raster(c1),
        half(v0, c0[3]),
        half(v1, c1[3]),
        c0[3],
        c1[3],
    )
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
        let clip = ctx.words("clip_positions");
        let near = scene.frame.near;
        let (c0, c1) = (
            clip.load_vec4(seg.v0 as usize),
            clip.load_vec4(seg.v1 as usize),
        );
        if c0[3] <= near || c1[3] <= near || tiles.valid == 0 {
            return None;
        }
        let trap = segment_trapezoid(scene, ctx, &tiles, &lod, seg.v0, seg.v1)?;
        let mid = [0.5 * (trap.a[0] + trap.b[0]), 0.5 * (trap.a[1] + trap.b[1])];
        let morton = morton(mid[0].max(0.0) as u32, mid[1].max(0.0) as u32);
        Some(Lane {
            trap,
            local: seg.local,
            lod,
            tiles,
            morton,
        })
    }

    /// Rasterizes one lane; returns its pixel count per column (for lane statistics).
    fn rasterize(&self, lane: &Lane, t: &Targets<'_>, tally: &mut CounterValues) -> Vec<u32> {
        let grid_w = (lane.tiles.grid_w * TILE) as i32;
        let grid_h = (lane.tiles.grid_h * TILE) as i32;
        let (x0, x1) = lane.trap.columns();
        let mut heights = Vec::new();
        for x in x0.max(0)..=x1.min(grid_w - 1) {
            let col = lane.trap.column(x);
            if col.is_empty() {
                heights.push(0);
                continue;
            }
            let (lo, hi) = col.range(1);
            let (y0, y1) = (
                (lo.floor() as i32).max(0),
                (hi.floor() as i32).min(grid_h - 1),
            );
            heights.push((y1 - y0 + 1).max(0) as u32);
            for y in y0..=y1 {
                let coverage = Trapezoid::coverage(&col, y);
                // Only coverage that quantises to at least 1/1024 counts: thinner
                // slivers are float noise the GPU backends need not agree on.
                if (coverage * COVERAGE_SCALE).round() >= 1.0 {
                    self.write_pixel(lane, x as u32, y as u32, coverage, t, tally);
                }
            }
        }
        heights
    }

    fn write_pixel(
        &self,
        lane: &Lane,
        x: u32,
        y: u32,
        coverage: f32,
        t: &Targets<'_>,
        tally: &mut CounterValues,
    ) {
        let tiles = &lane.tiles;
        let view_depth = lane.trap.depth_at(x as i32, y as i32);
        // Depth test at the screen pixel under this atlas texel's centre.
        let d = tiles.downscale;
        let sx = ((tiles.origin_x * TILE + x) * d + d / 2).min(t.width - 1);
        let sy = ((tiles.origin_y * TILE + y) * d + d / 2).min(t.height - 1);
        let z = t.depth.load_f32((sy * t.width + sx) as usize);
        if view_depth >= linear_depth(z, t.scene.frame.near, t.scene.frame.far) {
            return;
        }
        let (tx, ty) = (x / TILE, y / TILE);
        let texel = ((tiles.first_tile + ty * tiles.grid_w + tx) * TILE_TEXELS
            + (y % TILE) * TILE
            + x % TILE) as usize;
        let mut payload = pack(
            quantize_depth(view_depth, lane.lod.depth_near, lane.lod.depth_far),
            lane.local,
        );
        tally.pixels_written += 1;
        // Kulikov, "Last layer culling": a plain load of the last layer.
        let culled =
            self.0.last_layer_cull && t.vis.load(texel + (LAYERS - 1) * t.layer_stride) < payload;
        if !culled {
            // Kulikov's WritePixelToVisBuffer: the evicted value moves down a layer.
            for layer in 0..LAYERS {
                let prev = t.vis.fetch_min(texel + layer * t.layer_stride, payload);
                tally.atomics += 1;
                if prev == EMPTY {
                    break;
                }
                payload = payload.max(prev);
            }
        }
        t.coverage
            .fetch_add(texel, (coverage * COVERAGE_SCALE).round() as u32);
        tally.atomics += 1;
    }
}

impl CpuKernel for RasterKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let count = ctx.words("raster_args").load(3);
        let sorted = ctx.words("sorted_segments");
        let lods = scene.lods(ctx);
        let tiles = scene.tiles(ctx);
        let mut lanes: Vec<Lane> = (group * GROUP..((group + 1) * GROUP).min(count))
            .filter_map(|i| {
                let seg = drawn_segment(&scene, &lods, sorted.load(i as usize))?;
                self.project(&scene, ctx, &seg, lods[seg.model], tiles[seg.model])
            })
            .collect();
        if self.0.morton_sort {
            // Kulikov: "sort according to Morton curve within each group".
            lanes.sort_by_key(|l| l.morton);
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
        let mut tally = CounterValues::default();
        let width = ctx.subgroup_width.max(1) as usize;
        for sub in lanes.chunks(width) {
            let heights: Vec<Vec<u32>> = sub
                .iter()
                .map(|l| self.rasterize(l, &targets, &mut tally))
                .collect();
            if ctx.instrument {
                let (active, total) = lanes::utilisation(&heights, width, self.0.loop_flattening);
                tally.active_lanes += active;
                tally.total_lanes += total;
            }
        }
        if ctx.instrument {
            ctx.counters.add(&tally);
        }
    }
}

#[cfg(test)]
mod tests;
