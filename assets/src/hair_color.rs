//! Hair colour from physics: pigment concentrations to an absorption
//! coefficient, and the absorption to the colour the shading models take.
//!
//! - Absorption: hair holds two melanins; d'Eon et al. 2011 ("An Energy-
//!   Conserving Hair Reflectance Model") and Chiang et al. 2016 ("A Practical
//!   and Controllable Hair and Fur Model for Production Path Tracing", §4.1)
//!   give σa = c_e·σa,e + c_p·σa,p with the per-unit-concentration absorption
//!   of eumelanin σa,e = (0.419, 0.697, 1.37) and pheomelanin
//!   σa,p = (0.187, 0.4, 1.05), per unit of fibre radius. Concentrations:
//!   about 0.3 is blond, 1.3 brown, 8 black (pbrt-v4's hair material uses the
//!   same scale).
//! - Colour: Chiang 2016 Eq. 9 maps a colour c to σa given the azimuthal
//!   roughness βn, σa = (ln c / D(βn))²; its inverse c = exp(−√σa · D(βn))
//!   is the colour whose multiply-scattered look matches the absorption.
//!   Lipp's Chiang lobes apply Eq. 9 to this colour and so recover σa
//!   exactly; Kulikov's Karis lobes take the colour itself (Karis 2016 tints
//!   TT and TRT with it).
//! - Dye: an optional dye colour adds the absorption Eq. 9 gives for it, as
//!   a second absorber in the fibre (dyes add absorbers; they do not replace
//!   melanin).

/// Chiang 2016 §4.1 (after d'Eon 2011): eumelanin's absorption per unit concentration.
pub const EUMELANIN_SIGMA_A: [f32; 3] = [0.419, 0.697, 1.37];
/// Chiang 2016 §4.1: pheomelanin's.
pub const PHEOMELANIN_SIGMA_A: [f32; 3] = [0.187, 0.4, 1.05];

/// Chiang 2016 Eq. 9's denominator, D(βn).
fn eq9_denominator(beta_n: f32) -> f32 {
    let b = beta_n;
    5.969 - 0.215 * b + 2.532 * b * b - 10.73 * b.powi(3) + 5.574 * b.powi(4) + 0.245 * b.powi(5)
}

/// The absorption of a fibre with `melanin` total concentration, a fraction
/// `redness` of which is pheomelanin.
pub fn sigma_a_from_melanin(melanin: f32, redness: f32) -> [f32; 3] {
    let ce = melanin * (1.0 - redness);
    let cp = melanin * redness;
    [0, 1, 2].map(|i| ce * EUMELANIN_SIGMA_A[i] + cp * PHEOMELANIN_SIGMA_A[i])
}

/// Chiang 2016 Eq. 9: the absorption whose multiply-scattered look is `color`.
pub fn sigma_a_from_color(color: [f32; 3], beta_n: f32) -> [f32; 3] {
    let d = eq9_denominator(beta_n);
    color.map(|c| {
        let l = c.clamp(1e-4, 1.0).ln() / d;
        l * l
    })
}

/// Eq. 9 inverted: the colour of absorption `sigma_a` at roughness `beta_n`.
pub fn color_from_sigma_a(sigma_a: [f32; 3], beta_n: f32) -> [f32; 3] {
    let d = eq9_denominator(beta_n);
    sigma_a.map(|s| (-s.max(0.0).sqrt() * d).exp())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq9_round_trips() {
        for beta in [0.1, 0.3, 0.6] {
            let c = [0.6, 0.35, 0.12];
            let back = color_from_sigma_a(sigma_a_from_color(c, beta), beta);
            for i in 0..3 {
                assert!((back[i] - c[i]).abs() < 1e-5, "{back:?} vs {c:?}");
            }
        }
    }

    #[test]
    fn melanin_darkens_and_warms() {
        let colour = |m, r| color_from_sigma_a(sigma_a_from_melanin(m, r), 0.3);
        let blond = colour(0.1, 0.0);
        let brown = colour(0.9, 0.0);
        let black = colour(8.0, 0.0);
        // Every melanin absorbs blue most: hair is warm at every concentration.
        for c in [blond, brown, black] {
            assert!(c[0] > c[1] && c[1] > c[2], "{c:?}");
        }
        assert!(blond[0] > 0.25 && brown[0] < 0.05 && black[0] < 1e-3);
        // Pheomelanin (redness) at the same total lightens and reddens.
        let red = colour(0.9, 0.8);
        assert!(red[0] > brown[0] && red[0] / red[2] > 2.0);
    }
}
