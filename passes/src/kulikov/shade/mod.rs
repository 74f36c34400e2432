//! `kulikov.shade`: per-vertex hair lighting in strand space.
//!
//! Kulikov, "Shading": "We shade strands per vertex to get smoother shading
//! and save performance", Marschner R/TT/TRT plus multiple scattering with a
//! scalar per lobe ([`karis`]). One lane per visible segment of
//! `shading_segments` (natural order, from `kulikov.shade_sort`): the lane
//! shades the segment's root-side vertex, and its tip-side vertex too when
//! the next segment of the strand is not visible, so every vertex of a
//! visible segment is shaded by exactly one lane. World positions come from
//! the post-transform cache (`inv_view_proj × clip`); the tangent is the
//! segment's direction towards the root. Output: radiance towards the
//! camera, `vertex_lighting` (rgba16f per vertex).
//!
//! Self-shadowing (`self_shadow`), Kulikov "Self-shadowing":
//! - `"None"`: every light unshadowed;
//! - `"VoxelMarch"`: march the model's `density_grid` towards each light
//!   (`march_steps` samples, grid `resolution`), "Density volume raymarching
//!   for each light"; visibility = exp(−absorption · strands crossed);
//! - `"Baked"`: Kulikov's "Precomputed self-shadowing", the shipped one:
//!   per vertex, clamped L1 SH of the number of scattering events towards
//!   every direction, ray traced offline against the strands and the head
//!   (`strandgraph-bake`, packed as `groom.shadow_sh`, 4 × f32 per vertex);
//!   "Fetch baked visibility at runtime and use for all lights":
//!   visibility = exp(−absorption · max(0, SH · light direction)). The bake
//!   settings are this pass's parameters too (`bake_rays`,
//!   `bake_max_distance`, `bake_vertex_stride`, `bake_occluder_stride`,
//!   `max_scatter_events`), so `frame::prepare` bakes with them when the
//!   live shade pass selects `"Baked"`.

pub mod karis;

use super::cull::drawn_segment;
use super::debug_resolve::store_rgba16f;
use super::density::{GRID_WORDS, Grid, MAX_RESOLUTION, check_resolution};
use super::shade_sort::{MAX_SHADE_GROUPS, SHADE_GROUP};
use super::{Scene, world_of_clip};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::layout::{LightData, read};
use crate::params::{Invalid, PassParams, in_range};
use glam::Vec3;
use karis::{Lobes, hair_shading};
use strandgraph_bake::{BakeSettings, HAIR_MAX_SCATTER_EVENTS};

crate::string_enum! {
    /// How lights are shadowed by the hair itself.
    pub enum SelfShadow {
        None,
        VoxelMarch,
        Baked,
    }
}

impl SelfShadow {
    /// The WGSL parameter block's encoding.
    pub fn code(self) -> u32 {
        self as u32
    }
}

/// The pass's parameters as the graph names them.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShadeParams {
    pub self_shadow: SelfShadow,
    /// Extinction per strand crossed.
    pub absorption: f32,
    /// Grid edge of `density_grid` (as written by `kulikov.density`).
    pub resolution: u32,
    /// `VoxelMarch` samples per light (1..=256).
    pub march_steps: u32,
    /// Fraction of the base colour added as ambient light.
    pub ambient: f32,
    /// Kulikov: "Non-PBR scalars for each path".
    pub r_scale: f32,
    pub tt_scale: f32,
    pub trt_scale: f32,
    /// Karis's multiple-scattering weight; off with `multiple_scattering: false`.
    pub scatter: f32,
    pub multiple_scattering: bool,
    // The offline bake `"Baked"` reads (ignored by the other modes).
    pub bake_rays: u32,
    pub max_scatter_events: f32,
    pub bake_max_distance: f32,
    pub bake_vertex_stride: u32,
    pub bake_occluder_stride: u32,
}

