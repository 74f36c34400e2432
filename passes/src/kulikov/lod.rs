//! `kulikov.lod`: how many strands of each model to draw this frame.
//!
//! Kulikov, "LODs": randomized strand order, so a LOD is a prefix of the
//! strand list; three bounds, applied in order:
//! 1. a per-asset cap ("Max 65k strands (PC High ...) Max 32k strands (PC Low ...)"),
//!    except for small models, "because they don't contribute much";
//! 2. "an upper boundary of 2000 segments per 64x64 tile" of the model's screen bounds;
//! 3. "limit it at 2 million segments ... proportionally reduce number of strands in
//!    each model until we fit".
//!
//! Dropped strands are compensated by thicker strands, and far models skip every
//! other vertex ("only helps with shading cost").

use super::payload::MAX_SEGMENTS_PER_MODEL;
use super::{ModelLod, Scene, drawn_segments, transform};
use crate::contract::{Binding, CpuKernel, Dispatch, MAX_COVER_GROUPS, Shader, flag};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::layout::{MODEL_LOD_ENABLED, ModelData};
use crate::params::{Invalid, PassParams, in_range, non_negative};

/// Lanes of the LOD pass's one workgroup (WGSL): model m is decided by lane
/// m % LOD_LANES, and the sums and prefixes go through workgroup memory.
/// The CPU kernel decides the models in one loop; every sum is of integers,
/// so both give the same bits. (One lane doing it all took 0.07 ms on the
/// crowd's 28 grooms on the H100, on the frame's critical path.)
pub const LOD_LANES: u32 = 64;

/// Skinning workgroup size; the LOD pass writes the skinning dispatch.
pub const SKIN_GROUP: u32 = 64;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LodParams {
    pub enabled: bool,
    /// The per-asset cap ("Max 65k strands (PC High ...)").
    pub max_strands: u32,
    /// Models with at most this many strands are not capped.
    pub small_model_strands: u32,
    /// "an upper boundary of 2000 segments per 64x64 tile".
    pub segments_per_tile: u32,
    pub tile_size: u32,
    /// "limit it at 2 million segments".
    pub segment_budget: u32,
    pub thickness_compensation: bool,
    pub max_thickness_scale: f32,
    /// Beyond this view distance every other vertex is skipped.
    pub skip_vertices_beyond_m: f32,
}

impl Default for LodParams {
    fn default() -> Self {
        Self {
            enabled: true,
            max_strands: 65536,
            small_model_strands: 4096,
            segments_per_tile: 2000,
            tile_size: 64,
            segment_budget: 2_000_000,
            thickness_compensation: true,
            max_thickness_scale: 4.0,
            skip_vertices_beyond_m: 8.0,
        }
    }
}

impl PassParams for LodParams {
    fn validate(&self) -> Result<(), Invalid> {
        in_range("tile_size", self.tile_size, 1..=u32::MAX)?;
        non_negative("max_thickness_scale", self.max_thickness_scale)?;
        non_negative("skip_vertices_beyond_m", self.skip_vertices_beyond_m)
    }
}

crate::gpu_block! {
    /// `LodParams` in shaders/kulikov/lod.wgsl.
    pub struct LodGpu {
        enabled: u32,
        max_strands: u32,
        small_model_strands: u32,
        segments_per_tile: u32,
        tile_size: u32,
        segment_budget: u32,
        thickness_compensation: u32,
        max_thickness_scale: f32,
        skip_vertices_beyond_m: f32,
    }
}

pub static LOD: PassKind<LodParams, LodGpu> = PassKind {
    kind: "kulikov.lod",
    summary: "per-model strand count: asset cap, segments per 64x64 tile, 2M-segment budget, thickness compensation",
    source: "Kulikov 2025, 'LODs'",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("models"),
        Binding::write("lod_models"),
        Binding::write("lod_args"),
    ]),
    workgroup_size: LOD_LANES,
    dispatch: Dispatch::Fixed(1),
    shader: Shader::compute("kulikov/lod.wgsl", "lod"),
    kernel: |p| Box::new(LodKernel(*p)),
    gpu: |p, _| LodGpu {
        enabled: flag(p.enabled),
        max_strands: p.max_strands,
        small_model_strands: p.small_model_strands,
        segments_per_tile: p.segments_per_tile,
        tile_size: p.tile_size,
        segment_budget: p.segment_budget,
        thickness_compensation: flag(p.thickness_compensation),
        max_thickness_scale: p.max_thickness_scale,
        skip_vertices_beyond_m: p.skip_vertices_beyond_m,
    },
    raster: None,
};

struct LodKernel(LodParams);

impl CpuKernel for LodKernel {
    fn run_workgroup(&self, _group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let lods = choose(&self.0, &scene);
        let out = ctx.words("lod_models");
        for (m, l) in lods.iter().enumerate() {
            l.store(&out, m);
        }
        let args = ctx.words("lod_args");
        let strands: u32 = lods.iter().map(|l| l.strands).sum();
        let drawn: u32 = lods.iter().map(ModelLod::drawn).sum();
        let skin = [strands.div_ceil(SKIN_GROUP), 1, 1, strands];
        for (k, w) in skin.into_iter().chain(drawn_dispatch(drawn)).enumerate() {
            args.store(k, w);
        }
    }
}

