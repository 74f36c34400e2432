//! Test-only reference: pbrt-v4's `HairBxDF` (Chiang et al. 2016 as pbrt-v4
//! implements it), in f64, transcribed from `src/pbrt/bxdfs.h` (`HairBxDF`,
//! `Mp`, `Ap`, `Phi`, `Np`), `src/pbrt/bxdfs.cpp` (`HairBxDF::HairBxDF`,
//! `HairBxDF::f`, `HairBxDF::SigmaAFromReflectance`), `src/pbrt/util/math.h`
//! (`I0`, `LogI0`, `Logistic`, `LogisticCDF`, `TrimmedLogistic`) and
//! `src/pbrt/util/scattering.h` (`FrDielectric`).
//!
//! Deliberate differences from pbrt's code, none of which changes the model:
//! f64 throughout; `std::exp` where pbrt calls `FastExp` (a polynomial
//! approximation of exp); RGB instead of sampled spectra. pbrt's series
//! truncations are kept (`I0` sums 10 terms, which is up to 2% low at the
//! argument 12 where `LogI0` switches to the asymptotic form), so the
//! reference is pbrt's numbers, not Chiang's exact integrals.
//!
//! [`average_over_h`] is what a deferred G-buffer pixel needs: the fibre is
//! narrower than a pixel and the pixel has no offset h, so it sees pbrt's f
//! averaged over h ∈ [−1, 1] (uniform in h, as the fibre's projected width
//! is). [`Azimuthal`] is the same average, factored: in pbrt's f only A_p
//! and N_p depend on h, and neither depends on θ_i, so
//! f̄ · |cos| = Σ_p M_p(θ_i, θ_o) · ½∫ A_p(h) N_p(φ; h) dh.

use std::f64::consts::PI;

pub const P_MAX: usize = 3;

/// Per lobe p = 0 (R), 1 (TT), 2 (TRT), 3 (pbrt's residual p ≥ 3), RGB.
pub type Lobes = [[f64; 3]; P_MAX + 1];

fn sqr(x: f64) -> f64 {
    x * x
}

/// pbrt-v4 `SafeSqrt`.
fn safe_sqrt(x: f64) -> f64 {
    x.max(0.0).sqrt()
}

/// pbrt-v4 `SafeASin`.
fn safe_asin(x: f64) -> f64 {
    x.clamp(-1.0, 1.0).asin()
}

/// pbrt-v4 util/math.h `I0`: I0(x) ≈ Σ_{i<10} x^(2i) / (4^i (i!)²).
pub fn i0(x: f64) -> f64 {
    let mut val = 0.0;
    let mut x2i = 1.0;
    let mut ifact: i64 = 1;
    let mut i4: i64 = 1;
    for i in 0..10 {
        if i > 1 {
            ifact *= i;
        }
        val += x2i / (i4 * ifact * ifact) as f64;
        x2i *= x * x;
        i4 *= 4;
    }
    val
}

/// pbrt-v4 util/math.h `LogI0`.
pub fn log_i0(x: f64) -> f64 {
    if x > 12.0 {
        x + 0.5 * (-(2.0 * PI).ln() + (1.0 / x).ln() + 1.0 / (8.0 * x))
    } else {
        i0(x).ln()
    }
}

/// pbrt-v4 util/math.h `Logistic`.
pub fn logistic(x: f64, s: f64) -> f64 {
    let x = x.abs();
    (-x / s).exp() / (s * sqr(1.0 + (-x / s).exp()))
}

/// pbrt-v4 util/math.h `LogisticCDF`.
pub fn logistic_cdf(x: f64, s: f64) -> f64 {
    1.0 / (1.0 + (-x / s).exp())
}

/// pbrt-v4 util/math.h `TrimmedLogistic`.
pub fn trimmed_logistic(x: f64, s: f64, a: f64, b: f64) -> f64 {
    logistic(x, s) / (logistic_cdf(b, s) - logistic_cdf(a, s))
}

/// pbrt-v4 util/scattering.h `FrDielectric`.
pub fn fr_dielectric(cos_theta_i: f64, eta: f64) -> f64 {
    let mut cos_theta_i = cos_theta_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_theta_i < 0.0 {
        eta = 1.0 / eta;
        cos_theta_i = -cos_theta_i;
    }
    let sin2_theta_i = 1.0 - sqr(cos_theta_i);
    let sin2_theta_t = sin2_theta_i / sqr(eta);
    if sin2_theta_t >= 1.0 {
        return 1.0;
    }
    let cos_theta_t = safe_sqrt(1.0 - sin2_theta_t);
    let r_parl = (eta * cos_theta_i - cos_theta_t) / (eta * cos_theta_i + cos_theta_t);
    let r_perp = (cos_theta_i - eta * cos_theta_t) / (cos_theta_i + eta * cos_theta_t);
    (sqr(r_parl) + sqr(r_perp)) / 2.0
}

