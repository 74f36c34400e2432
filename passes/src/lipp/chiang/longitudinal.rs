//! M_p of Chiang's model (d'Eon et al. 2011, Chiang Eq. 6 and 7) with
//! pbrt-v4's cuticle tilts, evaluated in log form.

/// Per lobe: sin, cos of the cuticle tilt applied to θ_o for scale tilt α
/// (R: −2α, TT: +α, TRT: +4α, pbrt-v4 `HairBxDF::f`) and v_p / v_0 (Chiang
/// Eq. 7: v_1 = v_0 / 4, v_2 = 4 v_0).
pub(super) fn tilt(alpha: f32) -> [(f32, f32, f32); 3] {
    let at = |k: f32, var: f32| {
        let (s, c) = (k * alpha).sin_cos();
        (s, c, var)
    };
    [at(-2.0, 1.0), at(1.0, 0.25), at(4.0, 4.0)]
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
        let p = 0.398_942_3
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
pub(super) fn mp(cos_i: f32, cos_o: f32, sin_i: f32, sin_o: f32, v: f32) -> f32 {
    let a = cos_i * cos_o / v;
    let b = sin_i * sin_o / v;
    (log_i0(a) - b - 1.0 / v - v.ln() - (1.0 - (-2.0 / v).exp()).ln()).exp()
}