/// Workgroup size of the passes over drawn segments (`kulikov.cull`,
/// `kulikov.sort`).
pub const DRAWN_GROUP: u32 = super::cull::GROUP;

/// The indirect dispatch over `drawn` segments: `[groups, 1, 1, drawn]`,
/// [`DRAWN_GROUP`] a workgroup, at most [`MAX_COVER_GROUPS`] workgroups
/// (the kernels stride over the rest; the 4th word is the count they read).
/// `lod_args` holds two dispatches: kept strands (skinning) at word 0, this
/// at word 4.
pub fn drawn_dispatch(drawn: u32) -> [u32; 4] {
    let groups = u64::from(drawn.div_ceil(DRAWN_GROUP)).min(MAX_COVER_GROUPS) as u32;
    [groups, 1, 1, drawn]
}

/// Screen-space bounds (pixels, clamped) and view-depth range of a model.
fn screen_extent(scene: &Scene, m: &ModelData) -> (f32, f32, f32) {
    let (w, h) = (scene.frame.screen[0], scene.frame.screen[1]);
    let (mut x0, mut y0, mut x1, mut y1) = (f32::MAX, f32::MAX, f32::MIN, f32::MIN);
    let (mut near, mut far) = (f32::MAX, 0.0f32);
    let mut behind = false;
    for i in 0..8 {
        let pick = |bit: usize, a: usize| {
            if i & bit == 0 {
                m.bounds_min[a]
            } else {
                m.bounds_max[a]
            }
        };
        let c = transform(
            &scene.frame.view_proj,
            [pick(1, 0), pick(2, 1), pick(4, 2), 1.0],
        );
        near = near.min(c[3]);
        far = far.max(c[3]);
        if c[3] <= scene.frame.near {
            behind = true;
            continue;
        }
        let s = super::clip_to_screen(c, w, h);
        (x0, y0, x1, y1) = (x0.min(s[0]), y0.min(s[1]), x1.max(s[0]), y1.max(s[1]));
    }
    if behind {
        // A corner behind the camera: the model may cover the whole screen.
        (x0, y0, x1, y1) = (0.0, 0.0, w, h);
    }
    let area = (x1.min(w) - x0.max(0.0)).max(0.0) * (y1.min(h) - y0.max(0.0)).max(0.0);
    (
        area,
        near.max(scene.frame.near),
        far.max(near.max(scene.frame.near) + 1e-3),
    )
}

