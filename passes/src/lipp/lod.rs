//! `lipp.lod`: Lipp §3.2, the per-bundle level-of-detail prepass.
//!
//! For every bundle: the screen-space AABB of its projected layer quads
//! (Lipp Eq. 3), the LOD value L (Eq. 2), the strand count N_LOD (Eq. 1, with
//! a per-bundle random δ), and the control-point count C (Eq. 4-5, snapped to
//! 2^k + 1). Bundles whose AABB lies outside the viewport are frustum-culled
//! (N_LOD = 0). The counts are prefix-summed into each bundle's first strand
//! and the total goes into the rasterizer's indirect dispatch arguments
//! `raster_args` = (min(drawn, 65535), 1, 1, drawn, Σ N), whose last two
//! words give `lipp.shade` the fraction β of Eq. 8.
//!
//! λ of Eq. 2 is the pass's `lambda` times the groom's `lod.lambda` from the
//! scene (Lipp Fig. 1 uses a different strength per style); a groom with
//! `lod.enabled: false` is drawn at full detail.
//!
//! In the graph's per-model block (Lipp §3.5, multiple grooms), the pass
//! decides for one groom (`model_index`): other grooms' bundles draw nothing
//! and β counts only this groom's strands. Outside the block it decides for
//! every groom at once (the deep opacity maps shadow with all of them).
//!
//! Deviation: the paper runs one thread per bundle and feeds N_LOD to a
//! per-bundle indirect dispatch. Here the rasterizer is one flat indirect
//! dispatch over all drawn strands (one workgroup per strand), so this pass
//! also needs the exclusive prefix sum of N_LOD: it runs one workgroup of 256
//! threads, each owning a contiguous run of bundles, and scans their sums in
//! workgroup memory. The CPU kernel computes the same values sequentially.

use super::{
    BUNDLE_WORDS, BundleLod, BundleRecord, Corner, LOD_CULLED, LOD_OTHER_GROOM, MAX_CONTROL_POINTS,
    MAX_GROUPS_X, bundle_count, frame, pcg, transform, unit,
};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::layout::FrameData;
use crate::params::{Invalid, PassParams};

/// Threads of the single LOD workgroup (WGSL).
pub const LOD_GROUP: u32 = 256;

/// `LodParams.model` in WGSL when the pass decides for every groom.
const ALL_MODELS: u32 = u32::MAX;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LodParams {
    /// Off: every bundle draws N strands of C_max points (frustum culling still applies).
    pub enabled: bool,
    /// λ of Eq. 2.
    pub lambda: f32,
    /// δ ~ U[0, 1) per bundle (Eq. 1); off, δ = 0.
    pub random_delta: bool,
    /// C_max of Eq. 4-5 (3..=129).
    pub max_control_points: u32,
    pub frustum_cull: bool,
    /// §3.2.1 dynamic strand counts (Eq. 1); off, N_LOD = N.
    pub strand_lod: bool,
    /// §3.2.2 dynamic strand resolution (Eq. 4-5); off, C from L = 1.
    pub resolution_lod: bool,
    /// Only this groom's bundles (the per-model block sets `model_index`); `None`: all.
    #[serde(rename = "model_index", deserialize_with = "crate::params::some")]
    pub model: Option<u32>,
}

impl Default for LodParams {
    fn default() -> Self {
        Self {
            enabled: true,
            lambda: 1.0,
            random_delta: true,
            max_control_points: 127,
            frustum_cull: true,
            strand_lod: true,
            resolution_lod: true,
            model: None,
        }
    }
}

impl PassParams for LodParams {
    const READS_MODEL_INDEX: bool = true;

    fn validate(&self) -> Result<(), Invalid> {
        if !(3..=MAX_CONTROL_POINTS).contains(&self.max_control_points) {
            return Err(Invalid::new(
                "max_control_points",
                format!(
                    "{} is outside 3..={MAX_CONTROL_POINTS} (32 lanes x 4 points per lane)",
                    self.max_control_points
                ),
            ));
        }
        if !(self.lambda.is_finite() && self.lambda >= 0.0) {
            return Err(Invalid::new(
                "lambda",
                format!("{} is not a finite λ >= 0", self.lambda),
            ));
        }
        Ok(())
    }
}

