//! `lipp.lod`: Lipp §3.2, the per-bundle level-of-detail prepass, one
//! thread per bundle as the paper runs it ("computed via a dispatch of B
//! threads, with one thread assigned to each bundle").
//!
//! For every bundle: the footprint of its projected layer quads (Eq. 3,
//! [`footprint`]), the LOD value L (Eq. 2), the strand count N_LOD (Eq. 1,
//! with a per-bundle random δ), and the control-point count C (Eq. 4-5,
//! snapped to 2^k + 1). Bundles whose footprint lies outside the viewport are
//! frustum-culled (flag `LOD_CULLED`: they keep N_LOD for β of Eq. 8 and
//! draw nothing). The decisions go to `lod_choices`, with each drawn
//! bundle's screen rectangle in the camera's view where the scan will put its
//! first strand ([`super::rect`]);
//! `lipp.lod_scan` ([`scan`]) turns them into first strands and the
//! rasterizer's indirect dispatch.
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
//! Shadow LOD (ours, `view: Light`): the paper does not say which strands
//! its deep opacity maps receive. With `view: Camera` they would receive the
//! camera's LOD: at close range nearly every strand at C_max points into a
//! 512² map, and fewer as the camera backs away, so shadows would change with
//! the camera. With `view: Light`, Eq. 2-5 run on each bundle's footprint in
//! the light's map (R_y = the map's resolution), taking the largest over the
//! lights; with `camera_bound` L is also at most the camera's, so a distant
//! groom's shadows get no more detail than the groom itself. The maps
//! compensate the removed strands' opacity (`lipp.dom_opacity`'s
//! `density_compensation`).

pub mod footprint;
pub mod scan;

use super::dom::{LightFrame, light_frames};
use super::rect;
use super::{
    BUNDLE_WORDS, BundleLod, BundleRecord, LOD_CULLED, LOD_OTHER_GROOM, LOD_WORDS,
    MAX_CONTROL_POINTS, bundle_count, frame, pcg, unit,
};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::layout::FrameData;
use crate::params::{Invalid, PassParams, in_range};
use footprint::Footprint;
use strandgraph_graph::schema::Quantity;

/// Lanes per workgroup of the LOD pass (WGSL): [`LOD_BUNDLES`] bundles, a
/// lane per layer.
pub const LOD_GROUP: u32 = 64;
/// Bundles per workgroup. The paper runs a thread per bundle ("a dispatch of
/// B threads"), which the CPU kernel follows; the WGSL gives each of a
/// bundle's (at most 16) layers a lane and reduces its footprints and box in
/// workgroup memory, with the same bits (min and max are exact). On the H100
/// a thread per bundle spent its time waiting on 16 layers' loads in a row:
/// the camera's `lipp.lod` took 0.029 ms at far and 0.040 at mid.
pub const LOD_BUNDLES: u32 = 4;

/// `LodParams.model` in WGSL when the pass decides for every groom.
pub(crate) const ALL_MODELS: u32 = u32::MAX;

crate::string_enum! {
    /// Whose view Eq. 2-5 measure a bundle in.
    pub enum View {
        /// The camera's screen (Lipp §3.2).
        Camera,
        /// Each light's deep opacity map (ours; see the module documentation).
        Light,
    }
}

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
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
    /// Camera view only: a light's map is fitted around every groom.
    pub frustum_cull: bool,
    /// Ours (the issue's "control-point cap from the groom's own
    /// resolution"): C is at most [`groom_cap`] of the groom the hair mesh
    /// stands for, one point between each two of its points. Beyond that the
    /// extra points only resample the Hermite curve and the styling more
    /// finely than the groom was authored; measured on the H100, the close
    /// view's 127 points cost the raster 10% more than 65.
    pub groom_resolution: bool,
    /// §3.2.1 dynamic strand counts (Eq. 1); off, N_LOD = N.
    pub strand_lod: bool,
    /// §3.2.2 dynamic strand resolution (Eq. 4-5); off, C from L = 1.
    pub resolution_lod: bool,
    /// The view a bundle's footprint is measured in.
    pub view: View,
    /// `view: Light`: texels per side of the deep opacity maps (R_y of Eq. 2
    /// in the light's view; the dom passes' `resolution`).
    pub map_resolution: u32,
    /// `view: Light`: L at most the camera's L (ours).
    pub camera_bound: bool,
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
            groom_resolution: true,
            strand_lod: true,
            resolution_lod: true,
            view: View::Camera,
            map_resolution: 512,
            camera_bound: true,
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
        in_range("map_resolution", self.map_resolution, 16..=4096)
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
        /// 1: `View::Light`.
        light_view: u32,
        map_resolution: u32,
        camera_bound: u32,
        groom_resolution: u32,
        _pad1: u32,
        _pad2: u32,
        _pad3: u32,
    }
}

