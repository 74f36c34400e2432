//! `kulikov.compose`: each hair model's visibility atlas, lit and blended
//! over the opaque image, back to front.
//!
//! Kulikov, "Composition": "Sort back to front. Camera-facing quad for each
//! hair piece ... Output lighting, depth and motion" and "Coverage
//! reconstruction" ([`reconstruct`]). The talk draws a quad per model with
//! premultiplied blending; here one compute lane per screen pixel visits the
//! models in the same back-to-front order and blends the same way, on the
//! GPU (`shaders/kulikov/compose.wgsl`) as on the CPU: Hopper runs pixel
//! shaders on few of its SMs, and the quads ran the reconstruction twice per
//! pixel (colour, then depth). Hair depth goes to the `hair_depth` image
//! (R32Float, NDC: the scene's depth where no hair is nearer), since compute
//! cannot write a depth attachment.
//!
//! Per pixel and model (parameters in brackets):
//! - the atlas texel, jittered by a fixed Poisson-disk pattern hashed by
//!   pixel where the model's tiles were downscaled ("Resolve stochastically
//!   to avoid pixelation. Poisson disk distribution for samples")
//!   [`poisson_samples`, 0 = off];
//! - `C_total` from the additive layer [`coverage_fit`: `"Quadratic"`, the
//!   shipped fit; `"Exponential"`, 1 − e^−x, the random-lines limit];
//! - per layer: the segment from the payload, its coverage of this texel
//!   [`layer_coverage`: `"Exact"`, the area of the segment's trapezoid in the
//!   texel, as `kulikov.raster` measured it (by edge integration rather than
//!   the raster's clipping, [`Trapezoid::pixel_coverage`] says why); `"Width"`, the projected
//!   strand width in texels, clamped to 1: a strand crossing the pixel covers
//!   about its width of it], and its lighting interpolated along the segment
//!   from `vertex_lighting` at the pixel centre's projection;
//! - [`reconstruct`] [`reconstruct_missing`: false uses the 3 front layers only;
//!   `layers`: how many of the 3 it reads, for the one-layer ablation];
//! - hair depth (the front layer's) where the result's coverage reaches
//!   [`depth_threshold`] and is nearer than `scene.depth`, into `hair_depth`;
//! - per-pixel motion ([`motion`]): of the front segment that wrote the
//!   depth, else the depth reprojected, into `pixel_motion`.
//!
//! Models sort by the view depth of their bounds' centre; facial hair is
//! pushed back by [`facial_hair_bias`] metres so it composes before the
//! main hair piece ("Large bias for facial hair").

pub mod motion;
pub mod reconstruct;
#[cfg(test)]
mod tests;

use super::cull::drawn_segment;
use super::debug_resolve::{load_rgba16f, store_rgba16f};
use super::payload::{COVERAGE_SCALE, EMPTY, segment_of, total_coverage};
use super::raster::geometry::Trapezoid;
use super::raster::{LAYERS, segment_trapezoid};
use super::tile_alloc::ModelTiles;
use super::{Scene, TILE};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, flag};
use crate::describe::PassKind;
use crate::kernel::{CounterValues, Ctx, Words};
use crate::layout::{FrameData, MODEL_FACIAL_HAIR, read};
use crate::params::{Invalid, PassParams, in_range};
use motion::Front;
use reconstruct::{Layer, reconstruct};
use strandgraph_graph::Quantities;
use strandgraph_graph::schema::Quantity;
pub const GROUP: u32 = 256;

/// A fixed Poisson-disk pattern in the unit disk (minimum distance 0.5),
/// scaled by half the downscale factor.
pub const POISSON: [[f32; 2]; 8] = [
    [0.0, 0.0],
    [0.62, 0.18],
    [-0.45, 0.55],
    [0.12, -0.71],
    [-0.66, -0.32],
    [0.38, 0.78],
    [0.85, -0.45],
    [-0.1, 0.95],
];

crate::string_enum! {
    /// Kulikov's coverage reconstruction from the summed coverage.
    pub enum CoverageFit {
        Quadratic,
        /// 1 − exp(−x).
        Exponential,
    }
}

crate::string_enum! {
    /// What a layer's coverage is measured by.
    pub enum LayerCoverage {
        /// The exact trapezoid area.
        Exact,
        /// The projected width.
        Width,
    }
}

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ComposeParams {
    /// Poisson-disk atlas samples per pixel (0..=8).
    pub poisson_samples: u32,
    pub coverage_fit: CoverageFit,
    pub layer_coverage: LayerCoverage,
    pub reconstruct_missing: bool,
    pub depth_threshold: f32,
    pub facial_hair_bias: f32,
    /// Ours: each workgroup first drops the models whose tiles cannot reach
    /// its pixels ([`reaches`]), so a pixel visits only nearby models.
    pub workgroup_cull: bool,
    /// The atlas layers composition reads, front first (1..=3). The talk
    /// reads its 3; fewer measure what the extra layers buy against the
    /// reference (the raster still writes all 3).
    pub layers: u32,
}

