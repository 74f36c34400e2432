//! Scheuermann 2004's hair shading ("Putting it All Together"), the CPU
//! mirror of `hair_lighting` in `shaders/scheuermann/hair.wgsl`: a
//! Kajiya-Kay strand model tuned to match Marschner's observations
//! phenomenologically.
//!
//! - diffuse: "a tweaked N·L term", `saturate(lerp(0.25, 1, N·L))`, which
//!   shifts the shadow boundary for a softer look (0.25 is
//!   [`Shading::diffuse_floor`]);
//! - two specular highlights from `StrandSpecular` (sin(T, H)^exponent with
//!   a smooth directional attenuation), each with its own tangent shifted
//!   along the normal by `ShiftTangent`: the primary "shifted towards hair
//!   tip" in the light's colour, the secondary "shifted towards hair root",
//!   "colored" (ours: the TRT tint times a strength, so dark
//!   hair keeps a dim secondary, as Marschner's TRT lobe) and masked by the
//!   sparkle texture ("Sparkling appearance of secondary highlight");
//! - `(diffuse + specular) · base texture · light colour`, times the baked
//!   ambient occlusion; alpha from the alpha texture.
//!
//! The paper's colours are an artist's; ours come from the groom's
//! material (the colour `models` carries), derived as the Kulikov
//! pipeline's hair shading (Karis's, `shaders/kulikov/shade.wgsl`) derives
//! its own, so every pipeline draws the same hair colour: the diffuse colour
//! is `sqrt(colour)` (Karis's Kajiya-Kay diffuse) and the secondary
//! highlight's is `colour^0.8` (his TRT lobe's tint at normal incidence).
//!
//! Two deviations, both of scale. The paper's colours were LDR and its
//! light colour at most 1; our scenes' lights are radiometric, calibrated
//! for renderers that divide Lambert's albedo by π, so the whole lit term
//! gets Lambert's 1/π, and the same light reads about as bright as in the
//! other pipelines. Where the paper adds the shift texture unscaled (`tex2D(tSpecShift) −
//! 0.5`, its texture authored for it), ours is generated in 0..1, so
//! [`Shading::shift_scale`] sets its amplitude.

use crate::layout::LightData;
use glam::{Vec3, Vec4};
use std::f32::consts::FRAC_1_PI;

/// The shading constants ("external constants are light blue" in the paper).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shading {
    /// Added to the tangent along the normal; negative moves the highlight
    /// towards the tip (tangents point root to tip).
    pub primary_shift: f32,
    pub secondary_shift: f32,
    /// Amplitude of the shift texture (centred on 0).
    pub shift_scale: f32,
    pub primary_exponent: f32,
    pub secondary_exponent: f32,
    /// Linear RGB of the primary highlight.
    pub primary: Vec3,
    /// The secondary highlight's colour is this times `colour^0.8`.
    pub secondary_strength: f32,
    /// The lerp's lower end: 0.25 in the paper.
    pub diffuse_floor: f32,
}

/// One fragment's interpolated surface.
#[derive(Debug, Clone, Copy)]
pub struct Surface {
    pub world: Vec3,
    pub tangent: Vec3,
    pub normal: Vec3,
    pub ao: f32,
}

/// Scheuermann: `ShiftTangent`.
pub fn shift_tangent(t: Vec3, n: Vec3, shift: f32) -> Vec3 {
    (t + shift * n).normalize_or_zero()
}

/// WGSL `smoothstep`.
fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Scheuermann: `StrandSpecular`, sin(T, H)^exponent attenuated smoothly
/// where T·H < 0.
pub fn strand_specular(t: Vec3, v: Vec3, l: Vec3, exponent: f32) -> f32 {
    let h = (l + v).normalize_or_zero();
    let dot_th = t.dot(h);
    let sin_th = (1.0 - dot_th * dot_th).max(0.0).sqrt();
    let dir_atten = smoothstep(-1.0, 0.0, dot_th);
    dir_atten * sin_th.max(1e-6).powf(exponent)
}

