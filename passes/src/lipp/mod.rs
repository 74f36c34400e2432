//! The Lipp-style pipeline (Lipp, Jarabo, Wimmer, Bode: "Deferred Software
//! Rasterization for Efficient Real-time Hair Rendering"): a per-bundle LOD
//! prepass feeding an indirect dispatch (§3.2), cooperative strand assembly
//! and DDA rasterization into a 64-bit centre/conservative G-buffer (§3.1,
//! Code 1), deferred shading (§3.4) and the reconnection filter (§3.3, Code 2).
//! Each pass is one file: definition, CPU kernel, citation. The WGSL in
//! `shaders/lipp/` ports the CPU kernels operation for operation.

pub mod assemble;
pub mod chiang;
#[cfg(test)]
mod chiang_reference;
pub mod clear;
pub mod dom;
pub mod filter;
pub mod lod;
pub mod payload;
pub mod probe;
pub mod raster;
pub mod rect;
pub mod reference;
pub mod shade;
pub mod shaded;
pub mod strand;
pub mod tiles;
pub mod upload;
pub mod walk;

use crate::kernel::{Ctx, Words};
use crate::layout::{FrameData, read};

/// Layers a bundle may have on the GPU (the `hairmesh.layers` size is
/// 16 layers per bundle; upload resamples taller bundles to this many).
pub const MAX_LAYERS: u32 = 16;
/// Words per packed layer: 4 corners × (position.xyz, AO, tangent.xyz, w).
pub const LAYER_WORDS: usize = 32;
/// Words per packed bundle record (`hairmesh.bundles`, 64 bytes).
pub const BUNDLE_WORDS: usize = 16;
/// Words per `bundle_lod` entry (Lipp §3.2.2: "fitting into a single uint4 per bundle").
pub const LOD_WORDS: usize = 4;
/// Workgroup size of the strand rasterizer: Lipp Code 1, "We use a WG size of
/// 32 since NVIDIA has a subgroup size of 32".
pub const RASTER_GROUP: u32 = 32;
/// Largest control-point count (C_max may not exceed it): 32 lanes × 4 points.
pub const MAX_CONTROL_POINTS: u32 = 129;
/// Most workgroups one dispatch dimension may have (WebGPU's default limit);
/// the rasterizer strides over strands beyond it.
pub const MAX_GROUPS_X: u32 = 65535;

/// `hairmesh.bundles`: one bundle (16 words).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BundleRecord {
    /// Index of the bundle's first layer in `hairmesh.layers`.
    pub first_layer: u32,
    /// 2..=16 layers.
    pub layer_count: u32,
    /// N, the full strand count (Lipp Eq. 1).
    pub strands: u32,
    /// Index into `models` (material).
    pub model: u32,
    /// Styling parameters (curl radius and turns, twist in turns, noise amplitude).
    pub curl_radius: f32,
    pub curl_turns: f32,
    pub twist: f32,
    pub noise: f32,
    /// Per-bundle random seed (δ of Eq. 1, strand identities).
    pub seed: u32,
    /// The groom's LOD strength, multiplying the pass's λ of Eq. 2 (Lipp
    /// Fig. 1 sets it per style: λ = {4.0, 5.5, 2.0, 2.8, 3.0}); 0 when the
    /// groom's LOD is off (`lod.enabled: false`): full detail.
    pub lod_lambda: f32,
    /// The most points of any strand of the groom the hair mesh stands for
    /// (0: unknown), for `lipp.lod`'s `groom_resolution` cap.
    pub groom_points: u32,
}

impl BundleRecord {
    pub fn load(w: &Words<'_>, b: usize) -> Self {
        let o = b * BUNDLE_WORDS;
        Self {
            first_layer: w.load(o),
            layer_count: w.load(o + 1),
            strands: w.load(o + 2),
            model: w.load(o + 3),
            curl_radius: w.load_f32(o + 4),
            curl_turns: w.load_f32(o + 5),
            twist: w.load_f32(o + 6),
            noise: w.load_f32(o + 7),
            seed: w.load(o + 8),
            lod_lambda: w.load_f32(o + 9),
            groom_points: w.load(o + 10),
        }
    }

    pub fn words(&self) -> [u32; BUNDLE_WORDS] {
        let mut o = [0u32; BUNDLE_WORDS];
        o[0] = self.first_layer;
        o[1] = self.layer_count;
        o[2] = self.strands;
        o[3] = self.model;
        o[4] = self.curl_radius.to_bits();
        o[5] = self.curl_turns.to_bits();
        o[6] = self.twist.to_bits();
        o[7] = self.noise.to_bits();
        o[8] = self.seed;
        o[9] = self.lod_lambda.to_bits();
        o[10] = self.groom_points;
        o
    }