impl Default for ComposeParams {
    fn default() -> Self {
        Self {
            poisson_samples: 8,
            coverage_fit: CoverageFit::Quadratic,
            layer_coverage: LayerCoverage::Exact,
            reconstruct_missing: true,
            depth_threshold: 0.75,
            facial_hair_bias: 0.5,
            workgroup_cull: true,
            layers: LAYERS as u32,
        }
    }
}

impl PassParams for ComposeParams {
    fn validate(&self) -> Result<(), Invalid> {
        in_range(
            "poisson_samples",
            self.poisson_samples,
            0..=POISSON.len() as u32,
        )?;
        in_range("layers", self.layers, 1..=LAYERS as u32)
    }
}

impl ComposeParams {
    /// Coverage fit 1 − exp(−x) rather than quadratic.
    pub fn exponential_fit(&self) -> bool {
        self.coverage_fit == CoverageFit::Exponential
    }
    /// Layer coverage by projected width rather than exact area.
    pub fn width_coverage(&self) -> bool {
        self.layer_coverage == LayerCoverage::Width
    }

    /// The WGSL `ComposeParams` block (binding 0, 32 bytes).
    pub fn uniform(&self, q: &Quantities) -> ComposeGpu {
        ComposeGpu {
            poisson_samples: self.poisson_samples,
            exponential_fit: flag(self.exponential_fit()),
            width_coverage: flag(self.width_coverage()),
            reconstruct_missing: flag(self.reconstruct_missing),
            depth_threshold: self.depth_threshold,
            facial_hair_bias: self.facial_hair_bias,
            width: q.width,
            height: q.height,
            workgroup_cull: flag(self.workgroup_cull),
            layers: self.layers,
        }
    }
}

crate::gpu_block! {
    /// `ComposeParams` in shaders/kulikov/compose.wgsl.
    pub struct ComposeGpu {
        poisson_samples: u32,
        /// 0 Quadratic, 1 Exponential.
        exponential_fit: u32,
        /// 0 Exact, 1 Width.
        width_coverage: u32,
        reconstruct_missing: u32,
        depth_threshold: f32,
        facial_hair_bias: f32,
        width: u32,
        height: u32,
        workgroup_cull: u32,
        /// Atlas layers read, 1..=3.
        layers: u32,
    }
}

pub static COMPOSE: PassKind<ComposeParams, ComposeGpu> = PassKind {
    kind: "kulikov.compose",
    summary: "per pixel, models back to front: coverage reconstruction, weighted lighting, Poisson-disk atlas sampling, hair depth and motion",
    source: "Kulikov 2025, 'Composition', 'Motion vectors'",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("lod_models"),
        Binding::read("atlas_tiles"),
        Binding::read("vis_atlas"),
        Binding::read("coverage_atlas"),
        Binding::read("vertex_lighting"),
        Binding::read("clip_positions"),
        Binding::read("groom.vertices"),
        Binding::read("scene.depth"),
        // Blended in place (read_write storage image).
        Binding::write("output"),
        Binding::write("hair_depth"),
        Binding::read("prev_frame"),
        Binding::read("vertex_motion"),
        Binding::write("pixel_motion"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Pixels,
        per_group: GROUP,
    },
    shader: Shader::compute("kulikov/compose.wgsl", "compose"),
    kernel: |p| Box::new(ComposeKernel(*p)),
    gpu: |p, q| p.uniform(q),
    raster: None,
};

/// Back-to-front model order: farthest (bias included) first.
pub fn model_order(scene: &Scene, facial_hair_bias: f32) -> Vec<usize> {
    let cam = &scene.frame.camera_pos;
    let mut keys: Vec<(f32, usize)> = scene
        .models
        .iter()
        .enumerate()
        .map(|(m, md)| {
            let d: f32 = (0..3)
                .map(|a| (0.5 * (md.bounds_min[a] + md.bounds_max[a]) - cam[a]).powi(2))
                .sum::<f32>()
                .sqrt();
            let bias = if md.flags & MODEL_FACIAL_HAIR != 0 {
                facial_hair_bias
            } else {
                0.0
            };
            (d + bias, m)
        })
        .collect();
    keys.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    keys.into_iter().map(|(_, m)| m).collect()
}

