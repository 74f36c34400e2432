//! `scene.depth_resolve`: `scene.depth` from the visibility buffer.
//!
//! Every hair pass that culls or depth-tests against the head reads
//! `scene.depth`, an `R32Float` screen image of NDC depth z/w (glam
//! `perspective_rh`: 0 at the near plane, 1 at the far plane): the high half
//! of each pixel's `scene.visibility` word, or 1.0 where no triangle is.
//!
//! `scene.depth_hiz` (ours) also writes `hiz`, the farthest depth of each
//! 16×16 block that `kulikov.depth_downsample` would make from
//! `scene.depth`: one workgroup per block resolves the block's pixels and
//! reduces them. A graph that culls against the Hi-Z saves a pass, its
//! barrier and its second read of the screen (the Lipp graphs;
//! `kulikov.ron` keeps the two passes on its async queue).

use super::visibility::unpack;
use super::{PIXEL_GROUP, pixel_dispatch};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::kulikov::depth_downsample::{FACTOR, block_pixels, depth_bits};
use crate::params::NoParams;
use strandgraph_graph::schema::Quantity;

crate::gpu_block! {
    /// `DepthResolveParams` in shaders/opaque_mesh/depth_resolve.wgsl.
    pub struct DepthResolveGpu {
        width: u32,
        height: u32,
    }
}

pub static DEPTH_RESOLVE: PassKind<NoParams, DepthResolveGpu> = PassKind {
    kind: "scene.depth_resolve",
    summary: "scene depth from the opaque meshes' visibility buffer",
    source: "strandgraph",
    bindings: Some(&[
        Binding::read("scene.visibility"),
        Binding::write("scene.depth"),
    ]),
    workgroup_size: PIXEL_GROUP,
    dispatch: pixel_dispatch(),
    shader: Shader::compute("opaque_mesh/depth_resolve.wgsl", "resolve"),
    kernel: |_| Box::new(ResolveKernel),
    gpu: |_, q| DepthResolveGpu {
        width: q.width,
        height: q.height,
    },
    raster: None,
};

pub static DEPTH_HIZ: PassKind<NoParams, DepthResolveGpu> = PassKind {
    kind: "scene.depth_hiz",
    summary: "scene depth from the visibility buffer and its 16x16 farthest-depth Hi-Z, in one pass",
    source: "strandgraph; the Hi-Z of Kulikov 2025, 'Culling'",
    bindings: Some(&[
        Binding::read("scene.visibility"),
        Binding::write("scene.depth"),
        Binding::write("hiz"),
    ]),
    workgroup_size: FACTOR * FACTOR,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Tiles(FACTOR),
        per_group: 1,
    },
    shader: Shader::compute("opaque_mesh/depth_resolve.wgsl", "resolve_hiz"),
    kernel: |_| Box::new(ResolveHizKernel),
    gpu: |_, q| DepthResolveGpu {
        width: q.width,
        height: q.height,
    },
    raster: None,
};

/// NDC depth of a visibility word: the far plane where it is empty.
pub fn depth(word: u64) -> f32 {
    unpack(word).map_or(1.0, |(_, z)| z)
}

struct ResolveKernel;

impl CpuKernel for ResolveKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let q = ctx.quantities;
        let pixels = q.width as usize * q.height as usize;
        let (vis, out) = (ctx.words("scene.visibility"), ctx.words("scene.depth"));
        let first = group as usize * PIXEL_GROUP as usize;
        for i in first..(first + PIXEL_GROUP as usize).min(pixels) {
            out.store_f32(i, depth(vis.load_u64(i)));
        }
    }
}

struct ResolveHizKernel;

impl CpuKernel for ResolveHizKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let w = ctx.quantities.width;
        let Some(pixels) = block_pixels(group, w, ctx.quantities.height) else {
            return;
        };
        let (vis, out, hiz) = (
            ctx.words("scene.visibility"),
            ctx.words("scene.depth"),
            ctx.words("hiz"),
        );
        // kulikov.depth_downsample's maximum of the block.
        let mut far = 0u32;
        for (x, y) in pixels {
            let i = (y * w + x) as usize;
            let z = depth(vis.load_u64(i));
            out.store_f32(i, z);
            far = far.max(depth_bits(z));
        }
        hiz.store(group as usize, far);
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{frame, harness, head, run};
    use super::super::visibility::{EMPTY, VISIBILITY, pack};
    use super::*;
    use glam::Vec3;

    #[test]
    fn empty_is_far_and_covered_is_its_depth() {
        assert_eq!(depth(EMPTY), 1.0);
        assert_eq!(depth(pack(0.25, 7)), 0.25);
        let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 35.0, 96, 64);
        let hs = harness(f, &head(), &[]);
        run(&hs, &VISIBILITY);
        run(&hs, &DEPTH_RESOLVE);
        assert_eq!(hs.out_of_bounds(), 0);
        let (vis, z) = (hs.read("scene.visibility"), hs.read("scene.depth"));
        for (i, &d) in z.iter().enumerate() {
            let word = u64::from(vis[2 * i]) | (u64::from(vis[2 * i + 1]) << 32);
            assert_eq!(d, depth(word).to_bits(), "pixel {i}");
        }
        assert!(z.iter().any(|&d| d != 1.0f32.to_bits()));
        assert!(z.iter().any(|&d| d == 1.0f32.to_bits()));
    }

    /// The fused pass writes what `scene.depth_resolve` then
    /// `kulikov.depth_downsample` write, on a screen whose edges cut
    /// blocks (97 x 61 is not a multiple of 16).
    #[test]
    fn depth_hiz_is_the_resolve_then_the_downsample() {
        use crate::kulikov::depth_downsample::DEPTH_DOWNSAMPLE;
        let f = frame(Vec3::new(0.0, 0.0, 0.3), Vec3::ZERO, 35.0, 97, 61);
        // 7 x 4 blocks.
        let with_hiz = || {
            let mut hs = harness(f, &head(), &[]);
            hs.buffer("hiz", vec![0; 7 * 4]);
            hs
        };
        let (two, one) = (with_hiz(), with_hiz());
        for hs in [&two, &one] {
            run(hs, &VISIBILITY);
        }
        run(&two, &DEPTH_RESOLVE);
        run(&two, &DEPTH_DOWNSAMPLE);
        run(&one, &DEPTH_HIZ);
        assert_eq!(one.out_of_bounds(), 0);
        assert_eq!(one.read("scene.depth"), two.read("scene.depth"));
        let hiz = one.read("hiz");
        assert_eq!(hiz, two.read("hiz"));
        // Blocks the head fills, and the background.
        assert!(hiz.iter().any(|&d| d != 1.0f32.to_bits()));
        assert!(hiz.iter().any(|&d| d == 1.0f32.to_bits()));
    }
}
