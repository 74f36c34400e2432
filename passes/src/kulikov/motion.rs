//! Motion vectors from the post-transform cache (Kulikov, "Motion vectors"):
//! "Compress post-transform NDC from current frame; use as last frame
//! positions in the next frame; assume no movement if vertex wasn't
//! transformed last frame (LOD change); clamped UNORM16 for x and y."
//!
//! - `kulikov.skin_motion` (skin.rs) skins each drawn vertex, takes its
//!   screen motion in pixels (now − previous, y down) against the word in
//!   the History buffer `prev_clip_positions`, and stores this frame's
//!   compressed NDC over that word: the history is updated in place, in the
//!   pass that makes the positions, and only for drawn vertices.
//! - `kulikov.store_history` keeps this frame's camera (`frame`) and LOD
//!   (`lod_models`) as `prev_frame` and `prev_lod_models`, after this
//!   frame's readers: one workgroup at the frame's end.
//!
//! "Wasn't transformed last frame" is read from last frame's LOD: kept
//! strands are a prefix of each model's list, so a vertex was transformed
//! when its strand's index among the kept ones is below last frame's kept
//! count and last frame's vertex step drew it ([`drawn_at`]). A vertex the
//! LOD dropped keeps a stale word that nothing reads; no pass clears the
//! post-transform cache or walks the vertices the LOD skips.
//!
//! This file holds the packed format both ends share: the encoder and
//! decoder ([`pack`], [`motion`]) are tested against each other here.

use super::ModelLod;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::layout::{FrameData, read};
use crate::params::NoParams;

const GROUP: u32 = 256;
/// Largest UNORM16 code used for NDC. Codes are stored plus one, so that
/// the word 0 is free to mean "not transformed".
const UNORM_MAX: f32 = 65534.0;
/// `prev_clip_positions` of a vertex that was not transformed: 0, which is
/// also what a History buffer holds before its first frame, so the first
/// frame has no motion.
pub const NOT_TRANSFORMED: u32 = 0;

/// NDC in [−1, 1] (clamped) to the UNORM16 code, and back.
pub fn compress(ndc: f32) -> u32 {
    ((ndc.clamp(-1.0, 1.0) * 0.5 + 0.5) * UNORM_MAX).round() as u32
}
pub fn decompress(code: u32) -> f32 {
    code as f32 / UNORM_MAX * 2.0 - 1.0
}

/// The packed history word of clip position `c`.
pub fn pack(c: [f32; 4], near: f32) -> u32 {
    if !(c[3] > near) {
        return NOT_TRANSFORMED;
    }
    (compress(c[0] / c[3]) + 1) | (compress(c[1] / c[3]) + 1) << 16
}

/// Screen motion in pixels (y down) from a history word to clip position
/// `c`; zero where either frame did not transform the vertex.
pub fn motion(prev: u32, c: [f32; 4], near: f32, width: f32, height: f32) -> [f32; 2] {
    if prev == NOT_TRANSFORMED || !(c[3] > near) {
        return [0.0, 0.0];
    }
    let (px, py) = (
        decompress((prev & 0xFFFF).saturating_sub(1)),
        decompress((prev >> 16).saturating_sub(1)),
    );
    let (nx, ny) = (c[0] / c[3], c[1] / c[3]);
    [(nx - px) * 0.5 * width, (py - ny) * 0.5 * height]
}

/// Whether a strand of `count` points draws vertex `v` at a vertex step
/// (every `step`-th vertex and the tip: `ModelLod::segment_vertices`).
pub fn drawn_at(v: u32, step: u32, count: u32) -> bool {
    v.is_multiple_of(step.max(1)) || v + 1 == count
}

crate::gpu_block! {
    /// `HistoryParams`: one reserved word (the pass has no parameters).
    pub struct HistoryGpu {
        reserved: u32,
    }
}