    /// Layer count clamped to what the kernels handle (2..=16).
    pub fn layers(&self) -> u32 {
        self.layer_count.clamp(2, MAX_LAYERS)
    }
}

/// One corner of a packed layer (world space).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Corner {
    pub position: [f32; 3],
    pub ao: f32,
    pub tangent: [f32; 3],
    /// w of the layer's uvw (root 0, tip 1).
    pub w: f32,
}

impl Corner {
    pub fn load(w: &Words<'_>, layer: usize, corner: usize) -> Self {
        let o = layer * LAYER_WORDS + corner * 8;
        Self {
            position: [w.load_f32(o), w.load_f32(o + 1), w.load_f32(o + 2)],
            ao: w.load_f32(o + 3),
            tangent: [w.load_f32(o + 4), w.load_f32(o + 5), w.load_f32(o + 6)],
            w: w.load_f32(o + 7),
        }
    }
}

/// `bundle_lod`: Lipp §3.2's per-bundle decision (uint4).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BundleLod {
    /// N_LOD (Eq. 1); 0 for another groom's bundle. In `lod_choices` a
    /// frustum-culled bundle keeps its N_LOD (β of Eq. 8 counts it);
    /// `lipp.lod_scan` draws none of its strands (`bundle_lod` holds 0).
    pub strands: u32,
    /// C, control points per strand (Eq. 4-5).
    pub control_points: u32,
    /// First drawn strand of this bundle in the dispatch's numbering. In
    /// `lod_choices`, before the scan: the bundle's screen rectangle in the
    /// camera's view ([`rect::Rect::pack_tiles`]), 0 if not drawn.
    pub first_strand: u32,
    /// Bit 0: frustum-culled; bit 1: another groom's (not drawn this time).
    pub flags: u32,
}

/// Outside the viewport (`lipp.lod`'s frustum cull).
pub const LOD_CULLED: u32 = 1;
/// A bundle of another groom than the one a per-model LOD pass decides for.
pub const LOD_OTHER_GROOM: u32 = 2;

/// `raster_args` words: the indirect dispatch (0-2), the strands drawn (3),
/// Σ N of the groom (4) and Σ N_LOD of the groom (5): β of Lipp Eq. 8 is
/// word 5 / word 4, the strands the LOD keeps whether or not the frustum
/// cull then draws them: a bundle out of view thins no visible strand.
/// Words 6 and 7 hold the groom's screen rectangle ([`rect::ARGS_RECT_LO`]).
pub const ARGS_DRAWN: usize = 3;
pub const ARGS_ALL: usize = 4;
pub const ARGS_KEPT: usize = 5;
/// `raster_args` words 11 and 12: the bundles [lo, hi) of the groom the scan
/// was for, where every drawn strand's bundle lies ([`bundle_range`]); the
/// scan writes no other bundle's `bundle_lod` record.
pub const ARGS_BUNDLES_LO: usize = 11;
pub const ARGS_BUNDLES_HI: usize = 12;

/// The bundles `args` (a `raster_args`) says the drawn strands lie in, at
/// most the first `count`; all of them in a `raster_args` with no room.
pub fn bundle_range(args: &Words<'_>, count: usize) -> std::ops::Range<usize> {
    if args.len() <= ARGS_BUNDLES_HI {
        return 0..count;
    }
    let hi = (args.load(ARGS_BUNDLES_HI) as usize).min(count);
    (args.load(ARGS_BUNDLES_LO) as usize).min(hi)..hi
}

impl BundleLod {
    pub fn load(w: &Words<'_>, b: usize) -> Self {
        let o = b * LOD_WORDS;
        Self {
            strands: w.load(o),
            control_points: w.load(o + 1),
            first_strand: w.load(o + 2),
            flags: w.load(o + 3),
        }
    }
    pub fn store(&self, w: &Words<'_>, b: usize) {
        let o = b * LOD_WORDS;
        w.store(o, self.strands);
        w.store(o + 1, self.control_points);
        w.store(o + 2, self.first_strand);
        w.store(o + 3, self.flags);
    }
}

