//! `lipp.occlusion` (ours): bundles hidden behind the opaque meshes draw no
//! strand. The paper culls bundles only against the frustum (§3.2); at the
//! close view a third of a long groom hangs behind the head and shoulders,
//! and the rasterizer assembles and walks every one of those strands only
//! for the scene-depth test to reject each sample.
//!
//! One thread per bundle, after `lipp.lod`: its decisions are copied from
//! `lod_choices` to `lod_visible`, a bundle the LOD kept flagged
//! [`LOD_OCCLUDED`] when every part of it is
//! behind the farthest opaque depth of the 16×16 blocks it covers
//! (`kulikov.depth_downsample`'s Hi-Z, Kulikov's occlusion test applied to
//! bundles). `lipp.lod_scan` then draws none of its strands, while β of
//! Eq. 8 still counts them, so the cull changes no shading.
//!
//! The test must be conservative, since a culled bundle's strands are never
//! assembled. A bundle is cut into a box per Hermite piece, between two
//! consecutive layers (with at least as many control points as layers,
//! which Eq. 4 ensures unless C_max is smaller, a chord lies in one piece or
//! across one layer; otherwise one box over all layers), each bounding what
//! assembly can produce
//! there (`strand::eval_cp`):
//! - the layer quads' bilinear patches over (u, v) ∈ [−¼, 1¼]²: the twist
//!   rotates a strand's (u, v) about the centre, reaching 0.5 − √½ ≈ −0.21;
//!   a bilinear patch lies in the hull of its four corners;
//! - widened by the Hermite bulge, at most 8/27 of a piece's chord (the
//!   basis h10 and h11 peak at 4/27 with unit tangents scaled by the chord);
//! - and by the styling offsets, curl radius plus √3 × noise amplitude.
//!
//! A box is hidden when all eight corners are in front of the near plane and
//! its nearest NDC depth is beyond the Hi-Z of every block its screen
//! rectangle (one pixel wider, for the sub-pixel snap) covers, or when the
//! rectangle is off screen. Boxes over more than [`MAX_BLOCKS`] blocks are
//! not tested.
//!
//! A long groom is rarely hidden whole: its tips hang beside the shoulders.
//! So the pass also records which boxes are hidden (bits from
//! [`BOX_BITS_SHIFT`] of the flags), and `lipp.raster` skips each segment
//! inside a hidden box ([`segment_hidden`]) before walking it.

use super::super::{
    BUNDLE_WORDS, BundleLod, BundleRecord, Corner, LOD_OCCLUDED, LOD_WORDS, bundle_count, frame,
    transform,
};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::kulikov::clip_to_screen;
use crate::kulikov::depth_downsample::FACTOR;
use crate::layout::FrameData;
use crate::params::{Invalid, PassParams};
use strandgraph_graph::schema::Quantity;

/// Threads per workgroup, one bundle each.
const GROUP: u32 = 64;
/// How far the twist carries (u, v) outside the unit square, rounded up.
const TWIST_REACH: f32 = 0.25;
/// Hermite bulge over the chord: 2 × 4/27, rounded up.
const HERMITE_BULGE: f32 = 0.3;
/// |2 id − 1| ≤ √3 for the noise offset, rounded up.
const NOISE_REACH: f32 = 1.75;
/// Hi-Z blocks a box may cover and still be tested.
pub const MAX_BLOCKS: u32 = 1024;
/// First bit of the hidden boxes in a bundle's flags (box j: bit 16 + j;
/// 16 layers make 15 boxes).
pub const BOX_BITS_SHIFT: u32 = 16;
/// NDC depth a box must be beyond its blocks' Hi-Z: covers the rounding of
/// the rasterizer's interpolated depth.
const DEPTH_MARGIN: f32 = 1e-5;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct OcclusionParams {
    /// Off: every decision is copied unchanged.
    pub enabled: bool,
}

impl Default for OcclusionParams {
    fn default() -> Self {
        Self { enabled: true }
    }
}

impl PassParams for OcclusionParams {
    fn validate(&self) -> Result<(), Invalid> {
        Ok(())
    }
}

crate::gpu_block! {
    /// `OcclusionParams` in shaders/lipp/occlusion.wgsl.
    pub struct OcclusionGpu {
        enabled: u32,
        /// Scene quantity: bundles packed.
        bundles: u32,
        _pad0: u32,
        _pad1: u32,
    }
}

