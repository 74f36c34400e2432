//! `reference.resolve`: per pixel, every hair fragment at every sample,
//! blended front to back over the opaque image.
//!
//! A workgroup per 8 × 8 tile, a lane per pixel. The lane walks its
//! tile's whole segment list, however long (no layer limit), and for every
//! segment that reaches the pixel tests each sample: a sample keeps the
//! nearest fragment covering it, by its depth at that sample (ties to the
//! lower segment id, so every backend picks alike). Strands are opaque (as
//! in Kulikov's pipeline, where coverage comes from width alone), so
//! blending a sample's fragments front to back leaves exactly the nearest
//! one: no sort is needed, and none of a sort's approximations (per-pixel
//! rather than per-sample order) enter. A sample shows that fragment's
//! per-vertex lighting, interpolated perspective-correctly, unless the
//! opaque scene is nearer; the pixel is the mean of its samples over the
//! opaque image.
//!
//! Not exact: the head's depth is one value per pixel, so its silhouette
//! is not antialiased (the same in every pipeline compared). Strands with
//! an opacity below one would need the fragments sorted per sample; no
//! groom format read here carries one.

use super::ribbon::{MAX_SAMPLES_PER_AXIS, Record, sample_position};
use super::{TILE, tiles};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::kulikov::compose::ndc_depth;
use crate::kulikov::debug_resolve::{load_rgba16f, store_rgba16f};
use crate::layout::{FrameData, read};
use crate::params::{Invalid, PassParams, in_range};
use strandgraph_graph::schema::Quantity;

const GROUP: u32 = TILE * TILE;
const MAX_SAMPLES: usize = (MAX_SAMPLES_PER_AXIS * MAX_SAMPLES_PER_AXIS) as usize;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ResolveParams {
    /// `n`: n × n stratified samples per pixel (8: 64, 16: 256).
    pub samples_per_axis: u32,
}

impl Default for ResolveParams {
    fn default() -> Self {
        Self {
            samples_per_axis: 8,
        }
    }
}

impl PassParams for ResolveParams {
    fn validate(&self) -> Result<(), Invalid> {
        in_range(
            "samples_per_axis",
            self.samples_per_axis,
            1..=MAX_SAMPLES_PER_AXIS,
        )
    }
}

crate::gpu_block! {
    /// `ResolveParams` in shaders/reference/resolve.wgsl.
    pub struct ResolveGpu {
        samples_per_axis: u32,
        width: u32,
        height: u32,
        tiles_x: u32,
    }
}

pub static RESOLVE: PassKind<ResolveParams, ResolveGpu> = PassKind {
    kind: "reference.resolve",
    summary: "per pixel, n x n stratified samples, each the nearest covering fragment of every listed segment (opaque strands blended front to back), no layer limit",
    source: "ours: the ground-truth reference (docs/reference.md)",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("reference_offsets"),
        Binding::read("reference_segments"),
        Binding::read("reference_ribbons"),
        Binding::read("vertex_lighting"),
        Binding::read("scene.depth"),
        // Blended in place (read_write storage image).
        Binding::write("output"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Tiles(TILE),
        per_group: 1,
    },
    shader: Shader::compute("reference/resolve.wgsl", "resolve"),
    kernel: |p| Box::new(ResolveKernel(*p)),
    gpu: |p, q| ResolveGpu {
        samples_per_axis: p.samples_per_axis,
        width: q.width,
        height: q.height,
        tiles_x: tiles(q.width, q.height).0,
    },
    raster: None,
};

/// A listed segment: its id (the tie-break), ribbon and end vertices.
#[derive(Debug, Clone, Copy)]
pub struct Candidate {
    pub id: u32,
    pub record: Record,
}

/// Where pixel `(x, y)` is resolved, and what hides the hair there.
#[derive(Debug, Clone, Copy)]
pub struct Pixel {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub samples_per_axis: u32,
    /// The opaque scene's NDC depth.
    pub scene_z: f32,
    pub near: f32,
    pub far: f32,
}

/// The hair's radiance at `px` (the mean over samples) and the fraction of
/// samples no hair covers. `lighting(vertices, t)` is the radiance at world
/// parameter `t` along the segment.
pub fn resolve_pixel(
    px: &Pixel,
    list: &[Candidate],
    lighting: impl Fn([u32; 2], f32) -> [f32; 3],
) -> ([f32; 3], f32) {
    let n = px.samples_per_axis;
    let samples = (n * n) as usize;
    let centre = [px.x as f32 + 0.5, px.y as f32 + 0.5];
    let mut at = [[0.0f32; 2]; MAX_SAMPLES];
    for (s, p) in at.iter_mut().enumerate().take(samples) {
        *p = sample_position(px.x, px.y, px.width, n, s as u32);
    }
    // Per sample, the nearest covering fragment: (view depth, list index).
    let mut nearest = [(f32::MAX, NONE); MAX_SAMPLES];
    for (i, c) in list.iter().enumerate() {
        let r = &c.record.ribbon;
        if !r.may_touch(centre, 0.5) {
            continue;
        }
        for s in 0..samples {
            let Some(t) = r.covers(at[s]) else {
                continue;
            };
            let z = r.depth_at(t);
            let (bz, bi) = nearest[s];
            // Ties go to the lower segment id, so every backend picks alike.
            if z < bz || (z == bz && (bi == NONE || c.id < list[bi].id)) {
                nearest[s] = (z, i);
            }
        }
    }
    let mut sum = [0.0f32; 3];
    let mut open = 0u32;
    for s in 0..samples {
        let (z, i) = nearest[s];
        // The opaque scene is nearer: no hair at this sample.
        if i == NONE || ndc_depth(z, px.near, px.far) > px.scene_z {
            open += 1;
            continue;
        }
        let c = &list[i].record;
        let t = c.ribbon.covers(at[s]).unwrap_or(0.0);
        let l = lighting(c.vertices, c.ribbon.world_t(t));
        for k in 0..3 {
            sum[k] += l[k];
        }
    }
    let inv = 1.0 / samples as f32;
    (sum.map(|v| v * inv), open as f32 * inv)
}