pub static LOD: PassKind<LodParams, LodGpu> = PassKind {
    kind: "lipp.lod",
    summary: "per-bundle LOD, a thread per bundle: footprint (Eq. 3) in the camera's or a light's view, L (Eq. 2), N_LOD (Eq. 1), control points (Eq. 4-5)",
    source: "Lipp §3.2",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("hairmesh.bundles"),
        Binding::read("hairmesh.layers"),
        Binding::read("models"),
        Binding::read("lights"),
        Binding::write("lod_choices"),
    ]),
    workgroup_size: LOD_GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Bundles,
        per_group: LOD_BUNDLES,
    },
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
        light_view: flag(p.view == View::Light),
        map_resolution: p.map_resolution,
        camera_bound: flag(p.camera_bound),
        groom_resolution: flag(p.groom_resolution),
        ..LodGpu::default()
    },
    raster: None,
};

/// Lipp Eq. 5: C_raw snapped up to 2^k + 1, at most C_max (C_raw >= 3).
pub fn snap_control_points(c_raw: u32, c_max: u32) -> u32 {
    let x = c_raw.max(3) - 1;
    (x.next_power_of_two() + 1).min(c_max)
}

/// The `groom_resolution` cap on C for a groom of at most `points` points per
/// strand: 2 (points − 1) + 1, snapped up to 2^k + 1 like Eq. 5 (65 for a
/// 32-point groom), at most C_max; C_max when the groom is unknown (0).
pub fn groom_cap(points: u32, c_max: u32) -> u32 {
    if points < 2 {
        return c_max;
    }
    snap_control_points(2 * (points - 1) + 1, c_max)
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
pub fn lod_value(fp: &Footprint, height: f32, lambda: f32) -> f32 {
    let (dx, dy) = (fp.hi[0] - fp.lo[0], fp.hi[1] - fp.lo[1]);
    ((dx * dx + dy * dy).sqrt() / height * lambda).clamp(0.0, 1.0)
}

/// The decision for one bundle (first_strand is filled in by the scan).
/// `lights`: the maps' views, for `view: Light`.
pub fn choose(
    p: &LodParams,
    f: &FrameData,
    layers: &Words<'_>,
    b: &BundleRecord,
    lights: &[LightFrame],
) -> BundleLod {
    if p.model.is_some_and(|m| m != b.model) {
        return BundleLod {
            strands: 0,
            control_points: 3,
            first_strand: 0,
            flags: LOD_OTHER_GROOM,
        };
    }
    let (fp, behind) = footprint::screen(f, layers, b);
    let (w, h) = (f.screen[0], f.screen[1]);
    // The groom's own strength multiplies the pass's.
    let lambda = p.lambda * b.lod_lambda;
    // A corner behind the camera: the bundle may cover the screen; full detail.
    let camera_l = if behind {
        1.0
    } else {
        lod_value(&fp, h, lambda)
    };
    let (culled, measured) = match p.view {
        View::Camera => {
            let outside =
                !fp.is_some() || fp.hi[0] < 0.0 || fp.lo[0] > w || fp.hi[1] < 0.0 || fp.lo[1] > h;
            // A corner behind the camera: not culled.
            (p.frustum_cull && outside && !behind, camera_l)
        }
        View::Light => {
            let res = p.map_resolution as f32;
            let mut l = 0.0f32;
            for lf in lights {
                l = l.max(lod_value(
                    &footprint::light_map(lf, res, layers, b),
                    res,
                    lambda,
                ));
            }
            let l = if p.camera_bound { l.min(camera_l) } else { l };
            // No map to draw into: nothing to draw.
            (lights.is_empty(), l)
        }
    };
    // 0: the groom has LOD off.
    let l = if !p.enabled || b.lod_lambda <= 0.0 {
        1.0
    } else {
        measured
    };
    let delta = if p.random_delta {
        unit(pcg(b.seed))
    } else {
        0.0
    };
    // A culled bundle keeps its N_LOD for β (lipp.lod_scan draws none).
    let strands = if p.strand_lod {
        lod_strands(l, b.strands, delta)
    } else {
        b.strands
    };
    let l_res = if p.resolution_lod { l } else { 1.0 };
    let c_max = if p.groom_resolution {
        groom_cap(b.groom_points, p.max_control_points)
    } else {
        p.max_control_points
    };
    let c = snap_control_points(
        raw_control_points(l_res, p.max_control_points, b.layers()),
        c_max,
    );
    // The bundle's screen rectangle in the camera's view (rect.rs), which
    // lipp.lod_scan unites and then overwrites with the first strand.
    let rect = if p.view == View::Camera && !culled {
        let (lo, hi) = rect::bundle_box(layers, b);
        rect::screen_rect(f, lo, hi).pack_tiles(w as u32, h as u32)
    } else {
        0
    };
    BundleLod {
        strands,
        control_points: c,
        first_strand: rect,
        flags: if culled { LOD_CULLED } else { 0 },
    }
}

struct LodKernel(LodParams);

impl CpuKernel for LodKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let f = frame(ctx);
        let (bundles, layers, out) = (
            ctx.words("hairmesh.bundles"),
            ctx.words("hairmesh.layers"),
            ctx.words("lod_choices"),
        );
        let lights = match self.0.view {
            View::Camera => Vec::new(),
            View::Light => light_frames(ctx, None),
        };
        let count = bundle_count(ctx)
            .min(bundles.len() / BUNDLE_WORDS)
            .min(out.len() / LOD_WORDS);
        let first = group as usize * LOD_BUNDLES as usize;
        for b in first..(first + LOD_BUNDLES as usize).min(count) {
            let rec = BundleRecord::load(&bundles, b);
            choose(&self.0, &f, &layers, &rec, &lights).store(&out, b);
        }
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
        let fp = |hi: [f32; 2]| Footprint { lo: [0.0; 2], hi };
        let l = lod_value(&fp([30.0, 40.0]), 1000.0, 2.0);
        assert!((l - 0.1).abs() < 1e-6);
        assert_eq!(lod_value(&fp([3000.0, 4000.0]), 1000.0, 1.0), 1.0);
    }

    /// One bundle whose two layers span ±`half` NDC on a 1000×1000 screen
    /// (clip = world, w = 1), with N = 1000 strands.
    fn decide(p: &LodParams, lod_lambda: f32, model: u32, half: f32) -> BundleLod {
        decide_lit(p, lod_lambda, model, half, &[])
    }

    fn decide_lit(
        p: &LodParams,
        lod_lambda: f32,
        model: u32,
        half: f32,
        lights: &[LightFrame],
    ) -> BundleLod {
        let b = BundleRecord {
            layer_count: 2,
            strands: 1000,
            model,
            lod_lambda,
            ..Default::default()
        };
        decide_record(p, &b, half, lights)
    }

    fn decide_record(
        p: &LodParams,
        b: &BundleRecord,
        half: f32,
        lights: &[LightFrame],
    ) -> BundleLod {
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
        choose(p, &f, &Words::new(&atoms, &oob), b, lights)
    }

    #[test]
    fn the_groom_cap_is_twice_the_grooms_segments_snapped_like_eq5() {
        assert_eq!(groom_cap(32, 127), 65, "31 segments: 62 + 1 -> 2^6 + 1");
        assert_eq!(groom_cap(33, 127), 65);
        assert_eq!(groom_cap(34, 127), 127, "67 snaps to 129, at most C_max");
        assert_eq!(groom_cap(2, 127), 3);
        assert_eq!(groom_cap(0, 127), 127, "unknown groom: no cap");
        assert_eq!(groom_cap(1, 127), 127);
    }

    #[test]
    fn the_groom_cap_limits_full_detail_and_leaves_coarser_lods() {
        let b = BundleRecord {
            layer_count: 2,
            strands: 1000,
            lod_lambda: 1.0,
            groom_points: 32,
            ..Default::default()
        };
        let on = LodParams::default();
        let off = LodParams {
            groom_resolution: false,
            ..on
        };
        // L = 1: Eq. 4-5 give C_max.
        assert_eq!(decide_record(&off, &b, 1.0, &[]).control_points, 127);
        assert_eq!(decide_record(&on, &b, 1.0, &[]).control_points, 65);
        // A small footprint: Eq. 4-5 choose fewer points than the cap.
        let small = decide_record(&off, &b, 0.002, &[]).control_points;
        assert!(small < 65, "{small}");
        assert_eq!(decide_record(&on, &b, 0.002, &[]).control_points, small);
        // The strands are Eq. 1's either way.
        assert_eq!(
            decide_record(&on, &b, 1.0, &[]).strands,
            decide_record(&off, &b, 1.0, &[]).strands
        );
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
    fn light_view_measures_the_footprint_in_each_lights_map() {
        use crate::layout::{LightData, ModelData};
        use bytemuck::Zeroable;
        let mut m = ModelData::zeroed();
        m.bounds_min = [-0.1, -0.1, -0.1, 0.0];
        m.bounds_max = [0.1, 0.1, 0.1, 0.0];
        let mut light = LightData::zeroed();
        light.position_or_direction = [0.0, 0.0, -1.0, 0.0];
        let lf = LightFrame::new(&light, &[m]);
        let p = LodParams {
            view: View::Light,
            camera_bound: false,
            random_delta: false,
            ..LodParams::default()
        };
        // The 0.04 m quad in a map 0.204 m across (bounds padded by 1%):
        // L = 0.04·√2 / 0.204 at any map resolution.
        let expect = (0.04 * 2f32.sqrt() / 0.204 * 1000.0).ceil() as i64;
        for res in [64, 512, 4096] {
            let lit = decide_lit(
                &LodParams {
                    map_resolution: res,
                    ..p
                },
                1.0,
                0,
                0.02,
                &[lf],
            );
            assert!(
                (i64::from(lit.strands) - expect).abs() <= 1,
                "{res}: {lit:?}"
            );
        }
        // Bound by the camera, where the quad is 20 px of 1000.
        let camera = decide(
            &LodParams {
                random_delta: false,
                ..LodParams::default()
            },
            1.0,
            0,
            0.02,
        );
        let bound = decide_lit(
            &LodParams {
                camera_bound: true,
                ..p
            },
            1.0,
            0,
            0.02,
            &[lf],
        );
        // The same decision; only the camera's view keeps a screen rectangle.
        assert_eq!(
            bound,
            BundleLod {
                first_strand: 0,
                ..camera
            }
        );
        assert_ne!(camera.first_strand, 0);
        assert!(camera.strands * 5 < expect as u32);
        // No light with a map: culled (the scan draws none of its strands).
        let dark = decide_lit(&p, 1.0, 0, 0.02, &[]);
        assert_eq!(dark.flags, LOD_CULLED);
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