/// A small integer hash (PCG-style) of a pixel.
pub fn pixel_hash(x: u32, y: u32) -> u32 {
    let mut h = x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^ (h >> 12)
}

/// NDC depth of view depth `w` under `perspective_rh` (inverse of `linear_depth`).
pub fn ndc_depth(w: f32, near: f32, far: f32) -> f32 {
    far * (w - near) / (w * (far - near))
}

/// Where pixel `(x, y)` samples a model's atlas downscaled `d` times: a
/// Poisson-disk jitter of up to half the downscale, hashed by pixel.
pub fn sample_at(
    x: u32,
    y: u32,
    d: u32,
    poisson_samples: u32,
    width: u32,
    height: u32,
) -> (u32, u32) {
    if d <= 1 || poisson_samples == 0 {
        return (x, y);
    }
    let k = pixel_hash(x, y) % poisson_samples;
    let r = 0.5 * d as f32;
    let [jx, jy] = POISSON[k as usize];
    (
        (x as f32 + 0.5 + jx * r).clamp(0.0, width as f32 - 1.0) as u32,
        (y as f32 + 0.5 + jy * r).clamp(0.0, height as f32 - 1.0) as u32,
    )
}

/// The screen rectangle of workgroup `group`'s pixels (a lane per pixel,
/// row-major), inclusive.
pub fn group_span(group: u32, width: u32, height: u32) -> [u32; 4] {
    let last = width * height - 1;
    let i0 = (group * GROUP).min(last);
    let i1 = (i0 + GROUP - 1).min(last);
    let (y0, y1) = (i0 / width, i1 / width);
    if y0 == y1 {
        [i0 % width, y0, i1 % width, y1]
    } else {
        [0, y0, width - 1, y1]
    }
}

/// Whether any pixel of `span` can sample `t`'s tiles: their screen
/// rectangle grown by the Poisson jitter (under half the downscale).
pub fn reaches(t: &ModelTiles, span: [u32; 4]) -> bool {
    if t.valid == 0 {
        return false;
    }
    let d = t.downscale.max(1);
    let (edge, margin) = (TILE * d, d / 2 + 1);
    let (lo_x, lo_y) = (t.origin_x * edge, t.origin_y * edge);
    let (hi_x, hi_y) = (
        (t.origin_x + t.grid_w) * edge,
        (t.origin_y + t.grid_h) * edge,
    );
    let [x0, y0, x1, y1] = span;
    x1 + margin >= lo_x && x0 < hi_x + margin && y1 + margin >= lo_y && y0 < hi_y + margin
}

struct ComposeKernel(ComposeParams);

struct Model<'a> {
    tiles: ModelTiles,
    seg_first: u32,
    lod: super::ModelLod,
    _w: std::marker::PhantomData<&'a ()>,
}

/// Where raster texel `(u, v)`'s centre projects on the segment's axis, in
/// [0, 1] from `a` to `b`: the weight lighting and motion interpolate with.
pub(crate) fn axis_t(trap: &Trapezoid, u: i32, v: i32) -> f32 {
    let c = [u as f32 + 0.5, v as f32 + 0.5];
    let d = [trap.b[0] - trap.a[0], trap.b[1] - trap.a[1]];
    (((c[0] - trap.a[0]) * d[0] + (c[1] - trap.a[1]) * d[1]) / (d[0] * d[0] + d[1] * d[1]))
        .clamp(0.0, 1.0)
}

/// One atlas layer of a texel as composition reads it.
struct Sample {
    layer: Layer,
    /// View depth at the texel.
    depth: f32,
    /// The segment, and where the texel centre projects on it.
    front: Front,
}

impl ComposeKernel {
    /// The up-to-3 layers of one texel.
    #[allow(clippy::too_many_arguments)]
    fn layers(
        &self,
        scene: &Scene,
        lods: &[super::ModelLod],
        ctx: &Ctx<'_>,
        md: &Model<'_>,
        texel: usize,
        u: i32,
        v: i32,
    ) -> Vec<Sample> {
        let (vis, light) = (ctx.words("vis_atlas"), ctx.words("vertex_lighting"));
        let stride = vis.len() / LAYERS;
        let mut out = Vec::with_capacity(LAYERS);
        for l in 0..(self.0.layers as usize).min(LAYERS) {
            let p = vis.load(texel + l * stride);
            if p == EMPTY {
                break;
            }
            let id = md.seg_first + segment_of(p);
            let Some(seg) = drawn_segment(scene, lods, id) else {
                continue;
            };
            let Some((trap, part)) =
                segment_trapezoid(scene, ctx, &md.tiles, &md.lod, seg.v0, seg.v1)
            else {
                continue;
            };
            let t = axis_t(&trap, u, v);
            let coverage = if self.0.width_coverage() {
                let pts = trap.quad.points();
                let w0 = ((pts[0][0] - pts[3][0]).powi(2) + (pts[0][1] - pts[3][1]).powi(2)).sqrt();
                let w1 = ((pts[1][0] - pts[2][0]).powi(2) + (pts[1][1] - pts[2][1]).powi(2)).sqrt();
                (w0 + t * (w1 - w0)).clamp(0.0, 1.0)
            } else {
                trap.pixel_coverage(u, v)
            };
            let (l0, l1) = (
                load_rgba16f(&light, seg.v0 as usize),
                load_rgba16f(&light, seg.v1 as usize),
            );
            // The vertex lighting at the ends of the part in front of the near plane.
            let lighting = [0, 1, 2].map(|k| {
                let [a, b] = part.ends(l0[k], l1[k]);
                a + t * (b - a)
            });
            out.push(Sample {
                layer: Layer { coverage, lighting },
                depth: trap.depth_at(u, v),
                front: Front {
                    ends: [seg.v0, seg.v1],
                    t,
                },
            });
        }
        out
    }
}

