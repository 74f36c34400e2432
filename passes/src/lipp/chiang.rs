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
    let [r, tt, trt] = chiang_lobes(t, l, v, m);
    std::array::from_fn(|k| r[k] + tt[k] + trt[k])
}

/// [`chiang`] per lobe: R, TT, TRT.
pub fn chiang_lobes(t: [f32; 3], l: [f32; 3], v: [f32; 3], m: &Material) -> [[f32; 3]; 3] {
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
    let mps: [f32; 3] = std::array::from_fn(|p| {
        let (sin_k, cos_k, var) = TILT[p];
        let var = var * v0;
        let sin_p = sin_o * cos_k + cos_o * sin_k;
        let cos_p = (cos_o * cos_k - sin_o * sin_k).abs();
        mp(cos_i, cos_p, sin_i, sin_p, var)
    });
    // R: d'Eon 2011's far-field N_R for a smooth cylinder.
    let cos_half = (0.5 + 0.5 * cos_phi).max(0.0).sqrt();
    let r = 0.25 * cos_half * fresnel(cos_o * cos_half) * mps[0];
    // TT, TRT: ½∫ A_p(h) N_p(φ; h) dh with Φ_p(h) piecewise linear between
    // the offsets of H_NODES: each piece is a box in φ convolved with the
    // logistic, a difference of two logistic CDFs.
    let etap = (ETA * ETA - sin_o * sin_o).sqrt() / cos_o.max(1e-4);
    let sin_t = sin_o / ETA;
    let cos_t = (1.0 - sin_t * sin_t).max(1e-4).sqrt();
    let sa = sigma_a(m.color, b);
    let mut a = [[[0.0f32; 3]; 2]; NODES];
    let mut d = [[0.0f32; 2]; NODES];
    for (j, &(h, gamma_o, cos_gamma_o)) in H_NODES.iter().enumerate() {
        let sin_gt = h / etap;
        let cos_gt = (1.0 - sin_gt * sin_gt).max(0.0).sqrt();
        let gamma_t = sin_gt.asin();
        let f = fresnel(cos_o * cos_gamma_o);
        let tr = sa.map(|a| (-2.0 * a * cos_gt / cos_t).exp());
        let t1 = (1.0 - f) * (1.0 - f);
        a[j] = [tr.map(|t| t1 * t), tr.map(|t| t1 * t * t * f)];
        d[j] = [2.0 * gamma_t - 2.0 * gamma_o, 4.0 * gamma_t - 2.0 * gamma_o];
    }
    let x = [phi - PI, phi];
    let norm = 1.0 / (logistic_cdf(PI, s) - logistic_cdf(-PI, s));
    let mut out = [[r; 3], [0.0; 3], [0.0; 3]];
    for p in 0..2 {
        for j in 0..NODES - 1 {
            let dh = H_NODES[j + 1].0 - H_NODES[j].0;
            let n = 0.5
                * dh
                * (segment(x[p], d[j][p], d[j + 1][p], s)
                    + segment(-x[p], d[j][p], d[j + 1][p], s));
            for k in 0..3 {
                out[p + 1][k] += 0.5 * (a[j][p][k] + a[j + 1][p][k]) * n;
            }
        }
        let mp = mps[p + 1] * norm;
        out[p + 1] = out[p + 1].map(|o| o * mp);
    }
    out
}

/// The logistic (scale s) convolved with a box from a to b, at x.
fn segment(x: f32, a: f32, b: f32, s: f32) -> f32 {
    if (b - a).abs() < 1e-3 * s {
        logistic(x - 0.5 * (a + b), s)
    } else {
        (logistic_cdf(x - a, s) - logistic_cdf(x - b, s)) / (b - a)
    }
}

const ETA: f32 = 1.55;

/// A box of half-width c convolved with a logistic of scale s, normalised
/// on [−π, π]: the h-averaged N_p when Φ_p(h) has spread variance `var`,
/// a fraction `k` of it put in the logistic and the rest in the box.
fn spread(x: f32, s: f32, var: f32, k: f32) -> f32 {
    let s = (s * s + 3.0 * k * var / (PI * PI)).sqrt();
    let c = (3.0 * (1.0 - k) * var).max(0.0).sqrt().min(0.5 * PI);
    if c < 1e-3 * s {
        return trimmed_logistic(x, s);
    }
    let box_ = (logistic_cdf(x + c, s) - logistic_cdf(x - c, s)) / (2.0 * c);
    let mass =
        1.0 + s / c * ((1.0 + (-(PI + c) / s).exp()).ln() - (1.0 + (-(PI - c) / s).exp()).ln());
    box_ / mass
}

