//! Chiang et al. 2016 single scattering (R, TT, TRT) in the compact form
//! `lipp.shade` evaluates per pixel (Lipp §3.4: "a physics-based hair shading
//! model similar to the one proposed by Pekelis et al. [2015], but fitted to
//! Chiang's model instead of Marschner's"). Ported to
//! `shaders/lipp/chiang.wgsl`.
//!
//! The target is pbrt-v4's `HairBxDF` (Chiang 2016 as pbrt implements it,
//! η = 1.55, α = 2°, β_m = β_n = roughness, σ_a from the colour by Chiang
//! Eq. 9 inverted), averaged over the fibre offset h ∈ [−1, 1]: a deferred
//! G-buffer pixel covers the whole (sub-pixel) fibre width and has no h.
//! [`chiang`] returns pbrt's f · |cos| (pbrt divides its sum by the shading
//! cosine and the integrator multiplies it back), Σ_p M_p A_p N_p, which
//! multiplies the light's radiance (irradiance, for a directional light);
//! no cos θ_i, or a white fibre in a white furnace would come out dark.
//!
//! - M_p: pbrt's (d'Eon et al. 2011, Chiang Eq. 6), with Chiang's variances
//!   v_0 = (0.726 β + 0.812 β² + 3.7 β^20)², v_1 = v_0 / 4, v_2 = 4 v_0
//!   (Eq. 7) and pbrt's cuticle tilt of θ_o (−2α, +α, +4α: with the tangent
//!   root to tip, R peaks near sin θ_i + sin θ_o = +2α and TRT near −4α),
//!   evaluated in log form with Abramowitz and Stegun's I0. M_p does not
//!   depend on h, so it is exact.
//! - R: d'Eon 2011's far-field N_R A_R of a smooth cylinder, ¼ cos(φ/2) ·
//!   F(cos θ_o cos(φ/2)) with the exact dielectric Fresnel (pbrt-v4
//!   `FrDielectric`), i.e. ½∫ A_R(h) N_R(φ; h) dh for a vanishing logistic,
//!   convolved with Chiang's logistic (s from Eq. 8) by a 3-point rule that
//!   matches its variance and fourth moment.
//! - TT, TRT: ½∫ A_p(h) N_p(φ; h) dh (pbrt-v4 `HairBxDF::Ap`, `Np`, `Phi`)
//!   with A_p and Φ_p(h) = 2pγ_t − 2γ_o + pπ evaluated at five offsets
//!   (γ_o = (π/2)(j/4)^0.8) and Φ_p linear in between: each of the 4 pieces
//!   per side is a box in φ convolved with the logistic, a difference of two
//!   logistic CDFs, so TT's spread and TRT's caustic come out of the
//!   geometry rather than a fitted width; A_p (exact Fresnel, T = exp(−2 σ_a
//!   cos γ_t / cos θ_t)) is integrated over each piece as linear in γ.
//!   pbrt's residual p ≥ 3 term (A_3 / 2π) is left out, as in Lipp (the
//!   Kajiya-Kay-like term of `lipp.shade` stands for multiple scattering).
//!
//! Cost per view ([`FibrePaths`]): 5 asin, 5 Fresnel and 15 exp for the RGB
//! transmittances; per light: 1 acos, 3 cos, 3 M_p (2 exp and up to 4 log
//! each), 3 Fresnel and 22 logistic exp.
//!
//! The check (`check` below, reference in `chiang_reference.rs`): 3 colours
//! (blonde, brown, black) × β ∈ {0.2, 0.3, 0.5} × θ_o ∈ {−44°, −21°, 0°,
//! 21°, 44°, 64°}, over the sphere of light directions (400 × 180 cells),
//! reference averaged over 1024 offsets. Worst cases over the 54 views:
//!
//! | | R | TT | TRT | R+TT+TRT |
//! |---|---|---|---|---|
//! | directional albedo error, before | −87% | −47% … +5% | −78% | −63% |
//! | directional albedo error, now | 1.3% | 1.5% | 0.9% | 1.0% |
//! | relative L1 over the sphere, before | 1.42 | 1.38 | 1.07 | 1.34 |
//! | relative L1 over the sphere, now | 0.061 | 0.074 | 0.060 | 0.054 |
//!
//! Longitudinal peaks of R and TRT (β ≤ 0.3) now agree within 0.1°; before,
//! every cuticle shift had the wrong sign (θ_o = 0, β = 0.2: R at −3.9°
//! against pbrt's +3.9°, TRT at +7° against −7.5°). What the old form (Karis
//! 2016's Gaussian M_p, N_p and A_p at h = 0, Schlick, × cos θ_i) got wrong,
//! besides the signs: N_p at h = 0 is a logistic of width s around pπ, where
//! R really spreads over every azimuth (¼ cos(φ/2)), TT over ±100° and TRT
//! over ±20° with a caustic; A_R at h = 0 is Fresnel at normal incidence
//! (with the extra cos θ_i, R's albedo was 1.6 to 7 times too low); the extra
//! cos θ_i lost energy at grazing light (half at 60°); and the Gaussian in
//! sin θ lost 38% of TRT's M_p at β = 0.5 outside sin θ_i ∈ [−1, 1]. The
//! shifts of Karis's form are for a tangent pointing to the root (Unreal's
//! convention); ours points to the tip (`strand::calc_tangent`), as pbrt's
//! ∂p/∂u does.
//!
//! The model is split by factor: `longitudinal` holds M_p and the cuticle
//! tilts, `attenuation` the fibre offsets h with their Fresnel and
//! transmittance (A_p), computed once per view ([`FibrePaths`], with the
//! directional albedo the probe term uses) for every light; the lobes (N_p
//! and the sum) are here. `check` compares the whole against
//! `chiang_reference`.