pub static STORE_HISTORY: PassKind<NoParams, HistoryGpu> = PassKind {
    kind: "kulikov.store_history",
    summary: "keep this frame's camera and LOD for next frame's motion vectors",
    source: "Kulikov 2025, 'Motion vectors'",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("lod_models"),
        Binding::write("prev_frame"),
        Binding::write("prev_lod_models"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::Fixed(1),
    shader: Shader::compute("kulikov/motion.wgsl", "store_history"),
    kernel: |_| Box::new(StoreKernel),
    gpu: |_, _| HistoryGpu::default(),
    raster: None,
};

struct StoreKernel;

impl CpuKernel for StoreKernel {
    fn run_workgroup(&self, _group: u32, ctx: &Ctx<'_>) {
        let (now, prev) = (ctx.words("frame"), ctx.words("prev_frame"));
        for k in 0..std::mem::size_of::<FrameData>() / 4 {
            prev.store(k, now.load(k));
        }
        let frame: FrameData = read(&now, 0);
        let (lods, prev_lods) = (ctx.words("lod_models"), ctx.words("prev_lod_models"));
        for k in 0..frame.model_count as usize * ModelLod::WORDS {
            prev_lods.store(k, lods.load(k));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compression_keeps_sub_pixel_precision_and_clamps() {
        for ndc in [-1.0, -0.3721, 0.0, 0.5, 0.99999] {
            // 2 / 65534 NDC: 0.03 px across a 1920-pixel screen.
            assert!((decompress(compress(ndc)) - ndc).abs() <= 1.0 / UNORM_MAX);
        }
        assert_eq!(compress(3.0), compress(1.0));
        assert_eq!(compress(1.0), 65534);
        assert_ne!(pack([1.0, 1.0, 0.0, 1.0], 0.02), NOT_TRANSFORMED);
    }

    #[test]
    fn untransformed_vertices_have_no_motion() {
        let c = [0.2, -0.1, 0.5, 2.0];
        assert_eq!(pack([0.0; 4], 0.02), NOT_TRANSFORMED);
        // The most negative NDC corner still packs to a word other than 0.
        assert_ne!(pack([-1.0, -1.0, 0.0, 1.0], 0.02), NOT_TRANSFORMED);
        assert_eq!(motion(NOT_TRANSFORMED, c, 0.02, 100.0, 100.0), [0.0, 0.0]);
        assert_eq!(
            motion(pack(c, 0.02), [0.0; 4], 0.02, 100.0, 100.0),
            [0.0, 0.0]
        );
        // Same position both frames: (quantisation-level) zero motion.
        let m = motion(pack(c, 0.02), c, 0.02, 1920.0, 1080.0);
        assert!(m[0].abs() < 0.02 && m[1].abs() < 0.02, "{m:?}");
    }

    #[test]
    fn a_vertex_step_draws_every_step_th_vertex_and_the_tip() {
        let drawn = |step, count| {
            (0..count)
                .filter(|&v| drawn_at(v, step, count))
                .collect::<Vec<_>>()
        };
        assert_eq!(drawn(1, 4), [0, 1, 2, 3]);
        assert_eq!(drawn(2, 6), [0, 2, 4, 5]);
        assert_eq!(drawn(2, 5), [0, 2, 4]);
        // The same vertices ModelLod::segment_vertices draws.
        let lod = ModelLod {
            vertex_step: 2,
            ..ModelLod::default()
        };
        let mut ends: Vec<u32> = (0..super::super::drawn_segments(6, 2))
            .flat_map(|k| {
                let (a, b) = lod.segment_vertices(6, k);
                [a, b]
            })
            .collect();
        ends.dedup();
        assert_eq!(ends, drawn(2, 6));
    }

    #[test]
    fn motion_is_in_pixels_with_y_down() {
        let (a, b) = ([0.0, 0.0, 0.5, 1.0], [0.1, 0.1, 0.5, 1.0]);
        let m = motion(pack(a, 0.02), b, 0.02, 1000.0, 500.0);
        assert!(
            (m[0] - 50.0).abs() < 0.05 && (m[1] + 25.0).abs() < 0.05,
            "{m:?}"
        );
    }
}