crate::gpu_block! {
    /// `LodParams` in shaders/lipp/lod.wgsl.
    pub struct LodGpu {
        enabled: u32,
        lambda: f32,
        random_delta: u32,
        max_control_points: u32,
        frustum_cull: u32,
        strand_lod: u32,
        resolution_lod: u32,
        /// Scene quantity: bundles packed.
        bundles: u32,
        /// Only this groom's bundles; `ALL_MODELS`: every groom.
        model: u32,
        _pad0: u32,
        _pad1: u32,
        _pad2: u32,
    }
}

pub static LOD: PassKind<LodParams, LodGpu> = PassKind {
    kind: "lipp.lod",
    summary: "per-bundle LOD: screen AABB (Eq. 3), L (Eq. 2), N_LOD (Eq. 1), control points (Eq. 4-5), indirect args",
    source: "Lipp §3.2",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("hairmesh.bundles"),
        Binding::read("hairmesh.layers"),
        Binding::write("bundle_lod"),
        Binding::write("raster_args"),
    ]),
    workgroup_size: LOD_GROUP,
    dispatch: Dispatch::Fixed(1),
    shader: Shader::compute("lipp/lod.wgsl", "lod"),
    kernel: |p| Box::new(LodKernel(*p)),
    gpu: |p, q| LodGpu {
        enabled: flag(p.enabled),
        lambda: p.lambda,
        random_delta: flag(p.random_delta),
        max_control_points: p.max_control_points,
        frustum_cull: flag(p.frustum_cull),
        strand_lod: flag(p.strand_lod),
        resolution_lod: flag(p.resolution_lod),
        bundles: count(q.bundles),
        model: p.model.unwrap_or(ALL_MODELS),
        ..LodGpu::default()
    },
    raster: None,
};

/// Lipp Eq. 5: C_raw snapped up to 2^k + 1, at most C_max (C_raw >= 3).
pub fn snap_control_points(c_raw: u32, c_max: u32) -> u32 {
    let x = c_raw.max(3) - 1;
    (x.next_power_of_two() + 1).min(c_max)
}

/// Lipp Eq. 4: C_raw = max(floor(sqrt(L) · C_max), C_layers).
pub fn raw_control_points(l: f32, c_max: u32, layers: u32) -> u32 {
    ((l.sqrt() * c_max as f32).floor() as u32).max(layers)
}

/// Lipp Eq. 1: N_LOD = clamp(ceil(L (N + δ)), 1, N).
pub fn lod_strands(l: f32, n: u32, delta: f32) -> u32 {
    if n == 0 {
        return 0;
    }
    ((l * (n as f32 + delta)).ceil() as u32).clamp(1, n)
}

/// Lipp Eq. 2: L = clamp(|AABB_max − AABB_min| / R_y · λ, 0, 1).
pub fn lod_value(aabb_min: [f32; 2], aabb_max: [f32; 2], height: f32, lambda: f32) -> f32 {
    let (dx, dy) = (aabb_max[0] - aabb_min[0], aabb_max[1] - aabb_min[1]);
    ((dx * dx + dy * dy).sqrt() / height * lambda).clamp(0.0, 1.0)
}

/// Lipp Eq. 3: the screen AABB (pixels) of bundle `b`'s layer corners, and
/// whether a corner lies behind the near plane.
pub fn screen_aabb(
    f: &FrameData,
    layers: &Words<'_>,
    b: &BundleRecord,
) -> ([f32; 2], [f32; 2], bool) {
    let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
    let mut behind = false;
    for i in 0..b.layers() {
        for k in 0..4 {
            let c = Corner::load(layers, (b.first_layer + i) as usize, k);
            let p = c.position;
            let clip = transform(&f.view_proj, [p[0], p[1], p[2], 1.0]);
            if clip[3] <= f.near {
                behind = true;
                continue;
            }
            let s = crate::kulikov::clip_to_screen(clip, f.screen[0], f.screen[1]);
            lo = [lo[0].min(s[0]), lo[1].min(s[1])];
            hi = [hi[0].max(s[0]), hi[1].max(s[1])];
        }
    }
    (lo, hi, behind)
}

