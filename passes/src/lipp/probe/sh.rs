//! Spherical harmonics projection of the environment for `env.sh`
//! (Ramamoorthi and Hanrahan 2001), computed at upload on the CPU.

use glam::Vec3;
use rayon::prelude::*;
use strandgraph_assets::loaders::envmap::{self, EnvMap};

/// The real L2 SH basis at unit `d` in Ramamoorthi and Hanrahan's order
/// (L00; L1−1 y, L10 z, L11 x; L2−2 xy, L2−1 yz, L20, L21 xz, L22), the
/// order `shade::sh_irradiance` reads.
pub fn sh_basis(d: Vec3) -> [f32; 9] {
    let (x, y, z) = (d.x, d.y, d.z);
    [
        0.282_095,
        0.488_603 * y,
        0.488_603 * z,
        0.488_603 * x,
        1.092_548 * x * y,
        1.092_548 * y * z,
        0.315_392 * (3.0 * z * z - 1.0),
        1.092_548 * x * z,
        0.546_274 * (x * x - y * y),
    ]
}

/// L_lm = Σ L(ω) Y_lm(ω) ΔΩ over the map's texels, ΔΩ the texel's exact
/// solid angle, times `scale`.
pub fn project_sh(map: &EnvMap, scale: [f32; 3]) -> [[f32; 3]; 9] {
    let (w, h) = (map.width, map.height);
    let rows: Vec<[[f64; 3]; 9]> = (0..h)
        .into_par_iter()
        .map(|y| {
            let d_omega = f64::from(envmap::texel_solid_angle(w, h, y));
            let mut acc = [[0f64; 3]; 9];
            for x in 0..w {
                let c = map.texel(x, y);
                let basis = sh_basis(envmap::texel_direction(w, h, x, y));
                for (a, b) in acc.iter_mut().zip(basis) {
                    for k in 0..3 {
                        a[k] += f64::from(c[k]) * f64::from(b) * d_omega;
                    }
                }
            }
            acc
        })
        .collect();
    std::array::from_fn(|i| {
        std::array::from_fn(|k| (rows.iter().map(|r| r[i][k]).sum::<f64>() as f32) * scale[k])
    })
}

#[cfg(test)]
mod tests {
    use super::super::{HEIGHT, PI, WIDTH};
    use super::*;

    #[test]
    fn constant_environment_projects_to_l00_only() {
        let c = [0.5, 1.0, 2.0];
        let sh = project_sh(&EnvMap::constant(WIDTH, HEIGHT, [1.0; 3]), c);
        let l00 = (4.0 * PI).sqrt();
        for k in 0..3 {
            assert!((sh[0][k] - c[k] * l00).abs() < 1e-5 * l00 * c[k], "{sh:?}");
            // The midpoint rule leaves O(1/rows²) in band 2.
            assert!(
                sh[1..].iter().all(|x| x[k].abs() < 1e-3 * l00 * c[k]),
                "{sh:?}"
            );
        }
        // The shade pass's irradiance of it: π c.
        let e = crate::lipp::shade::sh_irradiance(&sh, [0.0, 1.0, 0.0]);
        assert!((e[2] - 2.0 * PI).abs() < 1e-3, "{e:?}");
    }

    #[test]
    fn clamped_cosine_environment_matches_the_analytic_coefficients() {
        // L(ω) = max(ω·z, 0): L00 = √π / 2, L10 = √(π/3), L20 = √(5π) / 8
        // (Ramamoorthi and Hanrahan 2001, the Â_l of the clamped cosine over
        // √(4π / (2l + 1))), all other coefficients zero.
        let map = EnvMap::from_fn(512, 256, |d| [d.z.max(0.0); 3]);
        let sh = project_sh(&map, [1.0; 3]);
        let want = [
            PI.sqrt() / 2.0,
            0.0,
            (PI / 3.0).sqrt(),
            0.0,
            0.0,
            0.0,
            (5.0 * PI).sqrt() / 8.0,
            0.0,
            0.0,
        ];
        for (i, (got, want)) in sh.iter().zip(want).enumerate() {
            assert!(
                (got[0] - want).abs() < 2e-3,
                "L[{i}] = {} vs {want}",
                got[0]
            );
        }
        // Rotated to +x: only L00, L11 (x) and the band-2 terms of x².
        let sh = project_sh(&EnvMap::from_fn(512, 256, |d| [d.x.max(0.0); 3]), [1.0; 3]);
        assert!((sh[3][0] - (PI / 3.0).sqrt()).abs() < 2e-3, "{sh:?}");
        assert!(sh[1][0].abs() < 2e-3 && sh[2][0].abs() < 2e-3, "{sh:?}");
    }
}
