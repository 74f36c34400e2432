//! `scene.opaque`: shade opaque meshes into `output`, once per pixel, from
//! the visibility buffer `scene.visibility` wrote.
//!
//! Each lane takes one pixel, fetches the triangle that won it, sets it up
//! again with the same integer rasterizer ([`Setup`](super::setup::Setup)),
//! and interpolates its corners perspective-correctly from the exact edge
//! functions at the pixel centre: deferred shading from a visibility buffer
//! (Burns and Hunt, "The Visibility Buffer: A Cache-Friendly Approach to
//! Deferred Shading", JCGT 2013). Pixels no triangle covers get `background`.
//!
//! Shading is diffuse with the scene's lights plus a small ambient term, in
//! linear RGB (the CLI tone-maps when saving), with Green's wrap lighting
//! per channel (GPU Gems, 2004, ch. 16, "Real-Time Approximations to
//! Subsurface Scattering": `max((n·l + w) / (1 + w), 0)`; a wider wrap in
//! red is skin's cheap subsurface look) and each corner's painted albedo
//! interpolated, or the pass's `albedo` for unpainted meshes. Each light's
//! irradiance and the ambient term are scaled by the pixel's `skin_shadow`
//! mask word (bytes 0–2: lights 0–2, byte 3: ambient; see
//! `kulikov::skin_shadow`), written by `kulikov.skin_shadow` from the hair
//! density, or cleared to `0xFFFFFFFF` (lit) by graphs without hair volumes.
//!
//! `output` is `Rgba16Float`: 2 words per texel, row-major,
//! word 0 = r | g << 16, word 1 = b | a << 16 (IEEE half floats).

use super::visibility::unpack;
use super::{PIXEL_GROUP, View, corner_normals, corners, pixel_dispatch};
use crate::contract::{Binding, CpuKernel, Shader};
use crate::describe::PassKind;
use crate::kernel::{CounterValues, Ctx, Words};
use crate::kulikov::skin_shadow::{ambient_visibility, light_visibility};
use crate::layout::{LightData, read, unpack_albedo};
use crate::params::{Invalid, PassParams, non_negative};
use glam::Vec3;
use half::f16;

pub static OPAQUE: PassKind<OpaqueParams, OpaqueGpu> = PassKind {
    kind: "scene.opaque",
    summary: "shade opaque meshes from their visibility buffer, including hair shadows on skin",
    source: "Kulikov 2025, 'Hair shadows on skin'; Burns and Hunt 2013 (visibility buffer)",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("mesh.triangles"),
        Binding::read("lights"),
        Binding::read("skin_shadow"),
        Binding::read("scene.visibility"),
        Binding::write("output"),
    ]),
    workgroup_size: PIXEL_GROUP,
    dispatch: pixel_dispatch(),
    shader: Shader::compute("opaque_mesh/opaque.wgsl", "opaque"),
    kernel: |p| Box::new(OpaqueKernel { params: *p }),
    gpu: |p, q| p.uniform(q.width, q.height),
    raster: None,
};

/// The pass's parameters, with their defaults.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct OpaqueParams {
    /// Linear RGB where no mesh is drawn.
    pub background: [f32; 3],
    /// Linear RGB diffuse albedo (default: a skin tone).
    pub albedo: [f32; 3],
    /// Fraction of the albedo added everywhere, standing in for sky light.
    pub ambient: f32,
    /// Diffuse wrap per channel (0 = Lambert).
    pub wrap: [f32; 3],
}

impl Default for OpaqueParams {
    fn default() -> Self {
        Self {
            background: [0.02, 0.02, 0.025],
            albedo: [0.62, 0.4, 0.31],
            ambient: 0.05,
            wrap: [0.3, 0.12, 0.1],
        }
    }
}

