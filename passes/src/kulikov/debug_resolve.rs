//! `kulikov.debug_resolve`: the visibility atlas resolved to screen, so a user
//! can look at it before shading exists.
//!
//! Writes the reconstructed coverage of every model, in its material colour,
//! over the opaque image (Kulikov's quadratic coverage fit), and an RGBA8
//! image of the three layers' 10-bit depths (R, G, B: brighter is nearer)
//! and total coverage (A).

use super::payload::{EMPTY, depth_of, total_coverage};
use super::raster::LAYERS;
use super::{Scene, TILE_TEXELS};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::params::NoParams;
use half::f16;
use strandgraph_graph::schema::Quantity;

const GROUP: u32 = 256;

crate::gpu_block! {
    /// `ResolveParams`: screen width and pixel count.
    pub struct ResolveGpu {
        width: u32,
        pixels: u32,
    }
}

pub static DEBUG_RESOLVE: PassKind<NoParams, ResolveGpu> = PassKind {
    kind: "kulikov.debug_resolve",
    summary: "resolve the visibility atlas to screen: coverage over the opaque image, layer depths",
    source: "Kulikov 2025, 'Visibility buffer' (debug view)",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("atlas_tiles"),
        Binding::read("vis_atlas"),
        Binding::read("coverage_atlas"),
        Binding::write("output"),
        Binding::write("debug_layers"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Pixels,
        per_group: GROUP,
    },
    shader: Shader::compute("kulikov/debug_resolve.wgsl", "resolve"),
    kernel: |_| Box::new(ResolveKernel),
    gpu: |_, q| ResolveGpu {
        width: q.width,
        pixels: count(u64::from(q.width) * u64::from(q.height)),
    },
    raster: None,
};

struct ResolveKernel;

/// Reads an Rgba16Float texel (two words: r | g << 16, b | a << 16).
pub fn load_rgba16f(w: &Words<'_>, texel: usize) -> [f32; 4] {
    let (lo, hi) = (w.load(2 * texel), w.load(2 * texel + 1));
    [lo & 0xFFFF, lo >> 16, hi & 0xFFFF, hi >> 16].map(|h| f16::from_bits(h as u16).to_f32())
}

pub fn store_rgba16f(w: &Words<'_>, texel: usize, c: [f32; 4]) {
    let h = c.map(|x| u32::from(f16::from_f32(x).to_bits()));
    w.store(2 * texel, h[0] | (h[1] << 16));
    w.store(2 * texel + 1, h[2] | (h[3] << 16));
}

impl CpuKernel for ResolveKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let (width, pixels) = (ctx.quantities.width, ctx.quantities.count(Quantity::Pixels));
        let tiles = scene.tiles(ctx);
        let (vis, cov, out, layers) = (
            ctx.words("vis_atlas"),
            ctx.words("coverage_atlas"),
            ctx.words("output"),
            ctx.words("debug_layers"),
        );
        let stride = vis.len() / LAYERS;
        debug_assert_eq!(stride % TILE_TEXELS as usize, 0);
        for i in group * GROUP..((group + 1) * GROUP).min(pixels as u32) {
            let (x, y) = (i % width, i / width);
            let mut color = load_rgba16f(&out, i as usize);
            let mut debug = 0u32;
            for (m, t) in tiles.iter().enumerate() {
                let Some(texel) = t.texel(x, y) else { continue };
                let alpha = total_coverage(cov.load(texel as usize));
                if alpha <= 0.0 {
                    continue;
                }
                let c = scene.models[m].color;
                for k in 0..3 {
                    color[k] = color[k] * (1.0 - alpha) + c[k] * alpha;
                }
                color[3] = color[3] * (1.0 - alpha) + alpha;
                if debug == 0 {
                    let depth = |l: usize| {
                        let p = vis.load(texel as usize + l * stride);
                        if p == EMPTY { 0 } else { 255 - depth_of(p) / 4 }
                    };
                    debug = depth(0)
                        | depth(1) << 8
                        | depth(2) << 16
                        | ((alpha * 255.0).round() as u32) << 24;
                }
            }
            store_rgba16f(&out, i as usize, color);
            layers.store(i as usize, debug);
        }
    }
}