mod attenuation;
#[cfg(test)]
mod check;
mod longitudinal;

use super::{dot, normalize, scale, sub};
use attenuation::{NODES, PIECES, fresnel};
use longitudinal::{mp, tilt};

pub use attenuation::{FibrePaths, R_ALBEDO_FIT};

const PI: f32 = std::f32::consts::PI;

/// Material inputs of one pixel.
#[derive(Debug, Clone, Copy)]
pub struct Material {
    pub color: [f32; 3],
    pub roughness: f32,
    /// Cuticle scale tilt α, radians (the scene material's `highlight_shift_deg`).
    pub alpha: f32,
}

/// pbrt-v4's and Chiang 2016's default scale tilt, 2°.
pub const DEFAULT_ALPHA: f32 = 2.0 * std::f32::consts::PI / 180.0;

/// Chiang 2016 Eq. 9 inverted: absorption from a desired colour (the scene
/// material's colour came from absorption through the same equation).
pub use strandgraph_assets::hair_color::sigma_a_from_color as sigma_a;

fn logistic(x: f32, s: f32) -> f32 {
    let e = (-x.abs() / s).exp();
    e / (s * (1.0 + e) * (1.0 + e))
}

fn logistic_cdf(x: f32, s: f32) -> f32 {
    1.0 / (1.0 + (-x / s).exp())
}

/// R + TT + TRT: pbrt-v4's `HairBxDF::f` · |cos| averaged over the fibre
/// offset h, for fibre tangent `t`, unit direction to the light `l` and to
/// the viewer `v` (see the module doc); `paths` are the view's,
/// `FibrePaths::new(t · v, m)`.
pub fn chiang(t: [f32; 3], l: [f32; 3], v: [f32; 3], m: &Material, paths: &FibrePaths) -> [f32; 3] {
    let [r, tt, trt] = chiang_lobes(t, l, v, m, paths);
    std::array::from_fn(|k| r[k] + tt[k] + trt[k])
}

