//! GGX prefiltering of the environment for `env.prefiltered` (Karis 2013's
//! PrefilterEnvMap with filtered importance sampling, Colbert and Křivánek
//! 2007), computed at upload on the CPU.

use super::lookup::{bilinear_taps, blend};
use super::{HEIGHT, LEVELS, PI, SAMPLES, WIDTH, level_alpha, level_size};
use glam::Vec3;
use rayon::prelude::*;
use strandgraph_assets::loaders::envmap::{self, EnvMap};

/// A lat-long image: w × h rgb texels, row 0 at +y.
#[derive(Debug, Clone, PartialEq)]
pub struct Level {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 3]>,
}

impl Level {
    fn at(&self, x: u32, y: u32) -> [f32; 3] {
        self.texels[(y * self.width + x) as usize]
    }

    /// Bilinear radiance in direction `d`.
    pub fn bilinear(&self, d: Vec3) -> [f32; 3] {
        let (u, v) = envmap::uv(d);
        self.bilinear_uv(u, v)
    }

    fn bilinear_uv(&self, u: f32, v: f32) -> [f32; 3] {
        let (taps, tx, ty) = bilinear_taps(u, v, self.width, self.height);
        blend(taps.map(|(x, y)| self.at(x, y)), tx, ty)
    }

    /// Half the size in each direction, each texel the solid-angle-weighted
    /// mean of its four (energy preserving).
    fn halved(&self) -> Level {
        let (w, h) = ((self.width / 2).max(1), (self.height / 2).max(1));
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let mut sum = [0.0f32; 3];
                let mut weight = 0.0;
                for sy in [2 * y, 2 * y + 1] {
                    let sy = sy.min(self.height - 1);
                    let dw = envmap::texel_solid_angle(self.width, self.height, sy);
                    for sx in [2 * x, 2 * x + 1] {
                        let c = self.at(sx.min(self.width - 1), sy);
                        for k in 0..3 {
                            sum[k] += c[k] * dw;
                        }
                        weight += dw;
                    }
                }
                sum.map(|s| s / weight)
            })
            .collect();
        Level {
            width: w,
            height: h,
            texels,
        }
    }
}

/// `map` scaled by `scale` at w × h: each destination texel averages an
/// n × n grid of bilinear source samples (n = source texels per destination
/// texel, so an integer downscale is an exact box filter).
pub fn resample(map: &EnvMap, w: u32, h: u32, scale: [f32; 3]) -> Level {
    let src = Level {
        width: map.width,
        height: map.height,
        texels: map.texels.clone(),
    };
    let n = map.width.div_ceil(w).max(map.height.div_ceil(h)).max(1);
    let texels = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let mut sum = [0.0f32; 3];
            for j in 0..n {
                for i in 0..n {
                    let u = (x as f32 + (i as f32 + 0.5) / n as f32) / w as f32;
                    let v = (y as f32 + (j as f32 + 0.5) / n as f32) / h as f32;
                    let c = src.bilinear_uv(u, v);
                    for k in 0..3 {
                        sum[k] += c[k];
                    }
                }
            }
            let inv = 1.0 / (n * n) as f32;
            std::array::from_fn(|k| sum[k] * inv * scale[k])
        })
        .collect();
    Level {
        width: w,
        height: h,
        texels,
    }
}

/// Van der Corput / Hammersley point i of n (Karis 2013).
fn hammersley(i: u32, n: u32) -> (f32, f32) {
    (
        i as f32 / n as f32,
        i.reverse_bits() as f32 * 2.328_306_4e-10,
    )
}