/// The decision for one bundle (first_strand is filled in by the scan).
pub fn choose(p: &LodParams, f: &FrameData, layers: &Words<'_>, b: &BundleRecord) -> BundleLod {
    if p.model.is_some_and(|m| m != b.model) {
        return BundleLod {
            strands: 0,
            control_points: 3,
            first_strand: 0,
            flags: LOD_OTHER_GROOM,
        };
    }
    let (lo, hi, behind) = screen_aabb(f, layers, b);
    let (w, h) = (f.screen[0], f.screen[1]);
    let any_in_front = lo[0] <= hi[0];
    let outside = !any_in_front || hi[0] < 0.0 || lo[0] > w || hi[1] < 0.0 || lo[1] > h;
    // A corner behind the camera: the bundle may cover the screen; not culled, full detail.
    let culled = p.frustum_cull && outside && !behind;
    // The groom's own strength multiplies the pass's (0: the groom has LOD off).
    let l = if !p.enabled || behind || b.lod_lambda <= 0.0 {
        1.0
    } else {
        lod_value(lo, hi, h, p.lambda * b.lod_lambda)
    };
    let delta = if p.random_delta {
        unit(pcg(b.seed))
    } else {
        0.0
    };
    let strands = if culled {
        0
    } else if p.strand_lod {
        lod_strands(l, b.strands, delta)
    } else {
        b.strands
    };
    let l_res = if p.resolution_lod { l } else { 1.0 };
    let c = snap_control_points(
        raw_control_points(l_res, p.max_control_points, b.layers()),
        p.max_control_points,
    );
    BundleLod {
        strands,
        control_points: c,
        first_strand: 0,
        flags: if culled { LOD_CULLED } else { 0 },
    }
}

struct LodKernel(LodParams);

