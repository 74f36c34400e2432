//! A_p of Chiang's model averaged over the fibre offset h: the offsets
//! where it is evaluated, their Fresnel and transmittance (pbrt-v4
//! `HairBxDF::Ap`), the weights of the pieces between them, and the
//! per-view table of them ([`FibrePaths`]) that every light and the probe
//! term read.

use super::{Material, sigma_a};

const ETA: f32 = 1.55;

/// The light path at one offset h of [`H_NODES`], seen at (sin θ_o, cos θ_o):
/// Fresnel at entry, the RGB transmittance through the fibre and sin γ_t
/// (pbrt-v4 `HairBxDF::Ap`'s inputs and `Phi`'s refracted angle).
pub(super) struct Offset {
    pub(super) f: f32,
    pub(super) tr: [f32; 3],
    pub(super) sin_gt: f32,
}

/// The light path at each of [`H_NODES`] for a view at (sin θ_o, cos θ_o)
/// through a fibre of absorption `sigma_a`.
pub(super) fn offsets(sin_o: f32, cos_o: f32, sigma_a: [f32; 3]) -> [Offset; NODES] {
    let etap = (ETA * ETA - sin_o * sin_o).sqrt() / cos_o.max(1e-4);
    let sin_t = sin_o / ETA;
    let cos_t = (1.0 - sin_t * sin_t).max(1e-4).sqrt();
    H_NODES.map(|(h, _, cos_gamma_o)| {
        let sin_gt = h / etap;
        let cos_gt = (1.0 - sin_gt * sin_gt).max(0.0).sqrt();
        Offset {
            f: fresnel(cos_o * cos_gamma_o),
            tr: sigma_a.map(|a| (-2.0 * a * cos_gt / cos_t).exp()),
            sin_gt,
        }
    })
}

/// What Chiang's model needs of one view through one fibre: A_p and
/// Φ_p − pπ of TT and TRT at each of [`H_NODES`], and the directional albedo
/// of R and TRT they give. None of it depends on the light, so `lipp.shade`
/// computes it once per shaded point, for every light's lobes
/// ([`super::chiang_lobes`]) and for the probe's lobe
/// (`probe::specular_lobe`).
pub struct FibrePaths {
    /// A_TT, A_TRT per node.
    pub(super) ap: [[[f32; 3]; 2]; NODES],
    /// Φ_TT − π, Φ_TRT − 2π per node.
    pub(super) dphi: [[f32; 2]; NODES],
    /// R's directional albedo: pbrt-v4's `HairBxDF::Ap` for p = 0 averaged
    /// over h (M_p and N_p integrate to one, so under uniform light the lobe
    /// returns this; [`r_albedo`]). `lipp.shade`'s probe term weights
    /// its single GGX lobe with it and TRT's (Lipp §3.4).
    pub r_albedo: f32,
    /// TRT's, per channel.
    pub trt_albedo: [f32; 3],
}

impl FibrePaths {
    /// The paths seen at sin θ_o = `sin_o` (T · V) through a fibre of
    /// material `m`.
    pub fn new(sin_o: f32, m: &Material) -> Self {
        let sin_o = sin_o.clamp(-1.0, 1.0);
        let cos_o = (1.0 - sin_o * sin_o).max(0.0).sqrt();
        let at = offsets(sin_o, cos_o, sigma_a(m.color, m.roughness.clamp(0.02, 1.0)));
        let mut ap = [[[0.0f32; 3]; 2]; NODES];
        let mut dphi = [[0.0f32; 2]; NODES];
        for (j, (o, &(_, gamma_o, _))) in at.iter().zip(&H_NODES).enumerate() {
            let gamma_t = o.sin_gt.asin();
            let (f, t1) = (o.f, (1.0 - o.f) * (1.0 - o.f));
            ap[j] = [o.tr.map(|t| t1 * t), o.tr.map(|t| t1 * t * t * f)];
            dphi[j] = [2.0 * gamma_t - 2.0 * gamma_o, 4.0 * gamma_t - 2.0 * gamma_o];
        }
        // TRT's albedo: A_p linear in γ over each piece, as the lobe
        // integrates it. R's: its own rule (r_albedo).
        let mut trt_albedo = [0.0f32; 3];
        for (j, &(wa, wb)) in PIECES.iter().enumerate() {
            for k in 0..3 {
                trt_albedo[k] += wa * ap[j][1][k] + wb * ap[j + 1][1][k];
            }
        }
        let r_albedo = r_albedo(cos_o);
        Self {
            ap,
            dphi,
            r_albedo,
            trt_albedo,
        }
    }
}