/// Scheuermann: `HairLighting`, summed over `lights`; straight (not
/// premultiplied) colour and alpha. `tex` is the sampled texture (base,
/// alpha, shift, sparkle), `colour` the groom's.
pub fn hair_lighting(
    s: &Shading,
    at: &Surface,
    tex: Vec4,
    colour: Vec3,
    camera: Vec3,
    lights: &[LightData],
) -> Vec4 {
    let base_colour = colour.max(Vec3::ZERO).map(f32::sqrt);
    let secondary = s.secondary_strength * colour.max(Vec3::ZERO).powf(0.8);
    let (t, n) = (
        at.tangent.normalize_or_zero(),
        at.normal.normalize_or_zero(),
    );
    let v = (camera - at.world).normalize_or_zero();
    let shift_tex = (tex.z - 0.5) * s.shift_scale;
    let t1 = shift_tangent(t, n, s.primary_shift + shift_tex);
    let t2 = shift_tangent(t, n, s.secondary_shift + shift_tex);
    let mut rgb = Vec3::ZERO;
    for light in lights {
        let pd = light.position_or_direction;
        let (mut l, mut atten) = ((-Vec3::new(pd[0], pd[1], pd[2])).normalize_or_zero(), 1.0);
        if pd[3] != 0.0 {
            let d = Vec3::new(pd[0], pd[1], pd[2]) - at.world;
            l = d.normalize_or_zero();
            atten = 1.0 / d.dot(d).max(1e-4);
        }
        let lerp = s.diffuse_floor * (1.0 - n.dot(l)) + n.dot(l);
        let diffuse = lerp.clamp(0.0, 1.0) * base_colour;
        let mut specular = s.primary * strand_specular(t1, v, l, s.primary_exponent);
        specular += secondary * tex.w * strand_specular(t2, v, l, s.secondary_exponent);
        let radiance = Vec3::new(light.radiance[0], light.radiance[1], light.radiance[2]);
        rgb += (diffuse + specular) * tex.x * radiance * (atten * FRAC_1_PI);
    }
    (rgb * at.ao).extend(tex.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The light elevation (radians, in the plane of T and N, seen from
    /// along N) where the highlight of a tangent shifted by `shift` peaks.
    fn peak(shift: f32) -> f32 {
        let (t, n) = (Vec3::Y, Vec3::Z);
        let shifted = shift_tangent(t, n, shift);
        (-1500..=1500)
            .map(|i| i as f32 * 1e-3)
            .max_by(|&a, &b| {
                let s = |th: f32| {
                    strand_specular(shifted, n, Vec3::new(0.0, th.sin(), th.cos()), 200.0)
                };
                s(a).total_cmp(&s(b))
            })
            .unwrap()
    }

    #[test]
    fn a_shift_along_the_normal_moves_the_highlight_by_twice_its_angle() {
        // H ⟂ T' where θ/2 = −atan(shift): a positive nudge needs light from
        // the root's side (−T), so the highlight moves towards the root.
        for shift in [-0.2f32, -0.05, 0.0, 0.1, 0.3] {
            let expect = -2.0 * shift.atan();
            assert!(
                (peak(shift) - expect).abs() < 2e-3,
                "{shift}: {}",
                peak(shift)
            );
        }
    }

    fn sun() -> LightData {
        LightData {
            position_or_direction: [0.0, 0.0, -1.0, 0.0],
            radiance: [2.0, 2.0, 2.0, 0.0],
            _pad: [0; 8],
        }
    }

    fn shading() -> Shading {
        Shading {
            primary_shift: -0.05,
            secondary_shift: 0.1,
            shift_scale: 0.0,
            primary_exponent: 80.0,
            secondary_exponent: 8.0,
            primary: Vec3::splat(0.3),
            secondary_strength: 0.5,
            diffuse_floor: 0.25,
        }
    }

    fn surface(ao: f32) -> Surface {
        Surface {
            world: Vec3::ZERO,
            tangent: Vec3::Y,
            normal: Vec3::Z,
            ao,
        }
    }

    #[test]
    fn the_secondary_highlight_is_masked_and_tinted() {
        let red = Vec3::new(0.4, 0.1, 0.05);
        let camera = Vec3::new(0.0, 0.0, 2.0);
        let lit = |sparkle: f32| {
            hair_lighting(
                &shading(),
                &surface(1.0),
                Vec4::new(1.0, 0.7, 0.5, sparkle),
                red,
                camera,
                &[sun()],
            )
        };
        let (dull, sparkling) = (lit(0.0), lit(1.0));
        let secondary = sparkling.truncate() - dull.truncate();
        assert!(secondary.min_element() > 0.0, "{secondary}");
        // The secondary term has the colour's TRT tint.
        let hue = secondary / secondary.x;
        let expect = red.powf(0.8) / red.x.powf(0.8);
        assert!((hue - expect).abs().max_element() < 1e-4, "{hue}");
        assert_eq!(dull.w, 0.7, "alpha is the alpha texture's");
    }

    #[test]
    fn ambient_occlusion_and_the_base_texture_scale_the_colour() {
        let c = Vec3::new(0.3, 0.2, 0.1);
        let camera = Vec3::new(0.0, 0.0, 2.0);
        let at = |ao: f32, base: f32| {
            hair_lighting(
                &shading(),
                &surface(ao),
                Vec4::new(base, 1.0, 0.5, 1.0),
                c,
                camera,
                &[sun()],
            )
        };
        let full = at(1.0, 1.0).truncate();
        assert!(((at(0.5, 1.0).truncate() - 0.5 * full).abs()).max_element() < 1e-6);
        assert!(((at(1.0, 0.25).truncate() - 0.25 * full).abs()).max_element() < 1e-6);
        // Diffuse only: lerp(0.25, 1, N·L) is 1 facing the light, 0.25 at
        // grazing light, and 0 once N·L ≤ −1/3.
        let diffuse = Shading {
            primary: Vec3::ZERO,
            secondary_strength: 0.0,
            ..shading()
        };
        let from = |d: [f32; 3]| {
            let light = LightData {
                position_or_direction: [d[0], d[1], d[2], 0.0],
                ..sun()
            };
            hair_lighting(&diffuse, &surface(1.0), Vec4::ONE, c, camera, &[light]).truncate()
        };
        let lambert = 2.0 * FRAC_1_PI * c.map(f32::sqrt);
        assert!((from([0.0, 0.0, -1.0]) - lambert).abs().max_element() < 1e-6);
        assert!(
            (from([0.0, -1.0, 0.0]) - 0.25 * lambert)
                .abs()
                .max_element()
                < 1e-6
        );
        assert_eq!(from([0.0, 0.6, 0.8]), Vec3::ZERO);
    }
}