/// pbrt-v4 `HairBxDF::Mp` (d'Eon et al. 2011's longitudinal function).
#[allow(
    clippy::approx_constant,
    reason = "pbrt's literal 0.6931 for ln 2, transcribed as is"
)]
pub fn mp(cos_theta_i: f64, cos_theta_o: f64, sin_theta_i: f64, sin_theta_o: f64, v: f64) -> f64 {
    let a = cos_theta_i * cos_theta_o / v;
    let b = sin_theta_i * sin_theta_o / v;
    if v <= 0.1 {
        (log_i0(a) - b - 1.0 / v + 0.6931 + (1.0 / (2.0 * v)).ln()).exp()
    } else {
        ((-b).exp() * i0(a)) / ((1.0 / v).sinh() * 2.0 * v)
    }
}

/// pbrt-v4 `HairBxDF::Ap`.
pub fn ap(cos_theta_o: f64, eta: f64, h: f64, t: [f64; 3]) -> Lobes {
    let mut ap = [[0.0; 3]; P_MAX + 1];
    // p = 0 attenuation at the first cylinder intersection.
    let cos_gamma_o = safe_sqrt(1.0 - sqr(h));
    let cos_theta = cos_theta_o * cos_gamma_o;
    let f = fr_dielectric(cos_theta, eta);
    ap[0] = [f; 3];
    // p = 1.
    ap[1] = t.map(|t| sqr(1.0 - f) * t);
    // p up to pMax.
    for p in 2..P_MAX {
        ap[p] = std::array::from_fn(|k| ap[p - 1][k] * t[k] * f);
    }
    // The remaining orders.
    ap[P_MAX] = std::array::from_fn(|k| {
        if 1.0 - t[k] * f != 0.0 {
            ap[P_MAX - 1][k] * f * t[k] / (1.0 - t[k] * f)
        } else {
            0.0
        }
    });
    ap
}

/// pbrt-v4 `HairBxDF::Phi`.
pub fn phi_p(p: usize, gamma_o: f64, gamma_t: f64) -> f64 {
    2.0 * p as f64 * gamma_t - 2.0 * gamma_o + p as f64 * PI
}

/// pbrt-v4 `HairBxDF::Np`.
pub fn np(phi: f64, p: usize, s: f64, gamma_o: f64, gamma_t: f64) -> f64 {
    let mut dphi = phi - phi_p(p, gamma_o, gamma_t);
    // Remap dphi to [−π, π].
    while dphi > PI {
        dphi -= 2.0 * PI;
    }
    while dphi < -PI {
        dphi += 2.0 * PI;
    }
    trimmed_logistic(dphi, s, -PI, PI)
}

/// pbrt-v4 `HairBxDF::SigmaAFromReflectance` (Chiang 2016 Eq. 9 inverted).
pub fn sigma_a_from_reflectance(c: [f64; 3], beta_n: f64) -> [f64; 3] {
    let b = beta_n;
    let d = 5.969 - 0.215 * b + 2.532 * sqr(b) - 10.73 * b.powi(3)
        + 5.574 * b.powi(4)
        + 0.245 * b.powi(5);
    c.map(|c| sqr(c.ln() / d))
}

/// pbrt-v4 `HairBxDF`'s members.
#[derive(Debug, Clone)]
pub struct HairBxDF {
    pub h: f64,
    pub eta: f64,
    pub sigma_a: [f64; 3],
    pub v: [f64; P_MAX + 1],
    pub s: f64,
    pub sin_2k_alpha: [f64; P_MAX],
    pub cos_2k_alpha: [f64; P_MAX],
}

