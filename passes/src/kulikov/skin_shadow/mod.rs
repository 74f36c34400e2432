//! `kulikov.skin_shadow`: hair shadows and ambient occlusion on opaque
//! pixels, marched through the hair density grids.
//!
//! Kulikov, "Hair volumetric shadows": "Raymarch hair density volume for
//! each skin pixel for each light. 6 steps per light, 1 ray per pixel,
//! 48x48x48 grid resolution. Also handles ambient occlusion (1 ray with 2
//! steps)." Our grids are `kulikov.density`'s, one per hair model over its
//! world bounds; a ray crosses every model's grid it meets (facial hair
//! shadows the face as the main hair does).
//!
//! The game shades skin with the march inline. We write a per-pixel shadow
//! mask instead (`skin_shadow`, one word per pixel) that `scene.opaque`
//! reads, so the opaque pass keeps one interface on every pipeline: graphs
//! without hair volumes clear the mask to "lit" (`common.clear` with
//! `0xFFFFFFFF`). Mask word: bytes 0–2 the visibility of lights 0–2 (UNORM8;
//! further lights are unshadowed), byte 3 the ambient occlusion.
//!
//! The position comes from `scene.depth` at the pixel centre. The AO ray
//! goes along a normal rebuilt from the neighbouring depths (the side with
//! the smaller depth step, so silhouettes do not bend it); the game has the
//! G-buffer normal, we have a depth prepass only.

mod tile;

use super::Scene;
use super::density::{AREA_UNIT, GRID_WORDS, Grid, MAX_RESOLUTION, check_resolution};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::layout::{LightData, read};
use crate::params::{Invalid, PassParams, in_range, non_negative};
use glam::{Mat4, Vec3, Vec4};
use strandgraph_graph::schema::Quantity;

const GROUP: u32 = 64;
/// Lights with a shadow byte in the mask word.
pub const MASK_LIGHTS: usize = 3;
/// The mask of a pixel nothing shadows (and of background pixels).
pub const LIT: u32 = 0xFFFF_FFFF;

pub static SKIN_SHADOW: PassKind<SkinShadowParams, SkinShadowGpu> = PassKind {
    kind: "kulikov.skin_shadow",
    summary: "hair shadows and AO on opaque pixels: march the density grids towards each light (6 steps) and along the normal (2 steps), into a per-pixel mask scene.opaque reads",
    source: "Kulikov 2025, 'Hair volumetric shadows'",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("lights"),
        Binding::read("density_grid"),
        Binding::read("scene.depth"),
        Binding::write("skin_shadow"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Pixels,
        per_group: GROUP,
    },
    shader: Shader::compute("kulikov/skin_shadow.wgsl", "march_skin"),
    kernel: |p| Box::new(*p),
    gpu: |p, q| p.uniform(q.width, q.height),
    raster: None,
};

/// The pass's parameters, with the talk's values as defaults.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SkinShadowParams {
    /// Grid edge of `density_grid` (as written by `kulikov.density`).
    pub resolution: u32,
    /// March steps per light (Kulikov: 6); 0 turns hair shadows off.
    pub steps: u32,
    /// AO steps along the normal (Kulikov: 2); 0 turns AO off.
    pub ao_steps: u32,
    /// How far the AO ray goes, in metres.
    pub ao_distance: f32,
    /// Extinction per strand crossed: the shadow intensity artists control
    /// (per asset in the game; one value per pass here).
    pub absorption: f32,
    /// The same for ambient occlusion.
    pub ao_absorption: f32,
    /// Ours: each workgroup marches only the grids a ray from its pixels
    /// can reach ([`tile`]); the mask is the same either way.
    pub tile_cull: bool,
}

impl Default for SkinShadowParams {
    fn default() -> Self {
        Self {
            resolution: MAX_RESOLUTION,
            steps: 6,
            ao_steps: 2,
            ao_distance: 0.05,
            absorption: 1.0,
            ao_absorption: 1.0,
            tile_cull: true,
        }
    }
}