impl PassParams for OpaqueParams {
    fn validate(&self) -> Result<(), Invalid> {
        non_negative("ambient", self.ambient)?;
        if !self.wrap.iter().all(|w| (0.0..=1.0).contains(w)) {
            return Err(Invalid::new(
                "wrap",
                format!("expected three numbers in 0..=1, got {:?}", self.wrap),
            ));
        }
        for (key, rgb) in [("background", self.background), ("albedo", self.albedo)] {
            if !rgb.iter().all(|c| c.is_finite() && *c >= 0.0) {
                return Err(Invalid::new(
                    key,
                    format!("expected three numbers >= 0, got {rgb:?}"),
                ));
            }
        }
        Ok(())
    }
}

crate::gpu_block! {
    /// `OpaqueParams` in shaders/opaque_mesh/opaque.wgsl.
    pub struct OpaqueGpu {
        /// rgb: albedo; a: ambient.
        albedo_ambient: [f32; 4],
        /// xyz: wrap per channel.
        wrap: [f32; 4],
        /// rgb: where no mesh is drawn; a: 1.
        background: [f32; 4],
        width: u32,
        height: u32,
        _pad: [u32; 2],
    }
}

impl OpaqueParams {
    /// The WGSL `OpaqueParams` block at binding 0, for a `width` × `height` screen.
    pub fn uniform(&self, width: u32, height: u32) -> OpaqueGpu {
        let [r, g, b] = self.albedo;
        let [wr, wg, wb] = self.wrap;
        let [br, bg, bb] = self.background;
        OpaqueGpu {
            albedo_ambient: [r, g, b, self.ambient],
            wrap: [wr, wg, wb, 0.0],
            background: [br, bg, bb, 1.0],
            width,
            height,
            _pad: [0; 2],
        }
    }
}

/// Linear RGB reflected towards the camera from a point `p` with unit
/// normal `n`: wrapped diffuse (albedo/π) over every light, whose radiance is
/// taken as irradiance at normal incidence (at 1 m for point lights, which
/// fall off with the inverse square), plus `ambient` × albedo; lights and
/// ambient scaled by the `shadow` mask word.
pub fn shade(
    p: Vec3,
    n: Vec3,
    lights: &[LightData],
    albedo: Vec3,
    ambient: f32,
    wrap: Vec3,
    shadow: u32,
) -> Vec3 {
    let mut irradiance = Vec3::ZERO;
    for (i, l) in lights.iter().enumerate() {
        let [x, y, z, kind] = l.position_or_direction;
        let (to_light, falloff) = if kind == 0.0 {
            // A direction the light travels: the light is the other way.
            (-Vec3::new(x, y, z).normalize_or_zero(), 1.0)
        } else {
            let d = Vec3::new(x, y, z) - p;
            // Clamped at 1 cm so a light on the surface cannot blow up.
            let d2 = d.length_squared().max(1e-4);
            (d / d2.sqrt(), 1.0 / d2)
        };
        let radiance = Vec3::new(l.radiance[0], l.radiance[1], l.radiance[2]);
        let visible = light_visibility(shadow, i);
        let wrapped = ((Vec3::splat(n.dot(to_light)) + wrap) / (Vec3::ONE + wrap)).max(Vec3::ZERO);
        irradiance += radiance * wrapped * (falloff * visible);
    }
    let ambient = ambient * ambient_visibility(shadow);
    albedo * (irradiance * std::f32::consts::FRAC_1_PI + Vec3::splat(ambient))
}

/// Two words of an `Rgba16Float` texel.
fn pack(c: [f32; 4]) -> [u32; 2] {
    let h = c.map(|v| u32::from(f16::from_f32(v).to_bits()));
    [h[0] | h[1] << 16, h[2] | h[3] << 16]
}

struct OpaqueKernel {
    params: OpaqueParams,
}

impl OpaqueKernel {
    fn lights(ctx: &Ctx<'_>, view: &View<'_>) -> Vec<LightData> {
        let w: Words<'_> = ctx.words("lights");
        let stored = (w.len() / (std::mem::size_of::<LightData>() / 4)) as u64;
        let n = u64::from(view.frame.light_count)
            .min(ctx.quantities.lights)
            .min(stored);
        (0..n as usize).map(|i| read(&w, i)).collect()
    }