/// [`chiang`] per lobe: R, TT, TRT.
pub fn chiang_lobes(
    t: [f32; 3],
    l: [f32; 3],
    v: [f32; 3],
    m: &Material,
    paths: &FibrePaths,
) -> [[f32; 3]; 3] {
    let (sin_i, sin_o) = (dot(t, l).clamp(-1.0, 1.0), dot(t, v).clamp(-1.0, 1.0));
    let cos_i = (1.0 - sin_i * sin_i).max(0.0).sqrt();
    let cos_o = (1.0 - sin_o * sin_o).max(0.0).sqrt();
    let lp = normalize(sub(l, scale(t, sin_i)));
    let vp = normalize(sub(v, scale(t, sin_o)));
    let cos_phi = dot(lp, vp).clamp(-1.0, 1.0);
    let phi = cos_phi.acos();
    let b = m.roughness.clamp(0.02, 1.0);
    let v0 = {
        let x = 0.726 * b + 0.812 * b * b + 3.7 * b.powi(20);
        x * x
    };
    let s = 0.626_657 * (0.265 * b + 1.194 * b * b + 5.372 * b.powi(22));
    // M_p with the cuticle tilt.
    let tilts = tilt(m.alpha);
    let mps: [f32; 3] = std::array::from_fn(|p| {
        let (sin_k, cos_k, var) = tilts[p];
        let var = var * v0;
        let sin_p = sin_o * cos_k + cos_o * sin_k;
        let cos_p = (cos_o * cos_k - sin_o * sin_k).abs();
        mp(cos_i, cos_p, sin_i, sin_p, var)
    });
    // R: d'Eon 2011's far-field N_R of a smooth cylinder, ¼ cos(φ/2) times
    // Fresnel at the offset that reflects into φ, convolved with the logistic
    // by a 3-point rule matching its variance and fourth moment.
    let a = 3.717 * s;
    let r =
        (0.7619 * n_r(phi, cos_o) + 0.1190 * (n_r(phi - a, cos_o) + n_r(phi + a, cos_o))) * mps[0];
    // TT, TRT: ½∫ A_p(h) N_p(φ; h) dh with A_p and Φ_p(h) evaluated at the
    // offsets of H_NODES (`paths`) and Φ_p linear in between: each piece is
    // a box in φ convolved with the logistic, a difference of two logistic
    // CDFs.
    let (ap, dphi) = (&paths.ap, &paths.dphi);
    // Deviation from each lobe's centre: TT at π, TRT at 2π.
    let x = [phi - PI, phi];
    let trim = 1.0 / (logistic_cdf(PI, s) - logistic_cdf(-PI, s));
    let mut out = [[r; 3], [0.0; 3], [0.0; 3]];
    for p in 0..2 {
        // h > 0 and its mirror h < 0 (Φ_p(−h) = −Φ_p(h)).
        for side in [1.0f32, -1.0] {
            let xs = side * x[p];
            let mut cdf = logistic_cdf(xs - dphi[0][p], s);
            for j in 0..NODES - 1 {
                let next = logistic_cdf(xs - dphi[j + 1][p], s);
                let width = dphi[j + 1][p] - dphi[j][p];
                let n = if width.abs() < 1e-3 * s {
                    logistic(xs - 0.5 * (dphi[j][p] + dphi[j + 1][p]), s)
                } else {
                    (cdf - next) / width
                };
                cdf = next;
                let (wa, wb) = PIECES[j];
                for k in 0..3 {
                    out[p + 1][k] += 0.5 * n * (wa * ap[j][p][k] + wb * ap[j + 1][p][k]);
                }
            }
        }
        let m = mps[p + 1] * trim;
        out[p + 1] = out[p + 1].map(|o| o * m);
    }
    out
}

/// d'Eon 2011's far-field N_R times A_R (s → 0): ¼ |cos(φ/2)| ·
/// F(cos θ_o |cos(φ/2)|), the reflection at offset h = sin(−φ/2).
fn n_r(phi: f32, cos_o: f32) -> f32 {
    let c = (0.5 * phi).cos().abs();
    0.25 * c * fresnel(cos_o * c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chiang_lobes_are_finite_and_r_peaks_at_the_specular_cone() {
        let m = Material {
            color: [0.3, 0.2, 0.1],
            roughness: 0.3,
            alpha: DEFAULT_ALPHA,
        };
        let t = [0.0, 1.0, 0.0];
        let v = normalize([0.0, 0.0, 1.0]);
        // Light on the mirror cone (sin θ_i = −sin θ_o) vs far off it.
        let paths = FibrePaths::new(dot(t, v), &m);
        let on = chiang(t, normalize([0.0, -0.05, 1.0]), v, &m, &paths);
        let off = chiang(t, normalize([0.0, 0.9, 0.3]), v, &m, &paths);
        assert!(on.iter().chain(&off).all(|x| x.is_finite() && *x >= 0.0));
        assert!(on[0] > off[0] * 2.0, "{on:?} vs {off:?}");
        let sa = sigma_a([0.3, 0.2, 0.1], 0.3);
        assert!(sa[0] < sa[1] && sa[1] < sa[2], "{sa:?}");
    }
}