/// Rays per probe vertex of the self-shadowing bake when the graph names none.
pub const DEFAULT_BAKE_RAYS: u32 = 16;
/// Probe every 8th vertex of a strand and its tip (Kulikov found "1 probe
/// per 4 vertices [...] very similar to 1 probe per 1 vertex"; 8 keeps the
/// showcase's 2.1M-vertex bake near a minute and a half on two cores).
pub const DEFAULT_BAKE_VERTEX_STRIDE: u32 = 8;
/// Trace against every 8th strand, 8× as thick (see
/// `strandgraph_bake::bvh::Occluders::new`).
pub const DEFAULT_BAKE_OCCLUDER_STRIDE: u32 = 8;
/// Metres a bake ray looks for occluders: "what matters most is short
/// neighborhood of each segment".
pub const DEFAULT_BAKE_MAX_DISTANCE: f32 = 0.1;

impl Default for ShadeParams {
    fn default() -> Self {
        Self {
            self_shadow: SelfShadow::VoxelMarch,
            absorption: 1.0,
            resolution: MAX_RESOLUTION,
            march_steps: 12,
            ambient: 0.05,
            r_scale: 1.0,
            tt_scale: 1.0,
            trt_scale: 1.0,
            scatter: 1.0,
            multiple_scattering: true,
            bake_rays: DEFAULT_BAKE_RAYS,
            max_scatter_events: HAIR_MAX_SCATTER_EVENTS,
            bake_max_distance: DEFAULT_BAKE_MAX_DISTANCE,
            bake_vertex_stride: DEFAULT_BAKE_VERTEX_STRIDE,
            bake_occluder_stride: DEFAULT_BAKE_OCCLUDER_STRIDE,
        }
    }
}

impl PassParams for ShadeParams {
    fn validate(&self) -> Result<(), Invalid> {
        in_range("march_steps", self.march_steps, 1..=256)?;
        check_resolution(self.resolution)?;
        self.bake().check().map_err(|e| {
            // BakeSettings names its own field first ("rays: ..."); the
            // graph's keys carry a `bake_` prefix.
            let detail = match &e {
                strandgraph_bake::BakeError::Settings(m) => m.clone(),
                other => other.to_string(),
            };
            let key = match detail.split(':').next().unwrap_or("") {
                "max_scatter_events" => "max_scatter_events".to_string(),
                field => format!("bake_{field}"),
            };
            Invalid::new(key, e.to_string())
        })
    }
}

impl ShadeParams {
    /// The per-lobe scalars the shading reads (the cuticle tilt is each
    /// model's, from its material; this gives Karis's 0.035 rad).
    pub fn lobes(&self) -> Lobes {
        Lobes {
            r: self.r_scale,
            tt: self.tt_scale,
            trt: self.trt_scale,
            scatter: if self.multiple_scattering {
                self.scatter
            } else {
                0.0
            },
            shift: 0.035,
        }
    }

    /// The offline bake `"Baked"` reads.
    pub fn bake(&self) -> BakeSettings {
        BakeSettings {
            rays: self.bake_rays,
            max_scatter_events: self.max_scatter_events,
            max_distance: self.bake_max_distance,
            vertex_stride: self.bake_vertex_stride,
            occluder_stride: self.bake_occluder_stride,
            ..BakeSettings::default()
        }
    }

    /// The WGSL `ShadeParams` block (binding 0, 48 bytes).
    pub fn uniform(&self) -> ShadeGpu {
        let l = self.lobes();
        ShadeGpu {
            lobes: [l.r, l.tt, l.trt, l.scatter],
            self_shadow: self.self_shadow.code(),
            absorption: self.absorption,
            resolution: self.resolution,
            march_steps: self.march_steps,
            ambient: self.ambient,
            ..ShadeGpu::default()
        }
    }
}