impl PassParams for SkinShadowParams {
    fn validate(&self) -> Result<(), Invalid> {
        check_resolution(self.resolution)?;
        in_range("steps", self.steps, 0..=64)?;
        in_range("ao_steps", self.ao_steps, 0..=64)?;
        non_negative("ao_distance", self.ao_distance)?;
        non_negative("absorption", self.absorption)?;
        non_negative("ao_absorption", self.ao_absorption)
    }
}

crate::gpu_block! {
    /// The WGSL `SkinShadowParams` block.
    pub struct SkinShadowGpu {
        width: u32,
        height: u32,
        resolution: u32,
        steps: u32,
        ao_steps: u32,
        ao_distance: f32,
        absorption: f32,
        ao_absorption: f32,
        tile_cull: u32,
    }
}

impl SkinShadowParams {
    /// The WGSL block for a `width` × `height` screen.
    pub fn uniform(&self, width: u32, height: u32) -> SkinShadowGpu {
        SkinShadowGpu {
            width,
            height,
            resolution: self.resolution,
            steps: self.steps,
            ao_steps: self.ao_steps,
            ao_distance: self.ao_distance,
            absorption: self.absorption,
            ao_absorption: self.ao_absorption,
            tile_cull: crate::contract::flag(self.tile_cull),
        }
    }
}

/// Where a ray from `p` along `dir` is inside the grid's box: `(enter, exit)`
/// with `enter >= 0`, or `None` when it misses (slab test).
pub fn ray_box(g: &Grid, p: Vec3, dir: Vec3) -> Option<(f32, f32)> {
    let (mut enter, mut exit) = (0.0f32, f32::MAX);
    for a in 0..3 {
        let (lo, hi) = (g.min[a], g.min[a] + g.size[a]);
        if dir[a].abs() > 1e-8 {
            let (t0, t1) = ((lo - p[a]) / dir[a], (hi - p[a]) / dir[a]);
            enter = enter.max(t0.min(t1));
            exit = exit.min(t0.max(t1));
        } else if p[a] < lo || p[a] > hi {
            return None;
        }
    }
    (enter < exit).then_some((enter, exit))
}

/// Density units of voxel `i`, zero outside the grid.
fn voxel(grid: &Words<'_>, base: u32, r: i64, i: [i64; 3]) -> f32 {
    if i.iter().any(|&i| i < 0 || i >= r) {
        return 0.0;
    }
    grid.load((i64::from(base) + (i[2] * r + i[1]) * r + i[0]) as usize) as f32
}

fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// The trilinear blend of a cell's corners, x first, then y, then z:
/// `front` holds the corners at z, `back` at z + 1, each as (x, y),
/// (x + 1, y), (x, y + 1), (x + 1, y + 1).
fn blend(front: [f32; 4], back: [f32; 4], t: [f32; 3]) -> f32 {
    let face = |c: [f32; 4]| lerp(lerp(c[0], c[1], t[0]), lerp(c[2], c[3], t[0]), t[1]);
    lerp(face(front), face(back), t[2])
}

/// The grid's density units at `p`, trilinear between voxel centres with
/// zero outside the grid: what a 3D texture with a linear sampler and a
/// zero border returns. Nearest-voxel lookups print the 48³ voxels as
/// blocks onto the skin. (The WGSL reads a cell inside the grid from one
/// base index; the blend is the same.)
pub fn trilinear(grid: &Words<'_>, base: u32, g: &Grid, p: Vec3) -> f32 {
    let r = i64::from(g.resolution);
    let f = [0, 1, 2].map(|a| (p[a] - g.min[a]) / g.size[a] * r as f32 - 0.5);
    let i0 = f.map(|f| f.floor());
    let t = [0, 1, 2].map(|a| f[a] - i0[a]);
    let [x, y, z] = i0.map(|i| i as i64);
    let at = |dx, dy, dz| voxel(grid, base, r, [x + dx, y + dy, z + dz]);
    blend(
        [at(0, 0, 0), at(1, 0, 0), at(0, 1, 0), at(1, 1, 0)],
        [at(0, 0, 1), at(1, 0, 1), at(0, 1, 1), at(1, 1, 1)],
        t,
    )
}

