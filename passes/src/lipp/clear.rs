//! `lipp.clear_gbuffer` (ours): the G-buffer cleared over the groom's screen
//! rectangle only ([`super::rect`]), where a full-screen clear cost every
//! groom the same 33 MB of writes at 1920x1080 however small it was.
//!
//! It clears every layer of the runs of [`TILE`] pixels `lipp.shade` shades
//! (the runs the rectangle touches), so every pixel the shade, the filter
//! and the rasterizer read or write was cleared this frame. A workgroup
//! clears a block of `lipp.lod_scan`'s `clear_runs` runs (ours, through its
//! own indirect dispatch, [`ARGS_CLEAR`]). A workgroup a run, as
//! `lipp.shade` is dispatched, launches a workgroup for every 1 KB of
//! writes (a 1920x1080 screen has 32,400 runs): the close view's clear took
//! 27 µs on the H200 that way, 19 in blocks of 8 runs
//! (benches/results/lipp-clear-blocks-h200.txt). Elsewhere the G-buffer
//! keeps what an earlier groom, or a resource aliased to it, left there:
//! the rasterizer writes inside the rectangle only (`tests/lipp_rect.rs`),
//! and the filter's taps outside it read no hair ([`super::filter`]). With
//! `lipp.lod_scan`'s `groom_rect` off the rectangle is the whole screen.

use super::payload::EMPTY;
use super::rect::{ARGS_CLEAR, ARGS_RECT_HI, ARGS_RECT_LO, Rect};
use super::tiles::TILE;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::params::NoParams;

crate::gpu_block! {
    /// `ClearParams` in shaders/lipp/clear_gbuffer.wgsl.
    pub struct ClearGpu {
        width: u32,
        height: u32,
        _pad0: u32,
        _pad1: u32,
    }
}

pub static CLEAR_GBUFFER: PassKind<NoParams, ClearGpu> = PassKind {
    kind: "lipp.clear_gbuffer",
    summary: "every G-buffer layer cleared over the runs of pixels the groom's screen rectangle touches, in blocks of runs",
    source: "ours (lipp::rect)",
    bindings: Some(&[Binding::read("raster_args"), Binding::write("gbuffer")]),
    workgroup_size: TILE,
    // A workgroup per block of runs (rect::Rect::run_dispatch).
    dispatch: Dispatch::Indirect {
        binding: "raster_args",
        word: ARGS_CLEAR,
    },
    shader: Shader::compute("lipp/clear_gbuffer.wgsl", "clear_gbuffer"),
    kernel: |_| Box::new(ClearKernel),
    gpu: |_, q| ClearGpu {
        width: q.width,
        height: q.height,
        ..ClearGpu::default()
    },
    raster: None,
};

struct ClearKernel;

impl CpuKernel for ClearKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let (w, h) = (ctx.quantities.width, ctx.quantities.height);
        let pixels = (w * h).max(1);
        let (args, g) = (ctx.words("raster_args"), ctx.words("gbuffer"));
        let rect = Rect::from_args(args.load(ARGS_RECT_LO), args.load(ARGS_RECT_HI));
        let layers = (g.len() / (2 * pixels as usize)) as u32;
        let empty = [EMPTY as u32, (EMPTY >> 32) as u32];
        for run in rect.runs_of_group(w, group, ctx.workgroups) {
            for layer in 0..layers {
                for i in run * TILE..((run + 1) * TILE).min(pixels) {
                    let slot = 2 * (layer * pixels + i) as usize;
                    g.store(slot, empty[0]);
                    g.store(slot + 1, empty[1]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::harness::Harness;
    use strandgraph_graph::Quantities;

    /// A 100x4 screen, two layers, a rectangle x 70..90, y 1..3: the runs
    /// of 64 pixels it touches are cleared in both layers, nothing else,
    /// by two workgroups of two runs.
    #[test]
    fn clears_the_runs_the_rectangle_touches_in_every_layer() {
        let (w, h) = (100u32, 4u32);
        let rect = Rect {
            x0: 70,
            y0: 1,
            x1: 90,
            y1: 3,
        };
        let mut args = vec![0u32; ARGS_CLEAR + 3];
        let [lo, hi] = rect.args();
        (args[ARGS_RECT_LO], args[ARGS_RECT_HI]) = (lo, hi);
        args[ARGS_CLEAR..].copy_from_slice(&rect.run_dispatch(w, 2));
        assert_eq!(args[ARGS_CLEAR], 2);
        let mut hs = Harness::new(Quantities {
            width: w,
            height: h,
            ..Default::default()
        });
        let slots = 2 * (w * h) as usize;
        hs.buffer("raster_args", args.clone())
            .buffer("gbuffer", vec![7; 2 * slots]);
        hs.run(&ClearKernel, args[ARGS_CLEAR], TILE);
        let g = hs.read("gbuffer");
        // Pixels 170..=289 lie in runs 2..=4 (128..320); run 2 starts in row 1.
        let (first, runs) = rect.runs(w);
        assert_eq!((first, runs), (2, 3));
        for layer in 0..2 {
            for i in 0..w * h {
                let slot = 2 * (layer * w * h + i) as usize;
                let cleared = (128..320).contains(&i);
                let want = if cleared { u32::MAX } else { 7 };
                assert_eq!([g[slot], g[slot + 1]], [want; 2], "layer {layer} pixel {i}");
            }
        }
        // Every pixel of the rectangle was cleared.
        for y in rect.y0..rect.y1 {
            for x in rect.x0..rect.x1 {
                assert_eq!(g[2 * (y * w + x) as usize], u32::MAX);
            }
        }
    }
}