crate::gpu_block! {
    /// `ShadeParams` in shaders/kulikov/shade.wgsl.
    pub struct ShadeGpu {
        /// r, tt, trt scales; scatter (0 = no multiple scattering).
        lobes: [f32; 4],
        /// 0 None, 1 VoxelMarch, 2 Baked.
        self_shadow: u32,
        absorption: f32,
        resolution: u32,
        march_steps: u32,
        ambient: f32,
        // WGSL rounds the struct to its vec4 alignment.
        _pad0: u32,
        _pad1: u32,
        _pad2: u32,
    }
}

pub static SHADE: PassKind<ShadeParams, ShadeGpu> = PassKind {
    kind: "kulikov.shade",
    summary: "per-vertex Marschner (Karis 2016 R, TT, TRT, multiple scattering), self-shadowing: none, voxel march, baked SH",
    source: "Kulikov 2025, 'Shading', 'Self-shadowing'",
    bindings: Some(&[
        Binding::read("shade_args"),
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("lod_models"),
        Binding::read("lights"),
        Binding::read("shading_segments"),
        Binding::read("segment_visibility"),
        Binding::read("clip_positions"),
        Binding::read("density_grid"),
        Binding::read("groom.shadow_sh"),
        Binding::write("vertex_lighting"),
    ]),
    workgroup_size: SHADE_GROUP,
    dispatch: Dispatch::Indirect {
        binding: "shade_args",
        word: 0,
    },
    shader: Shader::compute("kulikov/shade.wgsl", "shade"),
    kernel: |p| {
        Box::new(ShadeKernel {
            params: *p,
            lobes: p.lobes(),
        })
    },
    gpu: |p, _| p.uniform(),
    raster: None,
};

struct ShadeKernel {
    params: ShadeParams,
    lobes: Lobes,
}

/// Distance along `dir` from `p` to where it leaves the box (0 if outside).
fn exit_distance(g: &Grid, p: Vec3, dir: Vec3) -> f32 {
    let mut t_exit = f32::MAX;
    for a in 0..3 {
        let (lo, hi) = (g.min[a], g.min[a] + g.size[a]);
        if dir[a] > 1e-8 {
            t_exit = t_exit.min((hi - p[a]) / dir[a]);
        } else if dir[a] < -1e-8 {
            t_exit = t_exit.min((lo - p[a]) / dir[a]);
        }
    }
    t_exit.max(0.0)
}

/// Kulikov: "Density volume raymarching for each light": strands crossed
/// from `p` towards the light, sampled at `steps` voxel centres, skipping
/// the voxel `p` sits in (its own strand is not a shadow caster).
pub fn march(
    grid: &Words<'_>,
    base: u32,
    g: &Grid,
    p: Vec3,
    dir: Vec3,
    max_t: f32,
    steps: u32,
) -> f32 {
    let voxel = g.size.iter().fold(f32::MAX, |a, &b| a.min(b)) / g.resolution as f32;
    let t0 = voxel;
    let t1 = exit_distance(g, p, dir).min(max_t);
    if t1 <= t0 {
        return 0.0;
    }
    let dt = (t1 - t0) / steps as f32;
    let mut crossed = 0.0;
    for i in 0..steps {
        let q = p + dir * (t0 + (i as f32 + 0.5) * dt);
        if let Some(v) = g.voxel(q.to_array()) {
            crossed += g.sigma(grid.load((base + v) as usize)) * dt;
        }
    }
    crossed
}