pub static OCCLUSION: PassKind<OcclusionParams, OcclusionGpu> = PassKind {
    kind: "lipp.occlusion",
    summary: "bundles behind the opaque depth's Hi-Z draw no strand (ours); β of Eq. 8 unchanged",
    source: "ours, after Kulikov 2025 'Culling' (Hi-Z occlusion) applied to Lipp's bundles",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("hairmesh.bundles"),
        Binding::read("hairmesh.layers"),
        Binding::read("hiz"),
        Binding::read("lod_choices"),
        Binding::write("lod_visible"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Bundles,
        per_group: GROUP,
    },
    shader: Shader::compute("lipp/occlusion.wgsl", "occlusion"),
    kernel: |p| Box::new(OcclusionKernel(*p)),
    gpu: |p, q| OcclusionGpu {
        enabled: flag(p.enabled),
        bundles: count(q.bundles),
        ..OcclusionGpu::default()
    },
    raster: None,
};

type V3 = [f32; 3];

/// Corner `k` of layer `layer`'s quad extended to (u, v) ∈ [−¼, 1¼]²
/// (bilinear, as `strand::layer_point` evaluates it).
fn extended_corner(layers: &Words<'_>, layer: usize, k: usize) -> V3 {
    let c = |k: usize| Corner::load(layers, layer, k).position;
    let lerp = |a: V3, b: V3, t: f32| [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t);
    let (lo, hi) = (-TWIST_REACH, 1.0 + TWIST_REACH);
    let (u, v) = [(lo, lo), (hi, lo), (hi, hi), (lo, hi)][k];
    lerp(lerp(c(0), c(1), u), lerp(c(3), c(2), u), v)
}

fn distance(a: V3, b: V3) -> f32 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// Whether the world box `lo`..`hi` is off screen or behind the Hi-Z.
pub fn box_hidden(f: &FrameData, hiz: &Words<'_>, lo: V3, hi: V3) -> bool {
    let (w, h) = (f.screen[0], f.screen[1]);
    let (mut s_lo, mut s_hi, mut nearest) = ([f32::MAX; 2], [f32::MIN; 2], f32::MAX);
    for i in 0..8 {
        let pick = |axis: usize| {
            if i >> axis & 1 == 1 {
                hi[axis]
            } else {
                lo[axis]
            }
        };
        let c = transform(&f.view_proj, [pick(0), pick(1), pick(2), 1.0]);
        if c[3] <= f.near {
            return false;
        }
        let s = clip_to_screen(c, w, h);
        s_lo = [s_lo[0].min(s[0]), s_lo[1].min(s[1])];
        s_hi = [s_hi[0].max(s[0]), s_hi[1].max(s[1])];
        nearest = nearest.min(s[2]);
    }
    // One pixel wider: the rasterizer snaps ends to 1/256 pixel.
    let (x0, y0, x1, y1) = (s_lo[0] - 1.0, s_lo[1] - 1.0, s_hi[0] + 1.0, s_hi[1] + 1.0);
    if x1 < 0.0 || y1 < 0.0 || x0 >= w || y0 >= h {
        return true;
    }
    let block = |v: f32, size: f32| (v.clamp(0.0, size - 1.0) as u32) / FACTOR;
    let (bx0, by0, bx1, by1) = (block(x0, w), block(y0, h), block(x1, w), block(y1, h));
    if (bx1 - bx0 + 1) * (by1 - by0 + 1) > MAX_BLOCKS {
        return false;
    }
    let hw = (w as u32).div_ceil(FACTOR);
    for by in by0..=by1 {
        for bx in bx0..=bx1 {
            if hiz.load_f32((by * hw + bx) as usize) + DEPTH_MARGIN >= nearest {
                return false;
            }
        }
    }
    true
}