    /// Linear RGB of pixel (x, y), covered by triangle `t`; `None` when the
    /// triangle does not set up (a visibility word from another frame).
    fn shade_pixel(
        &self,
        view: &View<'_>,
        lights: &[LightData],
        t: u32,
        (x, y): (u32, u32),
        shadow: u32,
    ) -> Option<Vec3> {
        if t >= view.count {
            return None;
        }
        let tri = view.triangle(t);
        let setup = view.setup(&tri)?;
        let b = setup.barycentrics(setup.edges(x, y));
        let (p, n) = (corners(&tri), corner_normals(&tri));
        let face = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or(Vec3::Z);
        let default_albedo = Vec3::from(self.params.albedo);
        let albedo = tri
            .albedo
            .map(|w| unpack_albedo(w).map_or(default_albedo, Vec3::from));
        let lerp = |v: [Vec3; 3]| v[0] * b[0] + v[1] * b[1] + v[2] * b[2];
        Some(shade(
            lerp(p),
            lerp(n).normalize_or(face),
            lights,
            lerp(albedo),
            self.params.ambient,
            Vec3::from(self.params.wrap),
            shadow,
        ))
    }
}

impl CpuKernel for OpaqueKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let view = View::load(ctx);
        let lights = Self::lights(ctx, &view);
        let (vis, out) = (ctx.words("scene.visibility"), ctx.words("output"));
        let mask = ctx.words("skin_shadow");
        let background = Vec3::from(self.params.background);
        let pixels = view.width as usize * view.height as usize;
        let first = group as usize * PIXEL_GROUP as usize;
        let mut local = CounterValues::default();
        for i in first..(first + PIXEL_GROUP as usize).min(pixels) {
            let xy = (
                (i % view.width as usize) as u32,
                (i / view.width as usize) as u32,
            );
            let c = unpack(vis.load_u64(i))
                .and_then(|(t, _)| self.shade_pixel(&view, &lights, t, xy, mask.load(i)))
                .unwrap_or(background);
            // Alpha 0: no hair yet (`output`'s alpha is the hair's coverage).
            let [w0, w1] = pack([c.x, c.y, c.z, 0.0]);
            out.store(2 * i, w0);
            out.store(2 * i + 1, w1);
            local.pixels_written += 1;
        }
        if ctx.instrument {
            ctx.counters.add(&local);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{frame, harness, head, near_and_far, render as run_all, sun};
    use super::*;

    fn unpack(words: &[u32], i: usize) -> [f32; 4] {
        let h = |w: u32, s: u32| f16::from_bits((w >> s) as u16).to_f32();
        [
            h(words[2 * i], 0),
            h(words[2 * i], 16),
            h(words[2 * i + 1], 0),
            h(words[2 * i + 1], 16),
        ]
    }

    #[test]
    fn params_default_parse_and_reject() {
        assert_eq!(
            OPAQUE.params(&ron::Value::Unit).unwrap(),
            OpaqueParams::default()
        );
        let v: ron::Value =
            ron::from_str(r#"{"background": [0.1, 0.2, 0.3], "albedo": (1, 1, 1)}"#).unwrap();
        let p = OPAQUE.params(&v).unwrap();
        assert_eq!(p.background, [0.1, 0.2, 0.3]);
        assert_eq!(p.albedo, [1.0; 3]);
        for bad in [
            r#"{"albedo": [1, 2]}"#,
            r#"{"background": 0.5}"#,
            r#"{"albedo": [1, -1, 0]}"#,
            r#"{"hair_ao_steps": 2}"#,
        ] {
            let v: ron::Value = ron::from_str(bad).unwrap();
            let e = OPAQUE.params(&v).unwrap_err();
            assert!(e.to_string().contains("scene.opaque"), "{e}");
        }
    }

    #[test]
    fn uniform_block_carries_albedo_and_ambient() {
        let p = OpaqueParams::default();
        assert_eq!(
            p.uniform(4, 4).albedo_ambient,
            [p.albedo[0], p.albedo[1], p.albedo[2], p.ambient]
        );
        let wgsl = include_str!("../../../shaders/opaque_mesh/opaque.wgsl");
        assert!(
            wgsl.contains("albedo_ambient: vec4<f32>"),
            "WGSL block changed without the Rust side"
        );
    }

    #[test]
    fn nearer_triangle_is_shaded() {
        let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 40.0, 32, 32);
        let light = sun(Vec3::new(0.0, 0.0, -1.0), 3.0);
        // The near triangle faces the light; the far one's normals face away.
        let [near, far] = near_and_far(Vec3::X);
        let hs = harness(f, &[far, near], &[light]);
        run_all(&hs);
        assert_eq!(hs.out_of_bounds(), 0);
        let out = hs.read("output");
        let p = OpaqueParams::default();
        let lit = unpack(&out, 16 * 32 + 16);
        let expected = p.albedo[0] * (3.0 / std::f32::consts::PI + p.ambient);
        assert!((lit[0] - expected).abs() < 1e-2, "{lit:?} vs {expected}");
        // No hair yet: `output`'s alpha is the hair's coverage.
        assert_eq!(lit[3], 0.0);
        let corner = unpack(&out, 0);
        assert!((corner[2] - p.background[2]).abs() < 1e-3, "{corner:?}");
    }

    /// Visibility, depth and shading from 1 m in front of the origin, under a
    /// sun and a point light; returns depth, output and out-of-bounds accesses.
    fn render(tris: &[crate::layout::TriangleData], w: u32, h: u32) -> (Vec<u32>, Vec<u32>, u64) {
        let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 35.0, w, h);
        let lights = [sun(Vec3::new(0.3, -0.5, -1.0), 3.0), {
            let mut l = sun(Vec3::X, 2.0);
            l.position_or_direction = [-0.6, 0.2, 0.6, 1.0];
            l
        }];
        let hs = harness(f, tris, &lights);
        run_all(&hs);
        (
            hs.read("scene.depth"),
            hs.read("output"),
            hs.out_of_bounds(),
        )
    }

    #[test]
    fn procedural_head_covers_a_plausible_blob() {
        let (depth, out, oob) = render(&head(), 128, 128);
        assert_eq!(oob, 0);
        let bg = pack([0.02, 0.02, 0.025, 0.0]);
        let covered = (0..depth.len())
            .filter(|&i| [out[2 * i], out[2 * i + 1]] != bg)
            .count();
        let fraction = covered as f64 / depth.len() as f64;
        assert!(fraction > 0.05 && fraction < 0.8, "{fraction}");
        // Every pixel with depth got shaded (no cracks between depth and colour).
        let deep = depth.iter().filter(|&&d| d != 1.0f32.to_bits()).count();
        assert_eq!(covered, deep);
        // The face is lit: the centre is brighter than the ambient floor.
        let c = unpack(&out, 64 * 128 + 64);
        assert!(c[0] > 0.2 && c[3] == 0.0, "{c:?}");
    }

    #[test]
    fn shuffled_triangles_give_identical_bits() {
        let tris = head();
        let mut shuffled = tris.clone();
        // Fisher–Yates with a fixed xorshift: reproducible without a dependency.
        let mut s = 0x9e37_79b9u32;
        for i in (1..shuffled.len()).rev() {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            shuffled.swap(i, s as usize % (i + 1));
        }
        let a = render(&tris, 96, 80);
        let b = render(&shuffled, 96, 80);
        assert!(a.0 == b.0, "depth differs");
        assert!(a.1 == b.1, "colour differs");
    }

    #[test]
    fn procedural_head_at_1080p() {
        let (depth, _, oob) = render(&head(), 1920, 1080);
        assert_eq!(oob, 0);
        let covered = depth.iter().filter(|&&d| d != 1.0f32.to_bits()).count();
        assert!(covered > 100_000, "{covered} pixels");
    }
}