impl HairBxDF {
    /// pbrt-v4 `HairBxDF::HairBxDF(h, eta, sigma_a, beta_m, beta_n, alpha)`
    /// (alpha in degrees).
    pub fn new(h: f64, eta: f64, sigma_a: [f64; 3], beta_m: f64, beta_n: f64, alpha: f64) -> Self {
        assert!((-1.0..=1.0).contains(&h));
        assert!((0.0..=1.0).contains(&beta_m) && (0.0..=1.0).contains(&beta_n));
        // Longitudinal variance from beta_m (Chiang Eq. 7).
        let mut v = [0.0; P_MAX + 1];
        v[0] = sqr(0.726 * beta_m + 0.812 * sqr(beta_m) + 3.7 * beta_m.powi(20));
        v[1] = 0.25 * v[0];
        v[2] = 4.0 * v[0];
        for p in 3..=P_MAX {
            v[p] = v[2];
        }
        // Azimuthal logistic scale from beta_n (Chiang Eq. 8).
        const SQRT_PI_OVER_8: f64 = 0.626657069;
        let s = SQRT_PI_OVER_8 * (0.265 * beta_n + 1.194 * sqr(beta_n) + 5.372 * beta_n.powi(22));
        // Cuticle scale tilt terms.
        let mut sin_2k_alpha = [0.0; P_MAX];
        let mut cos_2k_alpha = [0.0; P_MAX];
        sin_2k_alpha[0] = alpha.to_radians().sin();
        cos_2k_alpha[0] = safe_sqrt(1.0 - sqr(sin_2k_alpha[0]));
        for i in 1..P_MAX {
            sin_2k_alpha[i] = 2.0 * cos_2k_alpha[i - 1] * sin_2k_alpha[i - 1];
            cos_2k_alpha[i] = sqr(cos_2k_alpha[i - 1]) - sqr(sin_2k_alpha[i - 1]);
        }
        Self {
            h,
            eta,
            sigma_a,
            v,
            s,
            sin_2k_alpha,
            cos_2k_alpha,
        }
    }

    /// sin θ'_o, cos θ'_o: θ_o rotated by the cuticle tilt for lobe p
    /// (the `sinThetap_o`/`cosThetap_o` block of `HairBxDF::f`).
    pub fn tilted(&self, p: usize, sin_theta_o: f64, cos_theta_o: f64) -> (f64, f64) {
        let (s2a, c2a) = (&self.sin_2k_alpha, &self.cos_2k_alpha);
        let (sin_p, cos_p) = match p {
            0 => (
                sin_theta_o * c2a[1] - cos_theta_o * s2a[1],
                cos_theta_o * c2a[1] + sin_theta_o * s2a[1],
            ),
            1 => (
                sin_theta_o * c2a[0] + cos_theta_o * s2a[0],
                cos_theta_o * c2a[0] - sin_theta_o * s2a[0],
            ),
            2 => (
                sin_theta_o * c2a[2] + cos_theta_o * s2a[2],
                cos_theta_o * c2a[2] - sin_theta_o * s2a[2],
            ),
            _ => (sin_theta_o, cos_theta_o),
        };
        // Out-of-range cos θ_o from the scale adjustment.
        (sin_p, cos_p.abs())
    }

    /// M_p of lobe p (`HairBxDF::f`'s `Mp(...)` call, with its tilt).
    pub fn mp_lobe(&self, p: usize, sin_theta_i: f64, sin_theta_o: f64) -> f64 {
        let cos_theta_i = safe_sqrt(1.0 - sqr(sin_theta_i));
        let cos_theta_o = safe_sqrt(1.0 - sqr(sin_theta_o));
        if p < P_MAX {
            let (sp, cp) = self.tilted(p, sin_theta_o, cos_theta_o);
            mp(cos_theta_i, cp, sin_theta_i, sp, self.v[p])
        } else {
            mp(
                cos_theta_i,
                cos_theta_o,
                sin_theta_i,
                sin_theta_o,
                self.v[P_MAX],
            )
        }
    }

    /// A_p(h) and γ_o, γ_t for view elevation sin θ_o (the part of
    /// `HairBxDF::f` before the lobe loop).
    pub fn ap_gamma(&self, sin_theta_o: f64) -> (Lobes, f64, f64) {
        let cos_theta_o = safe_sqrt(1.0 - sqr(sin_theta_o));
        let gamma_o = safe_asin(self.h);
        // cos θ_t of the refracted ray.
        let sin_theta_t = sin_theta_o / self.eta;
        let cos_theta_t = safe_sqrt(1.0 - sqr(sin_theta_t));
        // γ_t of the refracted ray.
        let etap = safe_sqrt(sqr(self.eta) - sqr(sin_theta_o)) / cos_theta_o;
        let sin_gamma_t = self.h / etap;
        let cos_gamma_t = safe_sqrt(1.0 - sqr(sin_gamma_t));
        let gamma_t = safe_asin(sin_gamma_t);
        // Transmittance of one path through the cylinder.
        let t = self
            .sigma_a
            .map(|s| (-s * (2.0 * cos_gamma_t / cos_theta_t)).exp());
        (ap(cos_theta_o, self.eta, self.h, t), gamma_o, gamma_t)
    }

