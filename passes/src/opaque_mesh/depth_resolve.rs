//! `scene.depth_resolve`: `scene.depth` from the visibility buffer.
//!
//! Every hair pass that culls or depth-tests against the head reads
//! `scene.depth`, an `R32Float` screen image of NDC depth z/w (glam
//! `perspective_rh`: 0 at the near plane, 1 at the far plane): the high half
//! of each pixel's `scene.visibility` word, or 1.0 where no triangle is.

use super::visibility::unpack;
use super::{PIXEL_GROUP, pixel_dispatch};
use crate::contract::{Binding, CpuKernel, Shader};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::params::NoParams;

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
}