impl CpuKernel for ComposeKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let (width, height) = (ctx.quantities.width, ctx.quantities.height);
        let pixels = ctx.quantities.count(Quantity::Pixels) as u32;
        let lods = scene.lods(ctx);
        let tiles = scene.tiles(ctx);
        let span = group_span(group, width, height);
        let models: Vec<Model<'_>> = model_order(&scene, self.0.facial_hair_bias)
            .into_iter()
            .filter(|&m| tiles[m].valid != 0)
            .filter(|&m| !self.0.workgroup_cull || reaches(&tiles[m], span))
            .map(|m| Model {
                tiles: tiles[m],
                seg_first: scene.models[m].segment_first,
                lod: lods[m],
                _w: std::marker::PhantomData,
            })
            .collect();
        let (cov, out, depth, hair_depth): (Words<'_>, Words<'_>, Words<'_>, Words<'_>) = (
            ctx.words("coverage_atlas"),
            ctx.words("output"),
            ctx.words("scene.depth"),
            ctx.words("hair_depth"),
        );
        let (vertex_motion, pixel_motion) = (ctx.words("vertex_motion"), ctx.words("pixel_motion"));
        let prev: FrameData = read(&ctx.words("prev_frame"), 0);
        let (near, far) = (scene.frame.near, scene.frame.far);
        let mut tally = CounterValues::default();
        for i in group * GROUP..((group + 1) * GROUP).min(pixels) {
            let (x, y) = (i % width, i / width);
            let mut color = load_rgba16f(&out, i as usize);
            let mut z_out = depth.load_f32(i as usize);
            // The front layer that wrote the depth, for motion.
            let mut front = None;
            let mut touched = false;
            for md in &models {
                let d = md.tiles.downscale;
                let (sx, sy) = sample_at(x, y, d, self.0.poisson_samples, width, height);
                let Some(texel) = md.tiles.texel(sx, sy) else {
                    continue;
                };
                let additive = cov.load(texel as usize);
                if additive == 0 {
                    continue;
                }
                let c_total = if self.0.exponential_fit() {
                    1.0 - (-(additive as f32) / COVERAGE_SCALE).exp()
                } else {
                    total_coverage(additive)
                };
                let u = (sx / d - md.tiles.origin_x * TILE) as i32;
                let v = (sy / d - md.tiles.origin_y * TILE) as i32;
                let samples = self.layers(&scene, &lods, ctx, md, texel as usize, u, v);
                let ls: Vec<Layer> = samples.iter().map(|s| s.layer).collect();
                let (hair, alpha) = reconstruct(&ls, c_total, self.0.reconstruct_missing);
                for k in 0..3 {
                    color[k] = hair[k] + (1.0 - alpha) * color[k];
                }
                color[3] = alpha + (1.0 - alpha) * color[3];
                touched = true;
                if alpha >= self.0.depth_threshold
                    && let Some(s) = samples.first()
                {
                    let z = ndc_depth(s.depth, near, far);
                    if z < z_out {
                        z_out = z;
                        front = Some(s.front);
                    }
                }
            }
            hair_depth.store_f32(i as usize, z_out);
            let m = motion::pixel_motion(front, &vertex_motion, &scene.frame, &prev, (x, y), z_out);
            pixel_motion.store_f32(2 * i as usize, m[0]);
            pixel_motion.store_f32(2 * i as usize + 1, m[1]);
            if touched {
                store_rgba16f(&out, i as usize, color);
                tally.pixels_written += 1;
            }
        }
        if ctx.instrument {
            ctx.counters.add(&tally);
        }
    }
}
