//! Chiang et al. 2016 single scattering (R, TT, TRT) in the compact form
//! `lipp.shade` evaluates per pixel (Lipp §3.4: "a physics-based hair shading
//! model similar to the one proposed by Pekelis et al. [2015], but fitted to
//! Chiang's model instead of Marschner's"). Ported to
//! `shaders/lipp/chiang.wgsl`.

use super::{dot, normalize, scale, sub};

const PI: f32 = std::f32::consts::PI;

/// Material inputs of one pixel.
#[derive(Debug, Clone, Copy)]
pub struct Material {
    pub color: [f32; 3],
    pub roughness: f32,
}

/// Chiang 2016 Eq. 9 inverted: absorption from a desired colour.
pub fn sigma_a(color: [f32; 3], beta_n: f32) -> [f32; 3] {
    let b = beta_n;
    let d = 5.969 - 0.215 * b + 2.532 * b * b - 10.73 * b.powi(3)
        + 5.574 * b.powi(4)
        + 0.245 * b.powi(5);
    color.map(|c| {
        let l = c.clamp(1e-4, 1.0).ln() / d;
        l * l
    })
}

fn logistic(x: f32, s: f32) -> f32 {
    let e = (-x.abs() / s).exp();
    e / (s * (1.0 + e) * (1.0 + e))
}

fn logistic_cdf(x: f32, s: f32) -> f32 {
    1.0 / (1.0 + (-x / s).exp())
}

/// Chiang's trimmed logistic on [−π, π].
fn trimmed_logistic(x: f32, s: f32) -> f32 {
    logistic(x, s) / (logistic_cdf(PI, s) - logistic_cdf(-PI, s))
}

/// Wraps an angle to [−π, π].
fn wrap(mut phi: f32) -> f32 {
    while phi > PI {
        phi -= 2.0 * PI;
    }
    while phi < -PI {
        phi += 2.0 * PI;
    }
    phi
}

/// The R + TT + TRT single-scattering BSDF times cos θ_i (compact Chiang 2016).
pub fn chiang(t: [f32; 3], l: [f32; 3], v: [f32; 3], m: &Material) -> [f32; 3] {
    let (sin_i, sin_o) = (dot(t, l).clamp(-1.0, 1.0), dot(t, v).clamp(-1.0, 1.0));
    let cos_i = (1.0 - sin_i * sin_i).max(0.0).sqrt();
    let cos_o = (1.0 - sin_o * sin_o).max(0.0).sqrt();
    let lp = normalize(sub(l, scale(t, sin_i)));
    let vp = normalize(sub(v, scale(t, sin_o)));
    let phi = dot(lp, vp).clamp(-1.0, 1.0).acos();
    let bm = m.roughness.clamp(0.02, 1.0);
    let v0 = {
        let x = 0.726 * bm + 0.812 * bm * bm + 3.7 * bm.powi(20);
        x * x
    };
    let s = 0.626_657 * (0.265 * bm + 1.194 * bm * bm + 5.372 * bm.powi(22));
    let alpha = 2.0f32.to_radians();
    let eta = 1.55;
    let f0 = ((eta - 1.0) / (eta + 1.0)) * ((eta - 1.0) / (eta + 1.0));
    let f = f0 + (1.0 - f0) * (1.0 - cos_o).powi(5);
    let sin_t = sin_o / eta;
    let cos_t = (1.0 - sin_t * sin_t).max(1e-4).sqrt();
    let sa = sigma_a(m.color, bm);
    let tr = sa.map(|a| (-2.0 * a / cos_t).exp());
    let mut out = [0.0f32; 3];
    let lobes = [
        (v0, -2.0 * alpha),
        (0.25 * v0, alpha),
        (4.0 * v0, 4.0 * alpha),
    ];
    for (p, (var, shift)) in lobes.iter().enumerate() {
        let x = sin_i + sin_o - shift;
        let mp = (-x * x / (2.0 * var)).exp() / (2.0 * PI * var).sqrt();
        let np = trimmed_logistic(wrap(phi - p as f32 * PI), s);
        let a = match p {
            0 => [f; 3],
            1 => tr.map(|t| (1.0 - f) * (1.0 - f) * t),
            _ => tr.map(|t| (1.0 - f) * (1.0 - f) * t * t * f),
        };
        for k in 0..3 {
            out[k] += mp * a[k] * np;
        }
    }
    scale(out, cos_i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chiang_lobes_are_finite_and_r_peaks_at_the_specular_cone() {
        let m = Material {
            color: [0.3, 0.2, 0.1],
            roughness: 0.3,
        };
        let t = [0.0, 1.0, 0.0];
        let v = normalize([0.0, 0.0, 1.0]);
        // Light on the mirror cone (sin θ_i = −sin θ_o) vs far off it.
        let on = chiang(t, normalize([0.0, -0.05, 1.0]), v, &m);
        let off = chiang(t, normalize([0.0, 0.9, 0.3]), v, &m);
        assert!(on.iter().chain(&off).all(|x| x.is_finite() && *x >= 0.0));
        assert!(on[0] > off[0] * 2.0, "{on:?} vs {off:?}");
        let sa = sigma_a([0.3, 0.2, 0.1], 0.3);
        assert!(sa[0] < sa[1] && sa[1] < sa[2], "{sa:?}");
    }
}