/// The LOD decision for every model (exposed for tests).
pub fn choose(p: &LodParams, scene: &Scene) -> Vec<ModelLod> {
    let cam = [
        scene.frame.camera_pos[0],
        scene.frame.camera_pos[1],
        scene.frame.camera_pos[2],
    ];
    let mut lods: Vec<ModelLod> = scene
        .models
        .iter()
        .map(|m| {
            let (area, near, far) = screen_extent(scene, m);
            let points = m.points_per_strand.max(2);
            let centre: Vec<f32> = (0..3)
                .map(|a| 0.5 * (m.bounds_min[a] + m.bounds_max[a]))
                .collect();
            let distance = (0..3)
                .map(|a| (centre[a] - cam[a]).powi(2))
                .sum::<f32>()
                .sqrt();
            let lod_on = p.enabled && m.flags & MODEL_LOD_ENABLED != 0;
            let step = if lod_on && distance > p.skip_vertices_beyond_m {
                2
            } else {
                1
            };
            let per_strand = drawn_segments(points, step);
            let mut n = m.strand_count;
            if area <= 0.0 {
                n = 0; // off screen
            } else if lod_on {
                if n > p.small_model_strands {
                    n = n.min(p.max_strands.max(p.small_model_strands));
                }
                let tile_area = (p.tile_size * p.tile_size) as f32;
                let allowed = (p.segments_per_tile as f32 * area / tile_area / per_strand as f32)
                    .ceil() as u32;
                let floor =
                    ((m.min_fraction.clamp(0.0, 1.0) * m.strand_count as f32).ceil() as u32).max(1);
                n = n.min(allowed.max(floor));
            }
            // The payload has 22 bits of segment index per model.
            n = n.min(MAX_SEGMENTS_PER_MODEL / (points - 1));
            ModelLod {
                strands: n,
                vertex_step: step,
                thickness_scale: 1.0,
                segments_per_strand: per_strand,
                strand_prefix: 0,
                depth_near: near,
                depth_far: far,
                segment_prefix: 0,
            }
        })
        .collect();
    let total: u64 = lods
        .iter()
        .map(|l| u64::from(l.strands) * u64::from(l.segments_per_strand))
        .sum();
    if p.enabled && total > u64::from(p.segment_budget) {
        let factor = p.segment_budget as f64 / total as f64;
        for l in &mut lods {
            l.strands = (f64::from(l.strands) * factor).floor() as u32;
        }
    }
    // Kept strands and drawn segments of the earlier models.
    let (mut prefix, mut drawn) = (0, 0);
    for (l, m) in lods.iter_mut().zip(&scene.models) {
        if p.thickness_compensation && l.strands > 0 {
            // Coverage is additive in this pipeline: keep strands × thickness constant.
            l.thickness_scale = (m.strand_count as f32 / l.strands as f32)
                .min(p.max_thickness_scale)
                .max(1.0);
        }
        l.strand_prefix = prefix;
        prefix += l.strands;
        l.segment_prefix = drawn;
        drawn += l.drawn();
    }
    lods
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::FrameData;
    use bytemuck::Zeroable;

    fn scene(models: Vec<ModelData>) -> Scene {
        let view = glam::Mat4::look_at_rh(
            glam::Vec3::new(0.0, 0.0, 3.0),
            glam::Vec3::ZERO,
            glam::Vec3::Y,
        );
        let proj = glam::Mat4::perspective_rh(0.8, 16.0 / 9.0, 0.02, 500.0);
        let mut frame = FrameData::zeroed();
        frame.view_proj = (proj * view).to_cols_array();
        frame.camera_pos = [0.0, 0.0, 3.0, 1.0];
        frame.screen = [1920.0, 1080.0, 1.0 / 1920.0, 1.0 / 1080.0];
        frame.near = 0.02;
        frame.far = 500.0;
        frame.model_count = models.len() as u32;
        Scene { frame, models }
    }

    fn model(strands: u32, points: u32, centre: [f32; 3], half: f32) -> ModelData {
        let mut m = ModelData::zeroed();
        m.strand_count = strands;
        m.points_per_strand = points;
        m.bounds_min = [centre[0] - half, centre[1] - half, centre[2] - half, 0.0];
        m.bounds_max = [centre[0] + half, centre[1] + half, centre[2] + half, 0.0];
        m.flags = MODEL_LOD_ENABLED;
        m.min_fraction = 0.0;
        m
    }

    fn params() -> LodParams {
        LodParams::default()
    }

    #[test]
    fn per_model_cap_applies_to_large_models_only() {
        let s = scene(vec![
            model(200_000, 32, [0.0; 3], 0.15),
            model(3_000, 32, [0.3, 0.0, 0.0], 0.05),
        ]);
        let mut p = params();
        p.segments_per_tile = u32::MAX / 4096; // isolate the cap
        p.segment_budget = u32::MAX;
        let l = choose(&p, &s);
        assert_eq!(l[0].strands, 65536);
        assert_eq!(l[1].strands, 3_000, "small models are not reduced");
        assert!((l[0].thickness_scale - 200_000.0 / 65536.0).abs() < 1e-3);
    }

    #[test]
    fn segments_per_tile_bound_shrinks_small_screen_models() {
        let near = choose(&params(), &scene(vec![model(60_000, 32, [0.0; 3], 0.15)]))[0].strands;
        let far = choose(
            &params(),
            &scene(vec![model(60_000, 32, [0.0, 0.0, -40.0], 0.15)]),
        )[0]
        .strands;
        assert!(far < near / 10, "far {far} vs near {near}");
    }

    #[test]
    fn budget_of_two_million_segments_is_never_exceeded() {
        // Twelve close 130k-strand models: the Kulikov worst case.
        let models = (0..12)
            .map(|i| model(130_000, 32, [i as f32 * 0.1 - 0.6, 0.0, 0.0], 0.5))
            .collect();
        let mut p = params();
        p.max_strands = 1 << 20;
        p.segments_per_tile = u32::MAX / 4096; // close-ups: the budget is what binds
        let l = choose(&p, &scene(models));
        let total: u64 = l
            .iter()
            .map(|l| u64::from(l.strands) * u64::from(l.segments_per_strand))
            .sum();
        assert!(total <= 2_000_000, "{total} segments");
        assert!(
            total > 1_900_000,
            "proportional reduction should use the budget: {total}"
        );
        assert!(
            l.windows(2)
                .all(|w| w[0].strands.abs_diff(w[1].strands) <= 1 + w[0].strands / 10)
        );
    }

    #[test]
    fn far_models_skip_every_other_vertex() {
        let l = choose(
            &params(),
            &scene(vec![model(1000, 32, [0.0, 0.0, -20.0], 0.15)]),
        );
        assert_eq!(l[0].vertex_step, 2);
        assert_eq!(l[0].segments_per_strand, 16);
        assert_eq!(l[0].segment_vertices(32, 15), (30, 31));
    }

    #[test]
    fn disabled_lod_draws_everything() {
        let mut p = params();
        p.enabled = false;
        let l = choose(
            &p,
            &scene(vec![model(100_000, 32, [0.0, 0.0, -40.0], 0.15)]),
        );
        assert_eq!(
            (l[0].strands, l[0].vertex_step, l[0].thickness_scale),
            (100_000, 1, 1.0)
        );
        // Except the payload's hard limit of 2^22 segments per model.
        let l = choose(&p, &scene(vec![model(200_000, 32, [0.0; 3], 0.15)]));
        assert_eq!(l[0].strands, (1 << 22) / 31);
    }
}