/// R's directional albedo, ∫₀¹ F(cos θ_o √(1 − h²)) dh = ∫₀^{π/2} F(cos θ_o
/// cos γ) cos γ dγ: what R's lobe (d'Eon's ¼ cos(φ/2) F over φ) integrates
/// to. The pieces of [`H_NODES`], which take A linear in γ, overestimate it
/// by 5-14%: Fresnel rises to 1 at grazing offsets, within the last piece.
///
/// It depends on cos θ_o alone (η is fixed), so it is a polynomial in cos θ_o
/// ([`R_ALBEDO_FIT`]) rather than the four Fresnel terms of its 4-point
/// Gauss–Legendre rule in γ (`tests::R_ALBEDO_NODES`, within 0.7% of what
/// the lobe reflects: `check::the_paths_albedo_is_what_the_lobes_reflect`)
/// at every shaded point: those cost 12 µs of `lipp.shade` at the close
/// view on the H200 (benches/results/lipp-r-albedo-h200.txt).
pub(super) fn r_albedo(cos_o: f32) -> f32 {
    R_ALBEDO_FIT
        .iter()
        .rev()
        .fold(0.0, |acc, &c| acc * cos_o + c)
}

/// [`r_albedo`]'s coefficients, constant term first: the least-squares fit
/// of the Gauss–Legendre rule over cos θ_o ∈ [0, 1] in relative error (worst
/// 0.13%; `tests::the_r_albedo_fit_follows_its_rule`). `chiang.wgsl` holds
/// the same bits (passes/tests/wgsl_shared.rs).
pub const R_ALBEDO_FIT: [f32; 8] = [
    0.998_711,
    -4.440_474_4,
    11.730_038,
    -21.808_463,
    28.510_157,
    -24.327_722,
    11.955_967,
    -2.542_785_4,
];

/// Offsets h ∈ [0, 1] (the average is symmetric in h) where Φ_p and A_p
/// are evaluated: γ = asin h = (π/2) (j/4)^0.8, (h, γ, cos γ).
pub(super) const NODES: usize = 5;
pub(super) const H_NODES: [(f32, f32, f32); NODES] = [
    (0.000000, 0.000000, 1.000000),
    (0.495291, 0.518170, 0.868727),
    (0.784684, 0.902186, 0.619896),
    (0.948310, 1.247869, 0.317344),
    (1.000000, std::f32::consts::FRAC_PI_2, 0.000000),
];

/// ∫ A dh over each piece for A linear in γ between its ends: A_j P + A_{j+1} Q.
pub(super) const PIECES: [(f32, f32); NODES - 1] = [
    (0.253339, 0.241951),
    (0.152679, 0.136714),
    (0.090546, 0.073080),
    (0.034400, 0.017290),
];

/// Dielectric Fresnel reflectance from outside (pbrt-v4 `FrDielectric`, η = 1.55).
pub(super) fn fresnel(cos_i: f32) -> f32 {
    let sin2_t = (1.0 - cos_i * cos_i) / (ETA * ETA);
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (ETA * cos_i - cos_t) / (ETA * cos_i + cos_t);
    let r_perp = (cos_i - ETA * cos_t) / (cos_i + ETA * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// R's albedo by 4-point Gauss–Legendre in γ: (cos γ_k, (π/4) w_k cos
    /// γ_k), four Fresnel terms.
    const R_ALBEDO_NODES: [(f32, f32); 4] = [
        (0.994058, 0.271581),
        (0.868624, 0.444904),
        (0.495472, 0.253777),
        (0.108847, 0.029738),
    ];

    fn r_albedo_rule(cos_o: f32) -> f32 {
        R_ALBEDO_NODES
            .iter()
            .map(|&(cos_gamma, w)| w * fresnel(cos_o * cos_gamma))
            .sum()
    }

    #[test]
    fn the_r_albedo_fit_follows_its_rule() {
        let worst = (0..=1000)
            .map(|i| {
                let c = i as f32 / 1000.0;
                (r_albedo(c) / r_albedo_rule(c) - 1.0).abs()
            })
            .fold(0.0f32, f32::max);
        assert!(worst < 0.002, "worst relative error {worst}");
    }
}
