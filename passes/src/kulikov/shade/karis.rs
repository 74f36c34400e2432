//! Marschner single scattering with Karis's real-time approximations, and
//! Karis's multiple-scattering fake.
//!
//! Kulikov, "Shading": "R, TT, TRT approximations based on [Karis16] and
//! [Tafuri19]". Tafuri 2019's TT/TRT forms are not reproduced here: all
//! three lobes follow Karis 2016, "Physically Based Hair Shading in Unreal"
//! (UE4 `HairShading`), and the multiple scattering is Karis's
//! `KajiyaKayDiffuseAttenuation`. `shaders/kulikov/shade.wgsl` ports these
//! functions operation for operation.

use glam::Vec3;
use std::f32::consts::PI;

/// Per-lobe artist scalars and material (Kulikov: "Non-PBR scalars for each path").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lobes {
    pub r: f32,
    pub tt: f32,
    pub trt: f32,
    /// Karis's "Scatter" (UE's hair Metallic slot); 0 turns multiple scattering off.
    pub scatter: f32,
    /// Cuticle tilt in radians (Karis: 0.035).
    pub shift: f32,
}

/// Karis 2016: the longitudinal Gaussian `M_p`.
fn hair_g(b: f32, theta: f32) -> f32 {
    (-0.5 * theta * theta / (b * b)).exp() / ((2.0 * PI).sqrt() * b)
}

/// Karis 2016: Schlick Fresnel for n = 1.55.
fn hair_f(cos_theta: f32) -> f32 {
    let f0 = ((1.0 - 1.55f32) / (1.0 + 1.55)).powi(2);
    f0 + (1.0 - f0) * (1.0 - cos_theta).powi(5)
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.3, 0.59, 0.11))
}

/// Fraction of a light's irradiance scattered towards the eye.
///
/// `t`: unit tangent pointing towards the root; `v`, `l`: unit directions to
/// the eye and to the light; `color`: the hair's base colour (absorption
/// tint); `shadow`: the light's visibility at this point (1 = unshadowed).
pub fn hair_shading(
    t: Vec3,
    v: Vec3,
    l: Vec3,
    color: Vec3,
    roughness: f32,
    shadow: f32,
    k: &Lobes,
) -> Vec3 {
    let rough = roughness.clamp(1.0 / 255.0, 1.0);
    let vol = v.dot(l);
    let sin_l = t.dot(l).clamp(-1.0, 1.0);
    let sin_v = t.dot(v).clamp(-1.0, 1.0);
    let cos_d = (0.5 * (sin_v.asin() - sin_l.asin()).abs()).cos();
    let lp = l - sin_l * t;
    let vp = v - sin_v * t;
    let cos_phi = lp.dot(vp) / (lp.dot(lp) * vp.dot(vp) + 1e-4).sqrt();
    let cos_half_phi = (0.5 + 0.5 * cos_phi).clamp(0.0, 1.0).sqrt();
    let n_prime = 1.19 / cos_d + 0.36 * cos_d;
    let alpha = [-k.shift * 2.0, k.shift, k.shift * 4.0];
    let r2 = rough * rough;
    let b = [r2, r2 / 2.0, r2 * 2.0];
    let mut s = Vec3::ZERO;

    // Karis 2016, R lobe.
    {
        let (sa, ca) = alpha[0].sin_cos();
        let shift = 2.0 * sa * (ca * cos_half_phi * (1.0 - sin_v * sin_v).sqrt() + sa * sin_v);
        let mp = hair_g(b[0] * 2f32.sqrt() * cos_half_phi, sin_l + sin_v - shift);
        let np = 0.25 * cos_half_phi;
        let fp = hair_f((0.5 + 0.5 * vol).clamp(0.0, 1.0).sqrt());
        s += Vec3::splat(k.r * mp * np * fp);
    }
    // Karis 2016, TT lobe.
    {
        let mp = hair_g(b[1], sin_l + sin_v - alpha[1]);
        let a = 1.0 / n_prime;
        let h = cos_half_phi * (1.0 + a * (0.6 - 0.8 * cos_phi));
        let f = hair_f(cos_d * (1.0 - h * h).clamp(0.0, 1.0).sqrt());
        let fp = (1.0 - f) * (1.0 - f);
        let tp = color.powf(0.5 * (1.0 - (h * a) * (h * a)).max(0.0).sqrt() / cos_d);
        let np = (-3.65 * cos_phi - 3.98).exp();
        s += tp * (k.tt * mp * np * fp);
    }
    // Karis 2016, TRT lobe.
    {
        let mp = hair_g(b[2], sin_l + sin_v - alpha[2]);
        let f = hair_f(cos_d * 0.5);
        let fp = (1.0 - f) * (1.0 - f) * f;
        let tp = color.powf(0.8 / cos_d);
        let np = (17.0 * cos_phi - 16.78).exp();
        s += tp * (k.trt * mp * np * fp);
    }
    s *= shadow;
    // Karis 2016, multiple scattering: KajiyaKayDiffuseAttenuation.
    if k.scatter > 0.0 {
        let kajiya = 1.0 - sin_l.abs();
        let fake_n = (v - t * sin_v).normalize_or(v);
        let nol = ((fake_n.dot(l) + 1.0) / 4.0).clamp(0.0, 1.0);
        let diffuse = (1.0 / PI) * (nol + (kajiya - nol) * 0.33) * k.scatter;
        let luma = luminance(color).max(1e-4);
        let tint = (color / luma).powf(1.0 - shadow);
        s += color.map(f32::sqrt) * diffuse * tint * shadow;
    }
    s.max(Vec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: Lobes = Lobes {
        r: 1.0,
        tt: 1.0,
        trt: 1.0,
        scatter: 1.0,
        shift: 0.035,
    };

    #[test]
    fn lobes_are_finite_and_switch_off() {
        let t = Vec3::Y;
        let color = Vec3::new(0.3, 0.2, 0.1);
        for (v, l) in [
            (Vec3::Z, Vec3::Z),
            (Vec3::Z, -Vec3::Z),
            (Vec3::Z, Vec3::Y),
            (
                Vec3::new(0.6, 0.0, 0.8),
                Vec3::new(-0.6, 0.3, 0.74).normalize(),
            ),
        ] {
            let s = hair_shading(t, v, l, color, 0.3, 1.0, &ALL);
            assert!(s.is_finite() && s.min_element() >= 0.0, "{s:?}");
        }
        let off = Lobes {
            r: 0.0,
            tt: 0.0,
            trt: 0.0,
            scatter: 0.0,
            ..ALL
        };
        assert_eq!(
            hair_shading(t, Vec3::Z, Vec3::Z, color, 0.3, 1.0, &off),
            Vec3::ZERO
        );
        // Backlit: TT dominates R; front lit: R dominates TT.
        let only = |r, tt| Lobes {
            r,
            tt,
            trt: 0.0,
            scatter: 0.0,
            ..ALL
        };
        let back = |k| hair_shading(t, Vec3::Z, -Vec3::Z, color * 3.0, 0.3, 1.0, &k).x;
        assert!(back(only(0.0, 1.0)) > back(only(1.0, 0.0)));
        let front = |k| hair_shading(t, Vec3::Z, Vec3::Z, color, 0.3, 1.0, &k).x;
        assert!(front(only(1.0, 0.0)) > front(only(0.0, 1.0)));
        // Shadowed light gives less.
        let lit = hair_shading(t, Vec3::Z, Vec3::X, color, 0.3, 1.0, &ALL);
        let dark = hair_shading(t, Vec3::Z, Vec3::X, color, 0.3, 0.2, &ALL);
        assert!(dark.x < lit.x);
    }
}