/// No fragment at a sample.
const NONE: usize = usize::MAX;

struct ResolveKernel(ResolveParams);

impl CpuKernel for ResolveKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let frame: FrameData = read(&ctx.words("frame"), 0);
        let (w, h) = (ctx.quantities.width, ctx.quantities.height);
        let tiles_x = tiles(w, h).0;
        let (offsets, ids, records) = (
            ctx.words("reference_offsets"),
            ctx.words("reference_segments"),
            ctx.words("reference_ribbons"),
        );
        let (light, depth, out) = (
            ctx.words("vertex_lighting"),
            ctx.words("scene.depth"),
            ctx.words("output"),
        );
        // The tile's list, cut at the lists' capacity as the fill cut it.
        let end = (offsets.load(group as usize + 1) as usize).min(ids.len());
        let start = (offsets.load(group as usize) as usize).min(end);
        // Each lane loads these from memory; here once per workgroup.
        let list: Vec<Candidate> = (start..end)
            .filter_map(|e| {
                let id = ids.load(e);
                Some(Candidate {
                    id,
                    record: Record::load(&records, id as usize)?,
                })
            })
            .collect();
        let lighting = |v: [u32; 2], t: f32| {
            let (a, b) = (
                load_rgba16f(&light, v[0] as usize),
                load_rgba16f(&light, v[1] as usize),
            );
            [0, 1, 2].map(|k| a[k] + t * (b[k] - a[k]))
        };
        let (tx, ty) = (group % tiles_x * TILE, group / tiles_x * TILE);
        for lane in 0..GROUP {
            let (x, y) = (tx + lane % TILE, ty + lane / TILE);
            if x >= w || y >= h {
                continue;
            }
            let texel = (y * w + x) as usize;
            let px = Pixel {
                x,
                y,
                width: w,
                samples_per_axis: self.0.samples_per_axis,
                scene_z: depth.load_f32(texel),
                near: frame.near,
                far: frame.far,
            };
            let (hair, open) = resolve_pixel(&px, &list, lighting);
            let bg = load_rgba16f(&out, texel);
            let c = [0, 1, 2].map(|k| hair[k] + open * bg[k]);
            store_rgba16f(&out, texel, [c[0], c[1], c[2], 1.0 - open * (1.0 - bg[3])]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::ribbon::Ribbon;

    /// A horizontal ribbon across pixel (0, 0) at height `y`, half width
    /// `h`, view depth `w`; its colour is its vertex index.
    fn across(id: u32, y: f32, h: f32, w: f32) -> Candidate {
        let ribbon = Ribbon {
            a: [-4.0, y],
            b: [4.0, y],
            ha: h,
            hb: h,
            wa: w,
            wb: w,
            join_a: false,
            join_b: false,
            range: [0.0, 1.0],
        };
        Candidate {
            id,
            record: Record {
                ribbon,
                vertices: [id, id],
            },
        }
    }

    const PX: Pixel = Pixel {
        x: 0,
        y: 0,
        width: 16,
        samples_per_axis: 8,
        scene_z: 1.0,
        near: 0.1,
        far: 100.0,
    };

    fn colour(v: [u32; 2], _: f32) -> [f32; 3] {
        [v[0] as f32, 1.0, 0.0]
    }

    #[test]
    fn a_ribbon_covers_its_width_of_the_pixel() {
        // A quarter-pixel band: 8 x 8 stratified samples find it within a row.
        let (hair, open) = resolve_pixel(&PX, &[across(3, 0.5, 0.125, 1.0)], colour);
        assert!((open - 0.75).abs() <= 0.125, "{open}");
        assert!((hair[1] - (1.0 - open)).abs() < 1e-6);
        assert!((hair[0] - 3.0 * (1.0 - open)).abs() < 1e-5);
    }

    #[test]
    fn each_sample_shows_the_nearest_fragment_whatever_the_list_order() {
        let near = across(1, 0.5, 1.0, 2.0);
        let far = across(2, 0.5, 1.0, 3.0);
        for list in [[near, far], [far, near]] {
            let (hair, open) = resolve_pixel(&PX, &list, colour);
            assert_eq!(open, 0.0);
            assert!((hair[0] - 1.0).abs() < 1e-6, "{hair:?}");
        }
        // At equal depth the lower segment id wins, on every backend alike.
        let twin = across(0, 0.5, 1.0, 2.0);
        let (hair, _) = resolve_pixel(&PX, &[near, twin], colour);
        assert_eq!(hair[0], 0.0);
    }

    #[test]
    fn the_opaque_scene_hides_hair_behind_it() {
        let hidden = Pixel {
            scene_z: ndc_depth(1.5, PX.near, PX.far),
            ..PX
        };
        let (hair, open) = resolve_pixel(&hidden, &[across(1, 0.5, 1.0, 2.0)], colour);
        assert_eq!((hair, open), ([0.0; 3], 1.0));
        let (_, open) = resolve_pixel(&hidden, &[across(1, 0.5, 1.0, 1.2)], colour);
        assert_eq!(open, 0.0);
    }
}