    /// pbrt-v4 `HairBxDF::f(wo, wi)` per lobe, times `AbsCosTheta(wi)`: pbrt
    /// divides its sum by |wi.z| (the shading normal's cosine) and the
    /// integrator multiplies by it again, so this is what multiplies the
    /// incident radiance. Local frame: x along the fibre, φ = atan2(z, y).
    pub fn f_cos(&self, wo: [f64; 3], wi: [f64; 3]) -> Lobes {
        let sin_theta_o = wo[0];
        let phi_o = wo[2].atan2(wo[1]);
        let sin_theta_i = wi[0];
        let phi_i = wi[2].atan2(wi[1]);
        let (ap, gamma_o, gamma_t) = self.ap_gamma(sin_theta_o);
        let phi = phi_i - phi_o;
        let mut out = [[0.0; 3]; P_MAX + 1];
        for p in 0..P_MAX {
            let m = self.mp_lobe(p, sin_theta_i, sin_theta_o);
            let n = np(phi, p, self.s, gamma_o, gamma_t);
            out[p] = ap[p].map(|a| m * a * n);
        }
        // The remaining orders: uniform in φ.
        let m = self.mp_lobe(P_MAX, sin_theta_i, sin_theta_o);
        out[P_MAX] = ap[P_MAX].map(|a| m * a / (2.0 * PI));
        out
    }
}

/// Reference parameters: pbrt's `HairMaterial` with `reflectance` (σ_a from
/// the colour by `SigmaAFromReflectance`), β_m = β_n = β, α = 2°, η = 1.55.
#[derive(Debug, Clone, Copy)]
pub struct Params {
    pub color: [f64; 3],
    pub beta: f64,
}

pub const ETA: f64 = 1.55;
pub const ALPHA_DEG: f64 = 2.0;

impl Params {
    pub fn bxdf(&self, h: f64) -> HairBxDF {
        let sa = sigma_a_from_reflectance(self.color, self.beta);
        HairBxDF::new(h, ETA, sa, self.beta, self.beta, ALPHA_DEG)
    }
}

/// Quadrature offsets over h ∈ [−1, 1] with their weights (summing to 1, the
/// uniform average): midpoints in γ = asin h (h = sin γ, dh = cos γ dγ), which
/// resolves the fast change of Φ_p near the silhouette.
pub fn h_nodes(n: usize) -> Vec<(f64, f64)> {
    let d = PI / n as f64;
    (0..n)
        .map(|k| {
            let g = -PI / 2.0 + (k as f64 + 0.5) * d;
            (g.sin(), 0.5 * g.cos() * d)
        })
        .collect()
}

/// pbrt's `f_cos` averaged over h directly (slow; checks [`Azimuthal`]).
pub fn average_over_h(p: &Params, wo: [f64; 3], wi: [f64; 3], n: usize) -> Lobes {
    let mut out = [[0.0; 3]; P_MAX + 1];
    for (h, w) in h_nodes(n) {
        let f = p.bxdf(h).f_cos(wo, wi);
        for (o, f) in out.iter_mut().zip(f) {
            for k in 0..3 {
                o[k] += w * f[k];
            }
        }
    }
    out
}

/// ½∫ A_p(h) N_p(φ; h) dh for one view elevation, tabulated at given φ.
pub struct Azimuthal {
    pub params: Params,
    pub sin_theta_o: f64,
    /// [φ index][lobe][rgb]; lobe 3 is pbrt's residual A_3 / 2π.
    pub table: Vec<Lobes>,
}

impl Azimuthal {
    pub fn new(params: Params, sin_theta_o: f64, phis: Vec<f64>, n_h: usize) -> Self {
        let mut table = vec![[[0.0; 3]; P_MAX + 1]; phis.len()];
        for (h, w) in h_nodes(n_h) {
            let bxdf = params.bxdf(h);
            let (ap, gamma_o, gamma_t) = bxdf.ap_gamma(sin_theta_o);
            for (row, &phi) in table.iter_mut().zip(&phis) {
                for p in 0..P_MAX {
                    let n = np(phi, p, bxdf.s, gamma_o, gamma_t);
                    for k in 0..3 {
                        row[p][k] += w * ap[p][k] * n;
                    }
                }
                for k in 0..3 {
                    row[P_MAX][k] += w * ap[P_MAX][k] / (2.0 * PI);
                }
            }
        }
        Self {
            params,
            sin_theta_o,
            table,
        }
    }

    /// pbrt's h-averaged f · |cos| at (sin θ_i, φ index).
    pub fn f_cos(&self, sin_theta_i: f64, phi_index: usize) -> Lobes {
        let bxdf = self.params.bxdf(0.0);
        std::array::from_fn(|p| {
            let m = bxdf.mp_lobe(p, sin_theta_i, self.sin_theta_o);
            self.table[phi_index][p].map(|n| m * n)
        })
    }
}
