//! `bench.raster`: the graphics roofline, through the hardware rasterizer
//! (WGSL: `shaders/bench/raster.wgsl`).
//!
//! Hopper runs vertex and pixel work on few of its SMs, so a pass that draws
//! through the rasterizer there is bound by that, not by its work. This pass
//! measures the ceiling in the same run as the pipelines: `layers` layers of
//! a grid of `cell` × `cell` pixel squares, two triangles each, over the
//! screen (`cell` 0: one square, the whole screen). A small cell measures
//! triangles per second; full-screen layers measure shaded fragments per
//! second. Every fragment writes a colour hashed from its pixel, so the image
//! is the same whatever order triangles are drawn in, on every backend.

use super::roofline::pcg;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::hardware_raster::Setup;
use crate::kernel::{CounterValues, Ctx};
use crate::params::{Invalid, PassParams, in_range};
use crate::raster_state::{
    Blend, ColorLoad, Compare, Cull, DepthLoad, Draw, Geometry, RasterState,
};
use strandgraph_graph::Quantities;
use strandgraph_graph::schema::Quantity;

/// Triangles per CPU workgroup.
const GROUP: u32 = 256;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RasterBenchParams {
    /// Edge of a grid square in pixels (0: one square covering the screen).
    pub cell: u32,
    /// How many times the grid is drawn.
    pub layers: u32,
}

impl Default for RasterBenchParams {
    fn default() -> Self {
        Self { cell: 2, layers: 1 }
    }
}

impl PassParams for RasterBenchParams {
    fn validate(&self) -> Result<(), Invalid> {
        in_range("cell", self.cell, 0..=256)?;
        in_range("layers", self.layers, 1..=64)
    }
}

impl RasterBenchParams {
    /// Grid squares across and down the screen.
    fn grid(&self, width: u32, height: u32) -> (u32, u32) {
        match self.cell {
            0 => (1, 1),
            c => (width.div_ceil(c), height.div_ceil(c)),
        }
    }

    /// Triangles the pass draws at this screen size.
    pub fn triangles(&self, width: u32, height: u32) -> u64 {
        let (gx, gy) = self.grid(width, height);
        2 * u64::from(gx) * u64::from(gy) * u64::from(self.layers)
    }

    /// Corner `k` of triangle `t`, in pixels (y down): square `s` of the
    /// grid is split along its rising diagonal; both halves wind the same way.
    pub fn corner(&self, t: u64, k: u32, width: u32, height: u32) -> [f32; 2] {
        let (gx, gy) = self.grid(width, height);
        let square = (t / 2) % (u64::from(gx) * u64::from(gy));
        let (sx, sy) = (
            (square % u64::from(gx)) as u32,
            (square / u64::from(gx)) as u32,
        );
        let (cw, ch) = match self.cell {
            0 => (width, height),
            c => (c, c),
        };
        // Corners of the square: 0 top-left, 1 bottom-left, 2 top-right, 3 bottom-right.
        let corner = if t.is_multiple_of(2) {
            [0, 1, 2]
        } else {
            [2, 1, 3]
        }[k as usize];
        [
            ((sx + (corner >> 1)) * cw) as f32,
            ((sy + (corner & 1)) * ch) as f32,
        ]
    }
}

crate::gpu_block! {
    /// `RasterBenchParams` in shaders/bench/raster.wgsl.
    pub struct RasterBenchGpu {
        cell: u32,
        layers: u32,
        width: u32,
        height: u32,
    }
}

pub static RASTER: PassKind<RasterBenchParams, RasterBenchGpu> = PassKind {
    kind: "bench.raster",
    summary: "triangles and shaded fragments per second through the hardware rasterizer (graphics roofline)",
    source: "strandgraph bench",
    bindings: Some(&[Binding::write("raster_target")]),
    workgroup_size: GROUP,
    // The CPU spreads the triangles over one workgroup per 256 pixels.
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Pixels,
        per_group: GROUP,
    },
    shader: Shader {
        file: "bench/raster.wgsl",
        entry: "vs_main",
        fragment: Some("fs_main"),
    },
    kernel: |p| Box::new(RasterBench(*p)),
    gpu: |p, q| RasterBenchGpu {
        cell: p.cell,
        layers: p.layers,
        width: q.width,
        height: q.height,
    },
    raster: Some(draw),
};

/// Colour only, no depth, no culling, replacing what is there.
fn draw(p: &RasterBenchParams, q: &Quantities) -> RasterState {
    RasterState {
        geometry: Geometry::Vertices(3 * p.triangles(q.width, q.height)),
        cull: Cull::None,
        color_load: ColorLoad::Clear([0.0; 4]),
        depth_load: DepthLoad::Load,
        draws: vec![Draw {
            fragment: "fs_main",
            blend: Blend::Replace,
            color_writes: true,
            depth_compare: Compare::Always,
            depth_write: false,
        }],
    }
}

/// The colour every fragment of pixel `i` writes: RGBA8 bytes of a hash.
pub fn pixel_colour(i: u32) -> u32 {
    pcg(i)
}

struct RasterBench(RasterBenchParams);

impl CpuKernel for RasterBench {
    fn prologue(&self, ctx: &Ctx<'_>) {
        let target = ctx.words("raster_target");
        (0..target.len()).for_each(|i| target.store(i, 0));
    }

    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let (w, h) = (ctx.quantities.width, ctx.quantities.height);
        let groups = ctx
            .quantities
            .count(Quantity::Pixels)
            .div_ceil(u64::from(GROUP));
        let total = self.0.triangles(w, h);
        // An even share of the triangles for each workgroup.
        let (first, last) = (
            total * u64::from(group) / groups,
            total * u64::from(group + 1) / groups,
        );
        let target = ctx.words("raster_target");
        let mut fragments = 0;
        for t in first..last {
            let xy = [0, 1, 2].map(|k| self.0.corner(t, k, w, h));
            if let Some(s) = Setup::from_screen(xy, [0.5; 3], [1.0; 3], w, h) {
                s.rasterize(|f| {
                    let i = f.y * w + f.x;
                    target.store(i as usize, pixel_colour(i));
                    fragments += 1;
                });
            }
        }
        if ctx.instrument {
            ctx.counters.add(&CounterValues {
                pixels_written: fragments,
                ..CounterValues::default()
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn squares_tile_the_screen_and_every_triangle_is_front_facing() {
        let p = RasterBenchParams { cell: 4, layers: 2 };
        let (w, h) = (10, 6);
        assert_eq!(p.triangles(w, h), 2 * 3 * 2 * 2);
        let mut covered = vec![0u32; (w * h) as usize];
        for t in 0..p.triangles(w, h) {
            let xy = [0, 1, 2].map(|k| p.corner(t, k, w, h));
            let s = Setup::from_screen(xy, [0.5; 3], [1.0; 3], w, h)
                .unwrap_or_else(|| panic!("triangle {t} {xy:?} culled"));
            s.rasterize(|f| covered[(f.y * w + f.x) as usize] += 1);
        }
        // Two layers: every pixel exactly twice (the fill rule splits the diagonals).
        assert!(covered.iter().all(|&c| c == 2), "{covered:?}");
        let full = RasterBenchParams { cell: 0, layers: 3 };
        assert_eq!(full.triangles(w, h), 6);
        assert_eq!(full.corner(1, 2, w, h), [10.0, 6.0]);
    }
}