/// Strands crossed from `p` along unit `dir` up to `max_t` through one
/// model's grid: `steps` samples at the centres of equal intervals of the
/// part of the ray inside the box. Kulikov: "Raymarch hair density volume".
pub fn crossed(
    grid: &Words<'_>,
    base: u32,
    g: &Grid,
    p: Vec3,
    dir: Vec3,
    max_t: f32,
    steps: u32,
) -> f32 {
    let Some((t0, t1)) = ray_box(g, p, dir) else {
        return 0.0;
    };
    let t1 = t1.min(max_t);
    if steps == 0 || t1 <= t0 {
        return 0.0;
    }
    let dt = (t1 - t0) / steps as f32;
    let units: f32 = (0..steps)
        .map(|i| trilinear(grid, base, g, p + dir * (t0 + (i as f32 + 0.5) * dt)))
        .sum();
    // Grid::sigma of the summed units.
    units * AREA_UNIT / g.voxel_volume() * dt
}

/// UNORM8 of a visibility in [0, 1], rounding half away from zero (as the
/// WGSL's `floor(x * 255 + 0.5)`).
fn unorm8(v: f32) -> u32 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5).floor() as u32
}

/// What a mask word means for light `i` (`None`: no shadow byte, lit) and
/// for the ambient term.
pub fn light_visibility(mask: u32, i: usize) -> f32 {
    if i < MASK_LIGHTS {
        ((mask >> (8 * i)) & 0xFF) as f32 / 255.0
    } else {
        1.0
    }
}

pub fn ambient_visibility(mask: u32) -> f32 {
    (mask >> 24) as f32 / 255.0
}

struct Pixels<'a> {
    depth: Words<'a>,
    inv_view_proj: Mat4,
    width: u32,
    height: u32,
}

impl Pixels<'_> {
    /// The world position at pixel `(x, y)`'s centre, `None` on background.
    fn world(&self, x: i64, y: i64) -> Option<Vec3> {
        if x < 0 || y < 0 || x >= i64::from(self.width) || y >= i64::from(self.height) {
            return None;
        }
        let z = f32::from_bits(self.depth.load((y * i64::from(self.width) + x) as usize));
        if !(z < 1.0) {
            return None;
        }
        let ndc = Vec4::new(
            (x as f32 + 0.5) / self.width as f32 * 2.0 - 1.0,
            1.0 - (y as f32 + 0.5) / self.height as f32 * 2.0,
            z,
            1.0,
        );
        let w = self.inv_view_proj * ndc;
        Some(w.truncate() / w.w)
    }

    /// The normal from the neighbours' positions, facing `eye`; on each
    /// axis the side with the smaller step (no bending at silhouettes).
    fn normal(&self, x: i64, y: i64, p: Vec3, eye: Vec3) -> Vec3 {
        let pick = |a: Option<Vec3>, b: Option<Vec3>| match (a, b) {
            (Some(a), Some(b)) if (a - p).length_squared() <= (p - b).length_squared() => a - p,
            (Some(a), None) => a - p,
            (_, Some(b)) => p - b,
            (None, None) => Vec3::ZERO,
        };
        let dx = pick(self.world(x + 1, y), self.world(x - 1, y));
        let dy = pick(self.world(x, y + 1), self.world(x, y - 1));
        let n = dx.cross(dy).normalize_or_zero();
        let to_eye = (eye - p).normalize_or(Vec3::Z);
        match n.dot(to_eye) {
            d if d > 0.0 => n,
            d if d < 0.0 => -n,
            _ => to_eye,
        }
    }
}

