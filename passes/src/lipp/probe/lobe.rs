//! The GGX lobe that stands in for R + TRT when the probe is read (Lipp
//! §3.4), and the probe's specular term.

use super::lookup::sample;
use crate::kernel::Words;
use crate::lipp::chiang::{FibrePaths, Material};
use crate::lipp::{dot, normalize, scale, sub};

/// The GGX lobe standing in for R + TRT (Lipp §3.4: "we approximate the R
/// and TRT lobes with a single GGX lobe, which we use for querying the
/// pre-filtered probe"): where to look and how rough, and the weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpecularLobe {
    /// Lookup direction (unit).
    pub direction: [f32; 3],
    /// GGX α.
    pub alpha: f32,
    /// A_R + A_TRT per channel.
    pub weight: [f32; 3],
}

/// The R + TRT stand-in lobe for a fibre of tangent `t` seen from `v` (both
/// unit), with `n` the view-facing fibre normal, colour `color` and
/// longitudinal roughness `roughness` (β_m), in the terms of
/// [`super::chiang::chiang`], whose view `paths` it reads:
///
/// - **Weight**: R's and TRT's directional albedo at θ_o, pbrt-v4's A_p
///   averaged over the fibre offset h ([`FibrePaths::r_albedo`] and
///   [`FibrePaths::trt_albedo`]).
///   The hair lobes are normalised in M_p and N_p, so under uniform radiance
///   their sum returns A_R + A_TRT of it, and so does this term.
/// - **Direction**: the longitudinal mirror of V across the fibre's normal
///   plane (sin θ_i = −sin θ_o, the specular cone), on the side of the
///   view-facing normal (azimuth φ = 0, where R and TRT both reflect back
///   towards the viewer), shifted along the fibre by the cuticle tilt:
///   Chiang's M_p peaks where sin θ_i + sin θ_o equals the lobe's shift
///   (+2α for R, −4α for TRT with the tangent root to tip, α = 2° as in
///   `chiang`).
/// - **Width**: the two longitudinal Gaussians (variances v_0 and 4 v_0,
///   Chiang Eq. 7) moment-matched into one, weighted by A_R and mean A_TRT:
///   shift μ = Σ w_p s_p / Σ w_p and σ² = Σ w_p (v_p + s_p²) / Σ w_p − μ².
///   A Beckmann lobe of roughness m spreads the reflected direction by a
///   variance of 2 m² per axis (θ_h has m² / 2), and GGX α ≈ Beckmann m
///   (Walter et al. 2007), so α = √(σ² / 2). The GGX lobe is isotropic: the
///   azimuthal spread of R and TRT across the fibre's width (N_p) is not
///   represented — the price of Lipp's single lobe.
pub fn specular_lobe(
    t: [f32; 3],
    v: [f32; 3],
    n: [f32; 3],
    m: &Material,
    paths: &FibrePaths,
) -> SpecularLobe {
    let sin_o = dot(t, v).clamp(-1.0, 1.0);
    let bm = m.roughness.clamp(0.02, 1.0);
    let v0 = {
        let x = 0.726 * bm + 0.812 * bm * bm + 3.7 * bm.powi(20);
        x * x
    };
    let alpha = m.alpha;
    let (w_r, a_trt) = (paths.r_albedo, paths.trt_albedo);
    let w_trt = (a_trt[0] + a_trt[1] + a_trt[2]) / 3.0;
    // Where M_p peaks in sin θ_i + sin θ_o (tangent root to tip, as in
    // `chiang`): R at +2α, TRT at −4α.
    let (s_r, s_trt) = (2.0 * alpha, -4.0 * alpha);
    let sum = w_r + w_trt;
    let mu = (w_r * s_r + w_trt * s_trt) / sum;
    let second = (w_r * (v0 + s_r * s_r) + w_trt * (4.0 * v0 + s_trt * s_trt)) / sum;
    let var = (second - mu * mu).max(0.0);
    let sin_l = (mu - sin_o).clamp(-1.0, 1.0);
    let cos_l = (1.0 - sin_l * sin_l).max(0.0).sqrt();
    let direction = normalize([
        t[0] * sin_l + n[0] * cos_l,
        t[1] * sin_l + n[1] * cos_l,
        t[2] * sin_l + n[2] * cos_l,
    ]);
    SpecularLobe {
        direction,
        alpha: (0.5 * var).sqrt().min(1.0),
        weight: a_trt.map(|a| a + w_r),
    }
}

/// The view-facing fibre normal (Lipp §3.4: "centered at a normal of the
/// fiber oriented towards the view direction"): V without its component
/// along T, or V itself when looking along the fibre.
pub fn view_facing_normal(t: [f32; 3], v: [f32; 3]) -> [f32; 3] {
    let n = normalize(sub(v, scale(t, dot(t, v))));
    if dot(n, n) > 0.0 { n } else { v }
}

