//! `kulikov.motion` and `kulikov.store_history`: motion vectors from the
//! post-transform cache (Kulikov, "Motion vectors"):
//! "Compress post-transform NDC from current frame; use as last frame
//! positions in the next frame; assume no movement if vertex wasn't
//! transformed last frame (LOD change); clamped UNORM16 for x and y."
//!
//! - `kulikov.motion` reads each vertex's last-frame word from the History
//!   buffer `prev_clip_positions` and this frame's `clip_positions`, writes
//!   its screen motion in pixels (now − previous, y down) to
//!   `vertex_motion`, and overwrites the word with this frame's compressed
//!   NDC for the next frame. Each invocation reads and writes only its own
//!   vertex, so the history is updated in place by the pass that reads it.
//! - `kulikov.store_history` keeps this frame's camera (`frame`) as
//!   `prev_frame` for next frame's `kulikov.pixel_motion`, after this
//!   frame's has read it: one workgroup copying 256 bytes, at the frame's end.
//!
//! The two kinds share one file because they keep one history: the encoder
//! and decoder ([`pack`], [`motion`]) are tested against each other here.
//!
//! A vertex was transformed this frame when its clip w is in front of the
//! near plane: the graph clears `clip_positions` before skinning, so a
//! vertex the LOD skipped reads w = 0.

use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::layout::{FrameData, read};
use crate::params::NoParams;
use strandgraph_graph::Quantities;
use strandgraph_graph::schema::Quantity;

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

const PER_VERTEX: Dispatch = Dispatch::PerElement {
    quantity: Quantity::Vertices,
    per_group: GROUP,
};

crate::gpu_block! {
    /// `HistoryParams`: vertex count, three pad words.
    pub struct HistoryGpu {
        vertices: u32,
        _pad0: u32,
        _pad1: u32,
        _pad2: u32,
    }
}

fn history_gpu(_: &NoParams, q: &Quantities) -> HistoryGpu {
    HistoryGpu {
        vertices: count(q.vertices),
        ..HistoryGpu::default()
    }
}

pub static STORE_HISTORY: PassKind<NoParams, HistoryGpu> = PassKind {
    kind: "kulikov.store_history",
    summary: "keep this frame's camera as prev_frame for next frame's per-pixel motion",
    source: "Kulikov 2025, 'Motion vectors'",
    bindings: Some(&[Binding::read("frame"), Binding::write("prev_frame")]),
    workgroup_size: GROUP,
    dispatch: Dispatch::Fixed(1),
    shader: Shader::compute("kulikov/motion.wgsl", "store_history"),
    kernel: |_| Box::new(StoreKernel),
    gpu: history_gpu,
    raster: None,
};

pub static MOTION: PassKind<NoParams, HistoryGpu> = PassKind {
    kind: "kulikov.motion",
    summary: "per-vertex screen motion from last frame's compressed NDC (none where either frame skipped the vertex); then this frame's NDC, clamped UNORM16 x, y, over it for the next",
    source: "Kulikov 2025, 'Motion vectors'",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("clip_positions"),
        Binding::write("prev_clip_positions"),
        Binding::write("vertex_motion"),
    ]),
    workgroup_size: GROUP,
    dispatch: PER_VERTEX,
    shader: Shader::compute("kulikov/motion.wgsl", "motion"),
    kernel: |_| Box::new(MotionKernel),
    gpu: history_gpu,
    raster: None,
};

/// The vertices of workgroup `group` (clamped to the vertex count).
fn vertices(group: u32, ctx: &Ctx<'_>) -> std::ops::Range<usize> {
    let n = ctx.quantities.vertices as usize;
    let start = (group * GROUP) as usize;
    start.min(n)..(start + GROUP as usize).min(n)
}

struct StoreKernel;

impl CpuKernel for StoreKernel {
    fn run_workgroup(&self, _group: u32, ctx: &Ctx<'_>) {
        let (now, prev) = (ctx.words("frame"), ctx.words("prev_frame"));
        for k in 0..std::mem::size_of::<FrameData>() / 4 {
            prev.store(k, now.load(k));
        }
    }
}

struct MotionKernel;

impl CpuKernel for MotionKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let f: FrameData = read(&ctx.words("frame"), 0);
        let (clip, prev, out) = (
            ctx.words("clip_positions"),
            ctx.words("prev_clip_positions"),
            ctx.words("vertex_motion"),
        );
        for v in vertices(group, ctx) {
            let c = clip.load_vec4(v);
            let m = motion(prev.load(v), c, f.near, f.screen[0], f.screen[1]);
            out.store(2 * v, m[0].to_bits());
            out.store(2 * v + 1, m[1].to_bits());
            prev.store(v, pack(c, f.near));
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
    fn motion_is_in_pixels_with_y_down() {
        let (a, b) = ([0.0, 0.0, 0.5, 1.0], [0.1, 0.1, 0.5, 1.0]);
        let m = motion(pack(a, 0.02), b, 0.02, 1000.0, 500.0);
        assert!(
            (m[0] - 50.0).abs() < 0.05 && (m[1] + 25.0).abs() < 0.05,
            "{m:?}"
        );
    }
}