impl ShadeKernel {
    #[allow(clippy::too_many_arguments)]
    fn shade_vertex(
        &self,
        scene: &Scene,
        lights: &[LightData],
        grid: &Words<'_>,
        sh: [f32; 4],
        model: usize,
        p: Vec3,
        t: Vec3,
    ) -> Vec3 {
        let k = &self.params;
        let md = &scene.models[model];
        let cam = Vec3::from_slice(&scene.frame.camera_pos[..3]);
        let v = (cam - p).normalize_or(Vec3::Z);
        let color = Vec3::from_slice(&md.color[..3]);
        let g = Grid::of(md, k.resolution);
        let lobes = Lobes {
            shift: md.highlight_shift,
            ..self.lobes
        };
        let mut out = color * k.ambient;
        for l in lights {
            let [x, y, z, kind] = l.position_or_direction;
            let (to_light, dist, falloff) = if kind == 0.0 {
                (-Vec3::new(x, y, z).normalize_or_zero(), f32::MAX, 1.0)
            } else {
                let d = Vec3::new(x, y, z) - p;
                let d2 = d.length_squared().max(1e-4);
                (d / d2.sqrt(), d2.sqrt(), 1.0 / d2)
            };
            let visibility = match k.self_shadow {
                SelfShadow::VoxelMarch => {
                    let base = model as u32 * GRID_WORDS;
                    let n = march(grid, base, &g, p, to_light, dist, k.march_steps);
                    (-k.absorption * n).exp()
                }
                // Kulikov: "numScatterEvents = max(0, ProjectL1SH(visSH,
                // lightDirection)); visibility = exp(-absorption * numScatterEvents)".
                SelfShadow::Baked => {
                    strandgraph_bake::sh::visibility_towards(&sh, to_light.to_array(), k.absorption)
                }
                SelfShadow::None => 1.0,
            };
            let radiance = Vec3::from_slice(&l.radiance[..3]) * falloff;
            out += radiance * hair_shading(t, v, to_light, color, md.color[3], visibility, &lobes);
        }
        out
    }
}

impl CpuKernel for ShadeKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let lods = scene.lods(ctx);
        let (list, bits, clip, grid, sh_words, out) = (
            ctx.words("shading_segments"),
            ctx.words("segment_visibility"),
            ctx.words("clip_positions"),
            ctx.words("density_grid"),
            ctx.words("groom.shadow_sh"),
            ctx.words("vertex_lighting"),
        );
        // The vertex's baked SH (4 words); only loaded when it is read.
        let baked = self.params.self_shadow == SelfShadow::Baked;
        let sh = |v: u32| -> [f32; 4] {
            if baked {
                std::array::from_fn(|i| f32::from_bits(sh_words.load(4 * v as usize + i)))
            } else {
                [0.0; 4]
            }
        };
        let lw = ctx.words("lights");
        let lights: Vec<LightData> = (0..(scene.frame.light_count as usize).min(lw.len() / 16))
            .map(|i| read(&lw, i))
            .collect();
        let count = ctx.words("shade_args").load(3);
        let inv = scene.frame.inv_view_proj;
        let world = |v: u32| Vec3::from(world_of_clip(&inv, clip.load_vec4(v as usize)));
        // A lane per segment, striding past the dispatch's cap.
        let stride = (MAX_SHADE_GROUPS * SHADE_GROUP) as usize;
        let lanes = (group * SHADE_GROUP..(group + 1) * SHADE_GROUP)
            .flat_map(|first| (first as usize..count as usize).step_by(stride));
        for i in lanes {
            let id = list.load(i);
            let Some(seg) = drawn_segment(&scene, &lods, id) else {
                continue;
            };
            let (p0, p1) = (world(seg.v0), world(seg.v1));
            // Towards the root (Karis's convention).
            let t = (p0 - p1).normalize_or(Vec3::Y);
            let c0 = self.shade_vertex(&scene, &lights, &grid, sh(seg.v0), seg.model, p0, t);
            store_rgba16f(&out, seg.v0 as usize, [c0.x, c0.y, c0.z, 1.0]);
            let per = scene.models[seg.model].points_per_strand - 1;
            let last = seg.local % per + 1 >= lods[seg.model].segments_per_strand;
            let next = id + 1;
            if last || bits.load((next / 32) as usize) & (1 << (next % 32)) == 0 {
                let c1 = self.shade_vertex(&scene, &lights, &grid, sh(seg.v1), seg.model, p1, t);
                store_rgba16f(&out, seg.v1 as usize, [c1.x, c1.y, c1.z, 1.0]);
            }
        }
    }
}

#[cfg(test)]
mod tests;