/// Karis 2013, ImportanceSampleGGX: a half vector for GGX α, in the frame
/// of the normal (z).
fn importance_sample_ggx(xi: (f32, f32), alpha: f32) -> Vec3 {
    let a2 = alpha * alpha;
    let phi = 2.0 * PI * xi.0;
    let cos_t = ((1.0 - xi.1) / (1.0 + (a2 - 1.0) * xi.1)).sqrt();
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// GGX D(n·h).
fn ggx_d(n_h: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = n_h * n_h * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// One prefilter sample in the normal's frame: the light direction, its
/// N·L weight and the source mip it reads.
#[derive(Debug, Clone, Copy)]
struct Tap {
    l: Vec3,
    n_l: f32,
    lod: f32,
}

/// Samples per texel of level k: a narrow lobe reads fine mips and needs
/// fewer (the filtered importance sampling keeps each smooth).
fn samples_of(k: u32) -> u32 {
    match k {
        0 => 1,
        1 => 64,
        2 => 128,
        _ => SAMPLES,
    }
}

/// Karis 2013, PrefilterEnvMap's samples for GGX α with N = V = R, in the
/// normal's frame (they are the same for every texel): L = 2 (N·H) H − N,
/// those below the horizon dropped. Each reads the source mip its pdf asks
/// for (Colbert and Křivánek 2007: lod = ½ log2(Ω_s / Ω_p) + 1, Ω_s =
/// 1 / (n pdf), Ω_p = a level-0 texel's mean solid angle).
fn taps(alpha: f32, n: u32, omega_p: f32, mips: usize) -> Vec<Tap> {
    (0..n)
        .filter_map(|i| {
            let h = importance_sample_ggx(hammersley(i, n), alpha);
            let n_h = h.z;
            let l = h * (2.0 * n_h) - Vec3::Z;
            (l.z > 0.0).then(|| {
                // pdf(l) = D(n·h) (n·h) / (4 v·h), and v·h = n·h with V = N.
                let pdf = ggx_d(n_h, alpha) / 4.0;
                let omega_s = 1.0 / (n as f32 * pdf + 1e-6);
                let lod = (0.5 * (omega_s / omega_p).log2() + 1.0).clamp(0.0, (mips - 1) as f32);
                Tap { l, n_l: l.z, lod }
            })
        })
        .collect()
}

/// The N·L-weighted average of the mip chain over `taps` around `n`.
fn prefilter_texel(mips: &[Level], n: Vec3, taps: &[Tap]) -> [f32; 3] {
    let up = if n.z.abs() < 0.999 { Vec3::Z } else { Vec3::X };
    let tx = up.cross(n).normalize();
    let ty = n.cross(tx);
    let mut sum = [0.0f32; 3];
    let mut weight = 0.0;
    for tap in taps {
        let l = tx * tap.l.x + ty * tap.l.y + n * tap.l.z;
        let m0 = tap.lod.floor() as usize;
        let m1 = (m0 + 1).min(mips.len() - 1);
        let t = tap.lod - m0 as f32;
        let (a, b) = (mips[m0].bilinear(l), mips[m1].bilinear(l));
        for k in 0..3 {
            sum[k] += (a[k] + (b[k] - a[k]) * t) * tap.n_l;
        }
        weight += tap.n_l;
    }
    sum.map(|s| s / weight.max(1e-12))
}

/// The [`LEVELS`] prefiltered levels of `map` scaled by `scale`.
pub fn prefilter(map: &EnvMap, scale: [f32; 3]) -> Vec<Level> {
    let _span = tracing::info_span!(
        "prefilter_environment",
        width = map.width,
        height = map.height
    )
    .entered();
    let start = std::time::Instant::now();
    let level0 = resample(map, WIDTH, HEIGHT, scale);
    let mut mips = vec![level0];
    while mips.last().is_some_and(|m| m.height > 1) {
        let next = mips
            .last()
            .map(Level::halved)
            .unwrap_or_else(|| unreachable!());
        mips.push(next);
    }
    let mut levels = vec![mips[0].clone()];
    for k in 1..LEVELS {
        let (w, h) = level_size(k);
        let omega_p = 4.0 * PI / (WIDTH * HEIGHT) as f32;
        let taps = taps(level_alpha(k), samples_of(k), omega_p, mips.len());
        let texels = (0..h)
            .into_par_iter()
            .flat_map_iter(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| prefilter_texel(&mips, envmap::texel_direction(w, h, x, y), &taps))
            .collect();
        levels.push(Level {
            width: w,
            height: h,
            texels,
        });
    }
    tracing::info!(
        ms = start.elapsed().as_secs_f64() * 1e3,
        "environment map prefiltered"
    );
    levels
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Solid-angle integral of one channel of a lat-long level as the
    /// shader reconstructs it (bilinear), on a 256 x 128 grid.
    fn integral(l: &Level, k: usize) -> f64 {
        let (w, h) = (256, 128);
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                f64::from(l.bilinear(envmap::texel_direction(w, h, x, y))[k])
                    * f64::from(envmap::texel_solid_angle(w, h, y))
            })
            .sum()
    }
    #[test]
    fn constant_environment_stays_constant_at_every_level() {
        let levels = prefilter(
            &EnvMap::constant(256, 128, [0.25, 0.5, 4.0]),
            [2.0, 1.0, 0.5],
        );
        assert_eq!(levels.len(), LEVELS as usize);
        for (k, l) in levels.iter().enumerate() {
            assert_eq!((l.width, l.height), level_size(k as u32));
            for t in &l.texels {
                for (c, want) in t.iter().zip([0.5, 0.5, 2.0]) {
                    assert!((c - want).abs() < 1e-5 * want, "level {k}: {t:?}");
                }
            }
        }
    }

    #[test]
    fn level_zero_is_the_input_and_a_bright_spot_spreads_with_roughness() {
        // A 128 x 64 map, dim background and one bright texel above the horizon.
        let spot = (40u32, 20u32);
        let map = EnvMap::from_fn(WIDTH, HEIGHT, |_| [0.01; 3]);
        let mut map = map;
        map.texels[(spot.1 * WIDTH + spot.0) as usize] = [1000.0; 3];
        let levels = prefilter(&map, [1.0; 3]);
        assert_eq!(levels[0].texels, map.texels, "level 0 is the mirror");
        let centre = envmap::texel_direction(WIDTH, HEIGHT, spot.0, spot.1);
        // Radiance-weighted mean angular distance from the spot.
        let spread = |l: &Level| {
            let (mut sum, mut weight) = (0.0f64, 0.0f64);
            for y in 0..l.height {
                let dw = f64::from(envmap::texel_solid_angle(l.width, l.height, y));
                for x in 0..l.width {
                    let d = envmap::texel_direction(l.width, l.height, x, y);
                    let e = f64::from(l.at(x, y)[0] - 0.01).max(0.0) * dw;
                    sum += e * f64::from(d.dot(centre).clamp(-1.0, 1.0).acos());
                    weight += e;
                }
            }
            sum / weight
        };
        let spreads: Vec<f64> = levels.iter().map(spread).collect();
        assert!(
            spreads.windows(2).all(|w| w[1] > w[0] * 1.1),
            "spread per level {spreads:?}"
        );
        // The peak falls level by level and stays where the spot is.
        let peaks: Vec<f32> = levels.iter().map(|l| l.bilinear(centre)[0]).collect();
        assert!(peaks.windows(2).all(|w| w[1] < w[0]), "{peaks:?}");
        // A convolution with a normalised, symmetric kernel keeps the energy.
        let e0 = integral(&levels[0], 0);
        for (k, l) in levels.iter().enumerate() {
            let e = integral(l, 0);
            assert!((e / e0 - 1.0).abs() < 0.03, "level {k}: {e} vs {e0}");
        }
    }

    #[test]
    fn larger_maps_are_box_filtered_down() {
        // 512 x 256 with a 4 x 4 block of 16: one level-0 texel of 16, energy kept.
        let mut map = EnvMap::constant(512, 256, [0.0; 3]);
        for y in 80..84 {
            for x in 200..204 {
                map.texels[y * 512 + x] = [16.0; 3];
            }
        }
        let l = resample(&map, WIDTH, HEIGHT, [1.0; 3]);
        assert_eq!(l.at(50, 20), [16.0; 3]);
        assert_eq!(l.texels.iter().filter(|t| t[0] > 0.0).count(), 1);
    }
}