/// The boxes (world `lo`, `hi`) that bound everything bundle `b` can draw
/// at `c` control points (module documentation): one per Hermite piece,
/// between layers j and j + 1, or their union when `c` is below the layer
/// count (C_max < layers), where a chord may span several layers.
pub fn bundle_boxes(layers: &Words<'_>, b: &BundleRecord, c: u32) -> Vec<(V3, V3)> {
    let n = b.layers() as usize;
    let first = b.first_layer as usize;
    let style = b.curl_radius.abs() + NOISE_REACH * b.noise.abs();
    let boxes = (0..n - 1).map(|j| {
        let (mut lo, mut hi, mut chord) = ([f32::MAX; 3], [f32::MIN; 3], 0.0f32);
        for k in 0..4 {
            let p = extended_corner(layers, first + j, k);
            for l in 0..4 {
                let q = extended_corner(layers, first + j + 1, l);
                chord = chord.max(distance(p, q));
                (lo, hi) = union(union((lo, hi), (p, p)), (q, q));
            }
        }
        let pad = style + HERMITE_BULGE * chord;
        (lo.map(|v| v - pad), hi.map(|v| v + pad))
    });
    if (c as usize) >= n {
        return boxes.collect();
    }
    vec![boxes.fold(([f32::MAX; 3], [f32::MIN; 3]), union)]
}

/// The box around two boxes (or points).
pub fn union((lo, hi): (V3, V3), (l, h): (V3, V3)) -> (V3, V3) {
    (
        [0, 1, 2].map(|a| lo[a].min(l[a])),
        [0, 1, 2].map(|a| hi[a].max(h[a])),
    )
}

/// What of bundle `b` at `c` control points is hidden: the flags to add,
/// [`LOD_OCCLUDED`] when all of it is, and otherwise the hidden pieces'
/// boxes as bits from [`BOX_BITS_SHIFT`] (only with a box per piece, which
/// [`segment_hidden`] needs). A chord across layer j + 1 lies in the box
/// around pieces j and j + 1, so a bundle is hidden whole only when those
/// boxes are too.
pub fn hidden_flags(
    f: &FrameData,
    hiz: &Words<'_>,
    layers: &Words<'_>,
    b: &BundleRecord,
    c: u32,
) -> u32 {
    let boxes = bundle_boxes(layers, b, c);
    let hidden = |(lo, hi): (V3, V3)| box_hidden(f, hiz, lo, hi);
    let mask = (0..boxes.len())
        .filter(|&j| hidden(boxes[j]))
        .fold(0u32, |m, j| m | 1 << j);
    if mask == 0 {
        0
    } else if mask == (1u32 << boxes.len()) - 1
        && boxes.windows(2).all(|p| hidden(union(p[0], p[1])))
    {
        LOD_OCCLUDED
    } else if c >= b.layers() {
        mask << BOX_BITS_SHIFT
    } else {
        0
    }
}

/// Whether the segment between control points at `wa` <= `wb` (their w,
/// root 0 to tip 1) of a bundle of `n` layers lies in a hidden box of
/// `flags` (bundle_lod's word 3): a segment inside Hermite piece j (as
/// `strand::eval_cp` numbers them) is hidden with box j; one across a layer
/// is drawn.
pub fn segment_hidden(flags: u32, n: u32, wa: f32, wb: f32) -> bool {
    let piece = |w: f32| ((w * (n - 1) as f32).floor() as u32).min(n - 2);
    let j = piece(wa);
    j == piece(wb) && (flags >> BOX_BITS_SHIFT) >> j & 1 == 1
}

struct OcclusionKernel(OcclusionParams);

impl CpuKernel for OcclusionKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let f = frame(ctx);
        let (bundles, layers, hiz, choices, visible) = (
            ctx.words("hairmesh.bundles"),
            ctx.words("hairmesh.layers"),
            ctx.words("hiz"),
            ctx.words("lod_choices"),
            ctx.words("lod_visible"),
        );
        let count = bundle_count(ctx)
            .min(bundles.len() / BUNDLE_WORDS)
            .min(choices.len() / LOD_WORDS)
            .min(visible.len() / LOD_WORDS);
        let first = (group * GROUP) as usize;
        for b in first..(first + GROUP as usize).min(count) {
            let mut lod = BundleLod::load(&choices, b);
            if self.0.enabled && lod.flags == 0 && lod.strands > 0 {
                let rec = BundleRecord::load(&bundles, b);
                lod.flags |= hidden_flags(&f, &hiz, &layers, &rec, lod.control_points);
            }
            lod.store(&visible, b);
        }
    }
}

#[cfg(test)]
mod tests;