/// Per lobe: sin 2kα, cos 2kα of the cuticle tilt applied to θ_o (α = 2°;
/// R: −2α, TT: +α, TRT: +4α, pbrt-v4 `HairBxDF::f`) and v_p / v_0 (Chiang
/// Eq. 7: v_1 = v_0 / 4, v_2 = 4 v_0).
const TILT: [(f32, f32, f32); 3] = [
    (-0.069_756_47, 0.997_564_05, 1.0),
    (0.034_899_5, 0.999_390_8, 0.25),
    (0.139_173_1, 0.990_268_05, 4.0),
];

/// Offsets h ∈ [0, 1] (the average is symmetric in h) where Φ_p and A_p
/// are evaluated: γ = asin h evenly spaced, (h, γ, cos γ).
const NODES: usize = 5;
const H_NODES: [(f32, f32, f32); NODES] = [
    (0.000000, 0.000000, 1.000000),
    (0.382683, 0.392699, 0.923880),
    (0.707107, 0.785398, 0.707107),
    (0.923880, 1.178097, 0.382683),
    (1.000000, 1.570796, 0.000000),
];

/// Dielectric Fresnel reflectance from outside (pbrt-v4 `FrDielectric`, η = 1.55).
fn fresnel(cos_i: f32) -> f32 {
    let sin2_t = (1.0 - cos_i * cos_i) / (ETA * ETA);
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (ETA * cos_i - cos_t) / (ETA * cos_i + cos_t);
    let r_perp = (cos_i - ETA * cos_t) / (cos_i + ETA * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

/// ln I0(x), x ≥ 0: Abramowitz and Stegun 9.8.1 and 9.8.2 (relative error
/// below 2e-7).
fn log_i0(x: f32) -> f32 {
    if x < 3.75 {
        let t = (x / 3.75) * (x / 3.75);
        (1.0 + t
            * (3.515_622_9
                + t * (3.089_942_4
                    + t * (1.206_749_2 + t * (0.265_973_2 + t * (0.036_076_8 + t * 0.004_581_3))))))
            .ln()
    } else {
        let t = 3.75 / x;
        let p = 0.398_942_28
            + t * (0.013_285_92
                + t * (0.002_253_19
                    + t * (-0.001_575_65
                        + t * (0.009_162_81
                            + t * (-0.020_577_06
                                + t * (0.026_355_37 + t * (-0.016_476_33 + t * 0.003_923_77)))))));
        x - 0.5 * x.ln() + p.ln()
    }
}

/// d'Eon et al. 2011's M_p (Chiang 2016 Eq. 6; pbrt-v4 `HairBxDF::Mp`),
/// csch(1/v) / (2v) · exp(−sin θ_i sin θ_o / v) · I0(cos θ_i cos θ_o / v),
/// in log form for every v (2v sinh(1/v) = v e^{1/v} (1 − e^{−2/v})).
fn mp(cos_i: f32, cos_o: f32, sin_i: f32, sin_o: f32, v: f32) -> f32 {
    let a = cos_i * cos_o / v;
    let b = sin_i * sin_o / v;
    (log_i0(a) - b - 1.0 / v - v.ln() - (1.0 - (-2.0 / v).exp()).ln()).exp()
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

/// The numerical check against pbrt-v4's `HairBxDF` (`chiang_reference`).
#[cfg(test)]
mod check {
    use super::super::chiang_reference as pbrt;
    use super::*;
    use std::f64::consts::PI as PI64;

    /// Midpoint grids: sin θ_i over [−1, 1] (dω = d sin θ_i dφ) and φ over
    /// [−π, π]; offsets h for the reference's average.
    const N_U: usize = 400;
    const N_PHI: usize = 180;
    const N_H: usize = 1024;

    pub struct Hair {
        pub name: &'static str,
        pub color: [f32; 3],
    }
    pub const HAIRS: [Hair; 3] = [
        Hair {
            name: "blonde",
            color: [0.75, 0.55, 0.32],
        },
        Hair {
            name: "brown",
            color: [0.24, 0.12, 0.05],
        },
        Hair {
            name: "black",
            color: [0.03, 0.02, 0.015],
        },
    ];
    pub const BETAS: [f32; 3] = [0.2, 0.3, 0.5];
    pub const SIN_O: [f64; 6] = [-0.7, -0.35, 0.0, 0.35, 0.7, 0.9];

    fn midpoints(n: usize, a: f64, b: f64) -> Vec<f64> {
        (0..n)
            .map(|k| a + (b - a) * (k as f64 + 0.5) / n as f64)
            .collect()
    }

    fn dir(sin: f64, phi: f64) -> [f32; 3] {
        let c = (1.0 - sin * sin).max(0.0).sqrt();
        [sin as f32, (c * phi.cos()) as f32, (c * phi.sin()) as f32]
    }

    const T: [f32; 3] = [1.0, 0.0, 0.0];

    /// One configuration measured: per lobe R, TT, TRT and their sum.
    #[derive(Debug, Default, Clone, Copy)]
    pub struct Lobe {
        /// Directional albedo ∫ S dω_i, compact and reference, RGB.
        pub energy: [[f64; 3]; 2],
        /// Σ|S_c − S_ref| / Σ S_ref over the grid (all channels).
        pub l1: f64,
        /// The same with both lobes scaled to unit energy (shape only).
        pub shape_l1: f64,
    }

    impl Lobe {
        /// Worst relative energy error over the channels whose reference
        /// energy is at least `floor` (black hair's TT is ~1e-7).
        pub fn energy_error(&self, floor: f64) -> f64 {
            (0..3)
                .filter(|&k| self.energy[1][k] >= floor)
                .map(|k| (self.energy[0][k] / self.energy[1][k] - 1.0).abs())
                .fold(0.0, f64::max)
        }
    }

    pub fn measure(color: [f32; 3], beta: f32, sin_o: f64) -> [Lobe; 4] {
        let params = pbrt::Params {
            color: color.map(f64::from),
            beta: beta as f64,
        };
        let m = Material {
            color,
            roughness: beta,
        };
        let us = midpoints(N_U, -1.0, 1.0);
        let phis = midpoints(N_PHI, -PI64, PI64);
        let reference = pbrt::Azimuthal::new(params, sin_o, phis.clone(), N_H);
        let v = dir(sin_o, 0.0);
        let dw = (2.0 / N_U as f64) * (2.0 * PI64 / N_PHI as f64);
        // [lobe][compact, reference] samples, RGB, over the grid.
        let mut c = vec![Vec::with_capacity(N_U * N_PHI); 4];
        let mut r = vec![Vec::with_capacity(N_U * N_PHI); 4];
        for &u in &us {
            for (j, &phi) in phis.iter().enumerate() {
                let sc = chiang_lobes(T, dir(u, phi), v, &m);
                let sr = reference.f_cos(u, j);
                let mut tc = [0.0; 3];
                let mut tr = [0.0; 3];
                for p in 0..3 {
                    let a = sc[p].map(f64::from);
                    c[p].push(a);
                    r[p].push(sr[p]);
                    for k in 0..3 {
                        tc[k] += a[k];
                        tr[k] += sr[p][k];
                    }
                }
                c[3].push(tc);
                r[3].push(tr);
            }
        }
        std::array::from_fn(|p| {
            let e = |s: &[[f64; 3]]| -> [f64; 3] {
                std::array::from_fn(|k| s.iter().map(|x| x[k]).sum::<f64>() * dw)
            };
            let (ec, er) = (e(&c[p]), e(&r[p]));
            let mut diff = 0.0;
            let mut shape = 0.0;
            let mut total = 0.0;
            for (a, b) in c[p].iter().zip(&r[p]) {
                for k in 0..3 {
                    diff += (a[k] - b[k]).abs();
                    total += b[k];
                    if ec[k] > 0.0 && er[k] > 0.0 {
                        shape += (a[k] / ec[k] - b[k] / er[k]).abs() * dw / 3.0;
                    }
                }
            }
            Lobe {
                energy: [ec, er],
                l1: diff / total,
                shape_l1: shape,
            }
        })
    }

    /// Lobe p at φ = 0 over θ_i: (argmax of S · cos θ_i, i.e. the peak per
    /// unit θ_i; centroid of θ_i weighted by S), degrees, compact and reference.
    pub fn peak(beta: f32, sin_o: f64, p: usize) -> [(f64, f64); 2] {
        let m = Material {
            color: HAIRS[0].color,
            roughness: beta,
        };
        let bxdf = pbrt::Params {
            color: m.color.map(f64::from),
            beta: beta as f64,
        }
        .bxdf(0.0);
        let v = dir(sin_o, 0.0);
        let us = midpoints(8000, -1.0, 1.0);
        let stats = |f: &dyn Fn(f64) -> f64| {
            let vals: Vec<f64> = us.iter().map(|&u| f(u)).collect();
            let k = (0..us.len())
                .max_by(|&a, &b| {
                    let c = |i: usize| vals[i] * (1.0 - us[i] * us[i]).sqrt();
                    c(a).total_cmp(&c(b))
                })
                .unwrap();
            let sum: f64 = vals.iter().sum();
            let mean: f64 = vals.iter().zip(&us).map(|(f, u)| f * u.asin()).sum::<f64>() / sum;
            (us[k].asin().to_degrees(), mean.to_degrees())
        };
        let c = stats(&|u| chiang_lobes(T, dir(u, 0.0), v, &m)[p][0] as f64);
        let r = stats(&|u| bxdf.mp_lobe(p, u, sin_o));
        [(c.0, r.0), (c.1, r.1)]
    }

    #[test]
    #[ignore = "prints the comparison table"]
    fn print_comparison() {
        let names = ["R", "TT", "TRT", "sum"];
        let mut worst = [0.0f64; 4];
        let mut mean = [0.0f64; 4];
        let mut count = 0.0;
        for hair in &HAIRS {
            for &beta in &BETAS {
                for &sin_o in &SIN_O {
                    let lobes = measure(hair.color, beta, sin_o);
                    count += 1.0;
                    for p in 0..4 {
                        worst[p] = worst[p].max(lobes[p].l1);
                        mean[p] += lobes[p].l1;
                    }
                    let mut line = format!(
                        "{:6} β={beta:.1} θo={:+5.1}°",
                        hair.name,
                        sin_o.asin().to_degrees()
                    );
                    for (p, l) in lobes.iter().enumerate() {
                        line += &format!(
                            " | {} E {:.4}/{:.4} L1 {:.2} sh {:.2}",
                            names[p], l.energy[0][0], l.energy[1][0], l.l1, l.shape_l1
                        );
                    }
                    eprintln!("{line}");
                }
            }
        }
        eprintln!("L1 mean {:?} worst {:?}", mean.map(|m| m / count), worst);
        if std::env::var("NOPEAK").is_ok() {
            return;
        }
        for &beta in &BETAS {
            for &sin_o in &SIN_O {
                let [(r, rr), (rc, rrc)] = peak(beta, sin_o, 0);
                let [(t, tr), (tc, trc)] = peak(beta, sin_o, 2);
                eprintln!(
                    "peak β={beta:.1} θo={:+5.1}°: R {r:+.2}° vs {rr:+.2}° (mean {rc:+.2}° vs {rrc:+.2}°), TRT {t:+.2}° vs {tr:+.2}° (mean {tc:+.2}° vs {trc:+.2}°)",
                    sin_o.asin().to_degrees()
                );
            }
        }
    }
}
#[cfg(test)]
mod probe {
    use super::super::chiang_reference as pbrt;
    use super::*;
    #[test]
    #[ignore]
    fn profile() {
        let beta: f32 = std::env::var("B").unwrap().parse().unwrap();
        let sin_o: f64 = std::env::var("SO").unwrap().parse().unwrap();
        let p: usize = std::env::var("P").unwrap().parse().unwrap();
        let phis: Vec<f64> = (0..60)
            .map(|k| (k as f64 + 0.5) * std::f64::consts::PI / 60.0)
            .collect();
        let params = pbrt::Params {
            color: [0.75, 0.55, 0.32],
            beta: beta as f64,
        };
        let az = pbrt::Azimuthal::new(params, sin_o, phis.clone(), 2048);
        let m = Material {
            color: [0.75, 0.55, 0.32],
            roughness: beta,
        };
        let u = -sin_o; // near the lobe
        let c = (1.0 - sin_o * sin_o).sqrt();
        let v = [sin_o as f32, c as f32, 0.0];
        for (j, &phi) in phis.iter().enumerate() {
            let cu = (1.0 - u * u).sqrt();
            let l = [u as f32, (cu * phi.cos()) as f32, (cu * phi.sin()) as f32];
            let sc = chiang_lobes([1.0, 0.0, 0.0], l, v, &m)[p][0];
            let sr = az.f_cos(u, j)[p][0];
            eprintln!("{:6.1} {:10.5} {:10.5}", phi.to_degrees(), sc, sr);
        }
    }
}