impl CpuKernel for SkinShadowParams {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let lights_w = ctx.words("lights");
        let stored = (lights_w.len() / (std::mem::size_of::<LightData>() / 4)) as u32;
        let lights: Vec<LightData> = (0..scene.frame.light_count.min(stored))
            .take(MASK_LIGHTS)
            .map(|i| read(&lights_w, i as usize))
            .collect();
        let (grid, out) = (ctx.words("density_grid"), ctx.words("skin_shadow"));
        let px = Pixels {
            depth: ctx.words("scene.depth"),
            inv_view_proj: Mat4::from_cols_array(&scene.frame.inv_view_proj),
            width: ctx.quantities.width,
            height: ctx.quantities.height,
        };
        let eye = Vec3::from_slice(&scene.frame.camera_pos[..3]);
        let grids: Vec<Grid> = scene
            .models
            .iter()
            .map(|m| Grid::of(m, self.resolution))
            .collect();
        // The workgroup's pixels and their world positions.
        let pixels: Vec<(u32, Option<Vec3>)> = (group * GROUP..(group + 1) * GROUP)
            .take_while(|&i| i < px.width * px.height)
            .map(|i| {
                (
                    i,
                    px.world(i64::from(i % px.width), i64::from(i / px.width)),
                )
            })
            .collect();
        let ao = (self.ao_steps > 0).then_some(self.ao_distance);
        let reached: Vec<bool> = match tile::TileBox::of(pixels.iter().filter_map(|p| p.1)) {
            Some(b) if self.tile_cull => (0..grids.len())
                .map(|m| m >= tile::MASKED_MODELS || b.reaches(&grids[m], &lights, ao))
                .collect(),
            _ => vec![true; grids.len()],
        };
        // Strands crossed along a ray, over every model's grid the tile reaches.
        let march = |p: Vec3, dir: Vec3, max_t: f32, steps: u32| -> f32 {
            grids
                .iter()
                .enumerate()
                .filter(|&(m, _)| reached[m])
                .map(|(m, g)| crossed(&grid, m as u32 * GRID_WORDS, g, p, dir, max_t, steps))
                .sum()
        };
        for (i, world) in pixels {
            let (x, y) = (i64::from(i % px.width), i64::from(i / px.width));
            let Some(p) = world else {
                out.store(i as usize, LIT);
                continue;
            };
            let mut mask = LIT;
            for (l, light) in lights.iter().enumerate() {
                let [lx, ly, lz, kind] = light.position_or_direction;
                let (dir, dist) = if kind == 0.0 {
                    (-Vec3::new(lx, ly, lz).normalize_or_zero(), f32::MAX)
                } else {
                    let d = Vec3::new(lx, ly, lz) - p;
                    (d.normalize_or_zero(), d.length())
                };
                let v = (-self.absorption * march(p, dir, dist, self.steps)).exp();
                mask = mask & !(0xFF << (8 * l)) | unorm8(v) << (8 * l);
            }
            if self.ao_steps > 0 {
                let n = px.normal(x, y, p, eye);
                let v = (-self.ao_absorption * march(p, n, self.ao_distance, self.ao_steps)).exp();
                mask = mask & 0x00FF_FFFF | unorm8(v) << 24;
            }
            out.store(i as usize, mask);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::harness::Harness;
    use crate::layout::{ModelData, words_of};
    use crate::opaque_mesh::testing::frame;
    use strandgraph_graph::Quantities;

    /// A 1 m box of hair above the origin: uniform density `units` per voxel.
    fn hair_box(units: u32) -> (ModelData, Vec<u32>) {
        let model = ModelData {
            bounds_min: [-0.5, 0.1, -0.5, 1.0],
            bounds_max: [0.5, 1.1, 0.5, 1.0],
            ..bytemuck::Zeroable::zeroed()
        };
        (model, vec![units; GRID_WORDS as usize])
    }

    /// A w×h view down at a floor at y = 0 (depth from the real projection).
    fn floor_view(w: u32, h: u32, light_dir: Vec3, units: u32) -> Harness {
        let eye = Vec3::new(0.0, 3.0, 0.01);
        let mut f = frame(eye, Vec3::ZERO, 40.0, w, h);
        let (model, grid) = hair_box(units);
        f.model_count = 1;
        f.light_count = 1;
        let vp = Mat4::from_cols_array(&f.view_proj);
        let inv = Mat4::from_cols_array(&f.inv_view_proj);
        // Depth of the floor per pixel: intersect the pixel ray with y = 0.
        let depth: Vec<u32> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let ndc = |z: f32| {
                    let q = inv
                        * Vec4::new(
                            (x as f32 + 0.5) / w as f32 * 2.0 - 1.0,
                            1.0 - (y as f32 + 0.5) / h as f32 * 2.0,
                            z,
                            1.0,
                        );
                    q.truncate() / q.w
                };
                let (a, b) = (ndc(0.0), ndc(1.0));
                let t = a.y / (a.y - b.y);
                let hit = a + (b - a) * t;
                let c = vp * hit.extend(1.0);
                (c.z / c.w).to_bits()
            })
            .collect();
        let light = LightData {
            position_or_direction: [light_dir.x, light_dir.y, light_dir.z, 0.0],
            radiance: [1.0; 4],
            _pad: [0; 8],
        };
        let mut hs = Harness::new(Quantities {
            models: 1,
            lights: 1,
            width: w,
            height: h,
            ..Default::default()
        });
        hs.buffer("frame", words_of(&[f]))
            .buffer("models", words_of(&[model]))
            .buffer("lights", words_of(&[light]))
            .buffer("density_grid", grid)
            .buffer("scene.depth", depth)
            .buffer("skin_shadow", vec![0; (w * h) as usize]);
        hs
    }

    fn run(hs: &Harness, params: &str) -> Vec<u32> {
        let kernel =
            crate::PassDef::cpu_kernel(&SKIN_SHADOW, &ron::from_str(params).unwrap()).unwrap();
        let (w, h) = (hs.quantities.width, hs.quantities.height);
        hs.run(kernel.as_ref(), (w * h).div_ceil(GROUP), GROUP);
        hs.read("skin_shadow")
    }

    #[test]
    fn hair_above_shadows_the_floor_under_it_only_and_matches_beer_lambert() {
        // Light straight down: pixels under the box cross 1 m of hair.
        let hs = floor_view(32, 32, Vec3::NEG_Y, 1000);
        let mask = run(&hs, "{}");
        let g = Grid::of(&hair_box(0).0, 48);
        let expected = (-g.sigma(1000) * 1.0).exp();
        let centre = light_visibility(mask[16 * 32 + 16], 0);
        assert!(
            (centre - expected).abs() < 2.0 / 255.0,
            "{centre} vs {expected}"
        );
        // The floor's corners are outside the box's shadow: fully lit.
        assert_eq!(light_visibility(mask[0], 0), 1.0);
        // Lights beyond the first are not in the mask: lit.
        assert_eq!(light_visibility(mask[16 * 32 + 16], 1), 1.0);
        // No shadow steps: everything lit.
        let off = run(&hs, "{\"steps\": 0, \"ao_steps\": 0}");
        assert!(off.iter().all(|&m| m == LIT));
    }

    #[test]
    fn a_light_from_below_casts_no_hair_shadow_and_ao_darkens_only_under_hair() {
        let hs = floor_view(32, 32, Vec3::Y, 3000);
        let mask = run(&hs, "{\"ao_distance\": 0.5}");
        assert_eq!(light_visibility(mask[16 * 32 + 16], 0), 1.0);
        // The floor's normal points up into the hair under the box: occluded.
        let under = ambient_visibility(mask[16 * 32 + 16]);
        assert!(under < 0.9, "{under}");
        assert_eq!(ambient_visibility(mask[0]), 1.0);
    }

    #[test]
    fn tile_culling_changes_no_bit() {
        for light in [Vec3::NEG_Y, Vec3::new(-1.0, -1.0, 0.3), Vec3::Y] {
            let hs = floor_view(48, 40, light, 2000);
            let on = run(&hs, "{\"ao_distance\": 0.5}");
            let off = run(&hs, "{\"ao_distance\": 0.5, \"tile_cull\": false}");
            assert!(on == off, "light {light}");
            assert!(
                on.iter().any(|&m| m != LIT),
                "light {light}: nothing shadowed"
            );
        }
    }

    #[test]
    fn trilinear_is_exact_on_linear_densities_and_fades_to_zero_outside() {
        // 4³ voxels over the unit cube; voxel (x, y, z) holds 1 + x + 2y + 4z.
        let g = Grid {
            min: [0.0; 3],
            size: [1.0; 3],
            resolution: 4,
        };
        let words: Vec<std::sync::atomic::AtomicU32> = (0..64u32)
            .map(|v| (1 + (v & 3) + 2 * (v >> 2 & 3) + 4 * (v >> 4)).into())
            .collect();
        let oob = std::sync::atomic::AtomicU64::new(0);
        let grid = Words::new(&words, &oob);
        // Voxel centres are at (i + 0.5) / 4; inside them the blend is exact.
        let at = |x: f32, y: f32, z: f32| (x * 4.0 - 0.5, y * 4.0 - 0.5, z * 4.0 - 0.5);
        for p in [[0.2f32, 0.3, 0.4], [0.5, 0.5, 0.5], [0.8, 0.13, 0.6]] {
            let (x, y, z) = at(p[0], p[1], p[2]);
            let got = trilinear(&grid, 0, &g, Vec3::from(p));
            assert!(
                (got - (1.0 + x + 2.0 * y + 4.0 * z)).abs() < 1e-4,
                "{p:?}: {got}"
            );
        }
        // On the grid's face the outer half-voxel blends with zero outside.
        let face = trilinear(&grid, 0, &g, Vec3::new(0.0, 0.625, 0.625));
        let inner = trilinear(&grid, 0, &g, Vec3::new(0.125, 0.625, 0.625));
        assert!((face - 0.5 * inner).abs() < 1e-4, "{face} vs {inner}");
        assert_eq!(trilinear(&grid, 0, &g, Vec3::new(2.0, 0.5, 0.5)), 0.0);
        assert_eq!(oob.load(std::sync::atomic::Ordering::Relaxed), 0);
    }

    #[test]
    fn rays_enter_the_box_from_outside_and_miss_it() {
        let g = Grid::of(&hair_box(0).0, 48);
        let hit = ray_box(&g, Vec3::new(0.0, -1.0, 0.0), Vec3::Y).unwrap();
        assert!((hit.0 - 1.1).abs() < 1e-5 && (hit.1 - 2.1).abs() < 1e-5);
        assert!(ray_box(&g, Vec3::new(2.0, 0.0, 0.0), Vec3::Y).is_none());
        assert!(ray_box(&g, Vec3::new(0.0, 2.0, 0.0), Vec3::Y).is_none());
    }

    #[test]
    fn params_are_checked() {
        let p = |s: &str| SKIN_SHADOW.params(&ron::from_str(s).unwrap());
        assert_eq!(p("{}").unwrap().steps, 6);
        assert_eq!(p("{}").unwrap().ao_steps, 2);
        assert!(p("{\"steps\": 65}").is_err());
        assert!(p("{\"absorption\": -1.0}").is_err());
        assert!(p("{\"resolution\": 49}").is_err());
    }
}