/// Radiance of the R + TRT probe term (before AO and the `specular` scale).
pub fn specular(
    w: &Words<'_>,
    t: [f32; 3],
    v: [f32; 3],
    n: [f32; 3],
    m: &Material,
    paths: &FibrePaths,
) -> [f32; 3] {
    let lobe = specular_lobe(t, v, n, m, paths);
    let l = sample(w, lobe.direction, lobe.alpha);
    std::array::from_fn(|k| l[k] * lobe.weight[k])
}

#[cfg(test)]
mod tests {
    use super::super::{atomics, constant_levels, words};
    use super::*;
    use std::sync::atomic::AtomicU64;

    fn mat(color: [f32; 3], roughness: f32) -> Material {
        Material {
            color,
            roughness,
            alpha: crate::lipp::chiang::DEFAULT_ALPHA,
        }
    }

    /// The lobe with the view's own fibre paths.
    fn lobe_of(t: [f32; 3], v: [f32; 3], n: [f32; 3], m: &Material) -> SpecularLobe {
        specular_lobe(t, v, n, m, &FibrePaths::new(dot(t, v), m))
    }

    #[test]
    fn the_stand_in_lobe_mirrors_the_view_and_widens_with_roughness() {
        let t = [0.0, 1.0, 0.0];
        let v = normalize([0.0, 0.3, 1.0]);
        let n = view_facing_normal(t, v);
        assert!((dot(n, [0.0, 0.0, 1.0]) - 1.0).abs() < 1e-6);
        let dark = [0.02, 0.015, 0.01];
        let lobe = lobe_of(t, v, n, &mat(dark, 0.3));
        // The lobe sits on the specular cone (sin θ_l = −sin θ_o) shifted by
        // the A-weighted mean of R's +2α and TRT's −4α; dark hair: nearly R's.
        let sin_o = dot(t, v);
        let shift = dot(lobe.direction, t) + sin_o;
        let paths = FibrePaths::new(sin_o, &mat(dark, 0.3));
        let (f, trt) = (paths.r_albedo, paths.trt_albedo);
        let a_trt = trt.iter().sum::<f32>() / 3.0;
        assert!((lobe.weight.iter().sum::<f32>() / 3.0 - (f + a_trt)).abs() < 1e-6);
        let alpha_c = 2f32.to_radians();
        let mu = (f * 2.0 * alpha_c + a_trt * -4.0 * alpha_c) / (f + a_trt);
        assert!((shift - mu).abs() < 1e-3, "shift {shift} rad, μ {mu}");
        assert!(a_trt < 0.15 * f && shift > alpha_c, "{lobe:?}");
        // R averaged over the fibre's width reflects more than at its centre
        // (Fresnel grows towards grazing offsets): above normal incidence's 4.65%.
        assert!(f > 0.0465, "{f}");
        assert!(dot(lobe.direction, n) > 0.9);
        // Between R's α = √(v0 / 2) and TRT's √(4 v0 / 2), near R's.
        let bm: f32 = 0.3;
        let v0 = (0.726 * bm + 0.812 * bm * bm).powi(2);
        let (a_r, a_t) = ((v0 / 2.0).sqrt(), (2.0 * v0).sqrt());
        assert!(
            lobe.alpha > a_r && lobe.alpha < 0.5 * (a_r + a_t),
            "{lobe:?}"
        );
        assert!(
            lobe.weight.iter().all(|&w| (0.04..0.1).contains(&w)),
            "{lobe:?}"
        );
        // Blond hair: TRT adds weight (more in red), shifts the lobe towards −4α, widens it.
        let blond = lobe_of(t, v, n, &mat([0.8, 0.6, 0.35], 0.3));
        assert!(blond.weight[0] > blond.weight[2] && blond.weight[2] > lobe.weight[2]);
        assert!(dot(blond.direction, t) < dot(lobe.direction, t));
        assert!(blond.alpha > lobe.alpha);
        // Rougher hair, wider lobe; capped at α = 1.
        let rough = lobe_of(t, v, n, &mat(dark, 0.6));
        assert!(rough.alpha > lobe.alpha && lobe_of(t, v, n, &mat(dark, 1.0)).alpha <= 1.0);
    }

    #[test]
    fn uniform_radiance_returns_the_attenuations() {
        let c = [0.3, 0.4, 0.5];
        let (a, oob) = (atomics(&words(&constant_levels(c))), AtomicU64::new(0));
        let w = Words::new(&a, &oob);
        let (t, v) = ([1.0, 0.0, 0.0], normalize([0.5, 0.2, 1.0]));
        let n = view_facing_normal(t, v);
        let m = mat([0.5, 0.4, 0.3], 0.35);
        let paths = FibrePaths::new(dot(t, v), &m);
        let lobe = specular_lobe(t, v, n, &m, &paths);
        let s = specular(&w, t, v, n, &m, &paths);
        for k in 0..3 {
            assert!((s[k] - c[k] * lobe.weight[k]).abs() < 1e-6, "{s:?}");
        }
    }
}