/// The first index of `range` where `below` stops holding (it holds on a
/// prefix of the range): a binary search over records read one at a time.
fn partition_point(range: std::ops::Range<usize>, below: impl Fn(usize) -> bool) -> usize {
    let (mut lo, mut hi) = (range.start, range.end);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if below(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The bundle owning drawn strand `s`: the last bundle whose first strand is
/// at most `s` (bundles with no strands share their successor's first strand,
/// so they are skipped), among `bundles`, sorted by `first_strand`.
pub fn bundle_of_strand(
    first_strand: impl Fn(usize) -> u32,
    bundles: std::ops::Range<usize>,
    s: u32,
) -> usize {
    let floor = bundles.start;
    partition_point(bundles, |b| first_strand(b) <= s)
        .saturating_sub(1)
        .max(floor)
}

/// G-buffer layers the graph gave (2: centre and conservative; N for the
/// MSAA reference mode): whole layers of both `gbuffer` and `shaded` (8
/// bytes per pixel per layer each, planar), at least 2.
pub fn gbuffer_layers(gbuffer: &Words<'_>, shaded: &Words<'_>, pixels: u32) -> u32 {
    let p = pixels.max(1) as usize;
    (gbuffer.len().min(shaded.len()) / (2 * p)).max(2) as u32
}

/// The bundles of groom `model` among the first `count` (all of them for
/// `None`): upload.rs packs each groom's bundles together, grooms in model
/// order, so a binary search over the records' model word finds them.
pub fn groom_bundles(
    bundles: &Words<'_>,
    count: usize,
    model: Option<u32>,
) -> std::ops::Range<usize> {
    let Some(m) = model else { return 0..count };
    let model_of = |b: usize| BundleRecord::load(bundles, b).model;
    partition_point(0..count, |b| model_of(b) < m)..partition_point(0..count, |b| model_of(b) <= m)
}

/// Number of bundles actually packed (the buffer may be larger).
pub fn bundle_count(ctx: &Ctx<'_>) -> usize {
    ctx.quantities.bundles as usize
}

/// The frame record.
pub fn frame(ctx: &Ctx<'_>) -> FrameData {
    read(&ctx.words("frame"), 0)
}

/// PCG hash (Jarzynski and Olano 2020), as `bench::pcg` and the WGSL.
pub use crate::bench::pcg;

/// A hash to [0, 1) with 24 bits (exact in f32 on every backend).
pub fn unit(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Column-major 4×4 times a point (as `kulikov::transform`).
pub use crate::kulikov::transform;

/// Octahedral encoding of a unit vector into [-1, 1]² (Cigolle et al. 2014).
pub fn oct_encode(n: [f32; 3]) -> [f32; 2] {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    if l1 <= 0.0 || !l1.is_finite() {
        return [0.0, 0.0];
    }
    let (px, py) = (n[0] / l1, n[1] / l1);
    if n[2] < 0.0 {
        let sx = if px >= 0.0 { 1.0 } else { -1.0 };
        let sy = if py >= 0.0 { 1.0 } else { -1.0 };
        [(1.0 - py.abs()) * sx, (1.0 - px.abs()) * sy]
    } else {
        [px, py]
    }
}

pub fn oct_decode(e: [f32; 2]) -> [f32; 3] {
    let z = 1.0 - e[0].abs() - e[1].abs();
    let (x, y) = if z < 0.0 {
        let sx = if e[0] >= 0.0 { 1.0 } else { -1.0 };
        let sy = if e[1] >= 0.0 { 1.0 } else { -1.0 };
        ((1.0 - e[1].abs()) * sx, (1.0 - e[0].abs()) * sy)
    } else {
        (e[0], e[1])
    };
    normalize([x, y, z])
}

pub fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub fn scale(a: [f32; 3], s: f32) -> [f32; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}
pub fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}
pub fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
pub fn length(a: [f32; 3]) -> f32 {
    dot(a, a).sqrt()
}
/// Normalised, or zero for a zero vector (WGSL: `select(v / l, 0, l == 0)`).
pub fn normalize(a: [f32; 3]) -> [f32; 3] {
    let l = length(a);
    if l > 0.0 { scale(a, 1.0 / l) } else { [0.0; 3] }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bundle_lookup_skips_empty_bundles() {
        // Bundles: 3 strands, 0 (culled), 2, 0 -> firsts 0, 3, 3, 5.
        let firsts = [0u32, 3, 3, 5];
        let f = |i: usize| firsts[i];
        assert_eq!(bundle_of_strand(f, 0..4, 0), 0);
        assert_eq!(bundle_of_strand(f, 0..4, 2), 0);
        assert_eq!(bundle_of_strand(f, 0..4, 3), 2);
        assert_eq!(bundle_of_strand(f, 0..4, 4), 2);
        // Within a groom's bundles 2..4: strand 4 of firsts 3, 5.
        assert_eq!(bundle_of_strand(f, 2..4, 4), 2);
    }

    #[test]
    fn octahedral_round_trip() {
        for n in [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [0.6, -0.8, 0.0],
            [0.3, 0.4, -0.866],
        ] {
            let d = oct_decode(oct_encode(n));
            assert!(length(sub(d, normalize(n))) < 1e-5, "{n:?} -> {d:?}");
        }
    }
}
