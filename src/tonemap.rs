//! Display transforms: scene-linear RGB (the graphs' `Rgba16Float` outputs)
//! to 8-bit display RGB. Tone mapping happens here, once, for every
//! pipeline and backend alike, so comparisons of linear outputs (agreement,
//! differential tests, FLIP) are not affected by the choice.
//!
//! - `Aces`: Stephen Hill's fit of the ACES reference rendering transform and
//!   sRGB output transform (RRT + ODT), with its input and output matrices
//!   (BakingLab, `ACES.hlsl`), then the sRGB encoding.
//! - `Agx`: Troy Sobotka's AgX with the default "base" look, in Benjamin
//!   Wrensch's minimal form (the inset matrix, a log2 encoding over
//!   [−12.47, +4.03] EV, the sixth-order polynomial fit of the contrast
//!   sigmoid, the outset matrix); its output is already display-encoded.
//! - `None`: clip to [0, 1], then sRGB encoding.

use glam::{Mat3, Vec3};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Tonemap {
    /// ACES (Hill's RRT + ODT fit).
    #[default]
    Aces,
    /// AgX, base look.
    Agx,
    /// Clip, no tone mapping.
    None,
}

/// The sRGB transfer function (IEC 61966-2-1), linear [0, 1] in.
pub fn srgb_encode(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

// Hill's matrices are written row by row in HLSL (mul(M, v)); glam takes columns.
fn rows(r: [[f32; 3]; 3]) -> Mat3 {
    Mat3::from_cols_array_2d(&r).transpose()
}

fn aces(c: Vec3) -> Vec3 {
    let input = rows([
        [0.59719, 0.35458, 0.04823],
        [0.07600, 0.90834, 0.01566],
        [0.02840, 0.13383, 0.83777],
    ]);
    let output = rows([
        [1.60475, -0.53108, -0.07367],
        [-0.10208, 1.10813, -0.00605],
        [-0.00327, -0.07276, 1.07602],
    ]);
    let v = input * c;
    let rrt_odt =
        (v * (v + 0.024_578_6) - 0.000_090_537) / (v * (0.983_729 * v + 0.432_951) + 0.238_081);
    (output * rrt_odt).map(srgb_encode)
}

fn agx(c: Vec3) -> Vec3 {
    // GLSL mat3(...) fills columns: these are the columns.
    let inset = Mat3::from_cols_array(&[
        0.842_479_06,
        0.042_328_24,
        0.042_375_655,
        0.078_433_6,
        0.878_468_64,
        0.078_433_6,
        0.079_223_745,
        0.079_166_13,
        0.879_143,
    ]);
    let outset = Mat3::from_cols_array(&[
        1.196_879,
        -0.052_896_85,
        -0.052_971_635,
        -0.098_020_88,
        1.151_903_1,
        -0.098_043_45,
        -0.099_029_74,
        -0.098_961_18,
        1.151_073_7,
    ]);
    let (min_ev, max_ev) = (-12.473_931, 4.026_069);
    let v = (inset * c.max(Vec3::splat(1e-10)))
        .map(|x| ((x.log2().clamp(min_ev, max_ev)) - min_ev) / (max_ev - min_ev));
    let contrast = v.map(|x| {
        let (x2, x4) = (x * x, x * x * x * x);
        15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x
            - 0.002_32
    });
    (outset * contrast).clamp(Vec3::ZERO, Vec3::ONE)
}

impl Tonemap {
    /// Scene-linear RGB, scaled by `2^exposure_ev`, to display-encoded [0, 1].
    pub fn display(self, linear: [f32; 3], exposure_ev: f32) -> [f32; 3] {
        let c = Vec3::from(linear).max(Vec3::ZERO) * exposure_ev.exp2();
        let c = if c.is_finite() { c } else { Vec3::ZERO };
        match self {
            Tonemap::Aces => aces(c),
            Tonemap::Agx => agx(c),
            Tonemap::None => c.map(srgb_encode),
        }
        .to_array()
    }

    /// As [`Tonemap::display`], quantised to 8 bits.
    pub fn display8(self, linear: [f32; 3], exposure_ev: f32) -> [u8; 3] {
        self.display(linear, exposure_ev)
            .map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn black_stays_black_and_brightness_is_monotonic() {
        for t in [Tonemap::Aces, Tonemap::Agx, Tonemap::None] {
            let black = t.display([0.0; 3], 0.0);
            assert!(black.iter().all(|&x| x < 0.01), "{t:?}: {black:?}");
            let mut last = -1.0;
            for i in 0..200 {
                let x = 0.001 * 1.06f32.powi(i);
                let y = t.display([x; 3], 0.0)[1];
                assert!(y >= last - 1e-6, "{t:?} not monotonic at {x}");
                last = y;
            }
        }
    }

    #[test]
    fn tone_mappers_roll_off_highlights_that_clipping_loses() {
        // 4 and 16 are both white when clipped; a tone mapper keeps them apart.
        for t in [Tonemap::Aces, Tonemap::Agx] {
            let (a, b) = (t.display([4.0; 3], 0.0)[0], t.display([16.0; 3], 0.0)[0]);
            assert!(a < b && b <= 1.0, "{t:?}: {a} {b}");
            // Mid grey lands in the middle of the display range.
            let g = t.display([0.18; 3], 0.0)[0];
            assert!((0.3..0.6).contains(&g), "{t:?}: 18% grey at {g}");
        }
        assert_eq!(Tonemap::None.display8([4.0; 3], 0.0), [255; 3]);
        // Exposure is a power of two on the input.
        let a = Tonemap::None.display([0.1; 3], 1.0);
        let b = Tonemap::None.display([0.2; 3], 0.0);
        assert!((a[0] - b[0]).abs() < 1e-6);
    }
}