impl CpuKernel for LodKernel {
    fn run_workgroup(&self, _group: u32, ctx: &Ctx<'_>) {
        let f = frame(ctx);
        let (bundles, layers, out) = (
            ctx.words("hairmesh.bundles"),
            ctx.words("hairmesh.layers"),
            ctx.words("bundle_lod"),
        );
        let count = bundle_count(ctx).min(bundles.len() / BUNDLE_WORDS);
        let (mut total, mut full) = (0u32, 0u32);
        for b in 0..count {
            let rec = BundleRecord::load(&bundles, b);
            if self.0.model.is_none_or(|m| m == rec.model) {
                full = full.saturating_add(rec.strands);
            }
            let mut lod = choose(&self.0, &f, &layers, &rec);
            lod.first_strand = total;
            total = total.saturating_add(lod.strands);
            lod.store(&out, b);
        }
        let args = ctx.words("raster_args");
        args.store(0, total.min(MAX_GROUPS_X));
        args.store(1, 1);
        args.store(2, 1);
        args.store(3, total);
        // β of Lipp Eq. 8 is word 3 / word 4.
        args.store(4, full);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq5_snaps_to_power_of_two_plus_one_below_c_max() {
        assert_eq!(snap_control_points(3, 127), 3);
        assert_eq!(snap_control_points(4, 127), 5);
        assert_eq!(snap_control_points(8, 127), 9);
        assert_eq!(snap_control_points(9, 127), 9);
        assert_eq!(snap_control_points(10, 127), 17);
        assert_eq!(snap_control_points(66, 127), 127, "129 is capped at C_max");
        assert_eq!(snap_control_points(2, 127), 3, "C_raw >= 3");
        assert_eq!(snap_control_points(127, 129), 129);
    }

    #[test]
    fn eq4_uses_sqrt_l_and_the_layer_floor() {
        assert_eq!(raw_control_points(1.0, 127, 8), 127);
        assert_eq!(raw_control_points(0.25, 127, 8), 63);
        assert_eq!(raw_control_points(0.0, 127, 8), 8);
        assert_eq!(raw_control_points(0.0001, 127, 8), 8);
    }

    #[test]
    fn eq1_keeps_at_least_one_strand_and_at_most_n() {
        assert_eq!(lod_strands(1.0, 127, 0.9), 127);
        assert_eq!(lod_strands(0.0, 127, 0.5), 1);
        assert_eq!(lod_strands(0.5, 100, 0.0), 50);
        assert_eq!(lod_strands(0.5, 100, 0.9), 51);
        assert_eq!(lod_strands(0.5, 0, 0.9), 0);
    }

    #[test]
    fn eq2_is_the_aabb_diagonal_over_the_height_times_lambda() {
        let l = lod_value([0.0, 0.0], [30.0, 40.0], 1000.0, 2.0);
        assert!((l - 0.1).abs() < 1e-6);
        assert_eq!(lod_value([0.0, 0.0], [3000.0, 4000.0], 1000.0, 1.0), 1.0);
    }

    /// One bundle whose two layers span ±`half` NDC on a 1000×1000 screen
    /// (clip = world, w = 1), with N = 1000 strands.
    fn decide(p: &LodParams, lod_lambda: f32, model: u32, half: f32) -> BundleLod {
        use std::sync::atomic::{AtomicU32, AtomicU64};
        let mut f: FrameData = bytemuck::Zeroable::zeroed();
        for i in 0..4 {
            f.view_proj[i * 5] = 1.0;
        }
        f.screen = [1000.0, 1000.0, 1e-3, 1e-3];
        f.near = 0.1;
        let mut words = Vec::new();
        for _layer in 0..2 {
            for (u, v) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                words.extend([u * half, v * half, 0.5, 1.0, 0.0, 1.0, 0.0, 0.0].map(f32::to_bits));
            }
        }
        let atoms: Vec<AtomicU32> = words.into_iter().map(AtomicU32::new).collect();
        let oob = AtomicU64::new(0);
        let b = BundleRecord {
            layer_count: 2,
            strands: 1000,
            model,
            lod_lambda,
            ..Default::default()
        };
        choose(p, &f, &Words::new(&atoms, &oob), &b)
    }

    #[test]
    fn the_grooms_strength_multiplies_lambda_and_zero_means_full_detail() {
        let p = LodParams::default();
        let p = LodParams {
            random_delta: false,
            ..p
        };
        // AABB 20 x 20 px: L = 20√2 / 1000 · λ.
        let one = decide(&p, 1.0, 0, 0.02).strands;
        let four = decide(&p, 4.0, 0, 0.02).strands;
        assert_eq!(one, (20.0 * 2f32.sqrt() / 1000.0 * 1000.0).ceil() as u32);
        assert_eq!(
            four,
            (4.0 * 20.0 * 2f32.sqrt() / 1000.0 * 1000.0).ceil() as u32
        );
        assert_eq!(
            decide(&p, 0.0, 0, 0.02).strands,
            1000,
            "LOD off for the groom"
        );
    }

    #[test]
    fn a_per_groom_pass_skips_other_grooms_bundles() {
        let p = LodParams {
            model: Some(1),
            ..LodParams::default()
        };
        let other = decide(&p, 1.0, 0, 0.02);
        assert_eq!((other.strands, other.flags), (0, LOD_OTHER_GROOM));
        assert!(decide(&p, 1.0, 1, 0.02).strands > 0);
    }

    #[test]
    fn bad_params_are_errors() {
        let v: ron::Value = ron::from_str(r#"{"max_control_points": 300}"#).unwrap();
        assert!(LOD.params(&v).is_err());
        let v: ron::Value = ron::from_str(r#"{"lambda": -1.0}"#).unwrap();
        assert!(LOD.params(&v).is_err());
        let v: ron::Value = ron::from_str(r#"{"enabled": 3}"#).unwrap();
        assert!(LOD.params(&v).is_err());
    }
}
