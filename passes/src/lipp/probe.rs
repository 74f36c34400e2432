//! Probe lighting for `lipp.shade` (Lipp §3.4: "we use the standard
//! approach of pre-filtered environment maps for specular components (the
//! single scattering hair shading model), and spherical harmonics expansion
//! for more diffuse contributions"): what upload computes from the scene's
//! environment, and the lookup the shader mirrors (`shaders/lipp/probe.wgsl`).
//!
//! **`env.prefiltered`** (Imported, [`BYTES`] = 178,176 B, fixed layout, no
//! header): [`LEVELS`] = 6 latitude-longitude levels, level k is
//! max(128 >> k, 16) × max(64 >> k, 8) texels (128×64, 64×32, 32×16, then
//! 16×8 three times), rgba32f (a = 1), row-major with row 0 at +y, levels
//! back to back from level 0 (texel offsets 0, 8192, 10240, 10752, 10880,
//! 11008; 11,136 texels). The lat-long convention is
//! `strandgraph_assets::loaders::envmap`'s (u = 0.5 looks down −z, u = 0.75
//! down +x). Level k is prefiltered for GGX roughness α_k = r_k², r_k =
//! k / 5 (the perceptual-roughness-linear mip mapping of Karis 2013); level 0
//! (α = 0, a mirror) is the input map resampled to 128 × 64.
//!
//! The prefilter is Karis 2013 ("Real Shading in Unreal Engine 4", the
//! first half of the split sum): with N = V = R assumed, each texel of
//! direction N averages the source over GGX importance samples L of the
//! half vector, weighted by N·L. Each sample reads a box-filtered mip of the
//! source chosen from its pdf (filtered importance sampling, Colbert and
//! Křivánek 2007, "GPU-Based Importance Sampling", GPU Gems 3 ch. 20), so
//! 64 to 256 samples per texel give a noise-free result.
//!
//! **`env.sh`**: the map projected to 9 L2 SH radiance coefficients
//! (Ramamoorthi and Hanrahan 2001) with exact per-row solid angles.
//!
//! The map is scaled by the environment's `color × intensity` (a white map
//! at intensity 1 is the file's radiance). Without a map, the constant
//! colour fills only L00 and every prefiltered texel; without an
//! environment, both are zero.

use super::chiang::{Material, reflected_albedo};
use super::{dot, normalize, scale, sub};
use crate::kernel::Words;
use glam::Vec3;
use rayon::prelude::*;
use strandgraph_assets::Scene;
use strandgraph_assets::loaders::envmap::{self, EnvMap};

/// Resource name.
pub const PREFILTERED: &str = "env.prefiltered";
/// Prefiltered levels (level 0 = mirror, level 5 = α 1).
pub const LEVELS: u32 = 6;
/// Level 0's size.
pub const WIDTH: u32 = 128;
pub const HEIGHT: u32 = 64;
/// Texels of all levels.
pub const TEXELS: u32 = level_offset(LEVELS);
/// `env.prefiltered`'s size in bytes (rgba32f texels).
pub const BYTES: u64 = TEXELS as u64 * 16;
/// GGX samples per prefiltered texel of the rough levels (fewer for the
/// narrow lobes of levels 1 and 2).
pub const SAMPLES: u32 = 256;

const PI: f32 = std::f32::consts::PI;

/// The smallest level's size: rougher levels stop halving here, since a
/// wide lobe still needs ~20° texels to reconstruct bilinearly (4 × 2
/// texels lost 10% of a spot's energy at α = 1).
pub const MIN_WIDTH: u32 = 16;
pub const MIN_HEIGHT: u32 = 8;

/// Level k's (width, height).
pub const fn level_size(k: u32) -> (u32, u32) {
    let (w, h) = (WIDTH >> k, HEIGHT >> k);
    (
        if w > MIN_WIDTH { w } else { MIN_WIDTH },
        if h > MIN_HEIGHT { h } else { MIN_HEIGHT },
    )
}

/// Level k's first texel.
pub const fn level_offset(k: u32) -> u32 {
    let mut o = 0;
    let mut i = 0;
    while i < k {
        let (w, h) = level_size(i);
        o += w * h;
        i += 1;
    }
    o
}

/// GGX α of level k: r² with r = k / (LEVELS − 1).
pub fn level_alpha(k: u32) -> f32 {
    let r = k as f32 / (LEVELS - 1) as f32;
    r * r
}

/// The fractional level of GGX roughness α (inverse of [`level_alpha`]).
pub fn alpha_lod(alpha: f32) -> f32 {
    alpha.clamp(0.0, 1.0).sqrt() * (LEVELS - 1) as f32
}

// ---------------------------------------------------------------------------
// The lookup (shaders/lipp/probe.wgsl ports these operation for operation).

/// Lat-long (u, v) of unit direction `d` (`envmap::uv`).
pub fn latlong_uv(d: [f32; 3]) -> (f32, f32) {
    let u = 0.5 + d[0].atan2(-d[2]) / (2.0 * PI);
    let v = d[1].clamp(-1.0, 1.0).acos() / PI;
    (u, v)
}

/// Bilinear texel coordinates at (u, v) of a w × h lat-long grid: the four
/// (x, y) (x wraps around, y clamps at the poles) and the fractions.
fn bilinear_taps(u: f32, v: f32, w: u32, h: u32) -> ([(u32, u32); 4], f32, f32) {
    let fx = u * w as f32 - 0.5;
    let fy = v * h as f32 - 0.5;
    let (x0, y0) = (fx.floor(), fy.floor());
    let (tx, ty) = (fx - x0, fy - y0);
    let (x0, y0) = (x0 as i32, y0 as i32);
    let xa = x0.rem_euclid(w as i32) as u32;
    let xb = (x0 + 1).rem_euclid(w as i32) as u32;
    let ya = y0.clamp(0, h as i32 - 1) as u32;
    let yb = (y0 + 1).clamp(0, h as i32 - 1) as u32;
    ([(xa, ya), (xb, ya), (xa, yb), (xb, yb)], tx, ty)
}

fn blend(c: [[f32; 3]; 4], tx: f32, ty: f32) -> [f32; 3] {
    std::array::from_fn(|k| {
        let top = c[0][k] + (c[1][k] - c[0][k]) * tx;
        let bottom = c[2][k] + (c[3][k] - c[2][k]) * tx;
        top + (bottom - top) * ty
    })
}

/// Bilinear radiance of prefiltered level `k` in direction `d`.
pub fn sample_level(w: &Words<'_>, k: u32, d: [f32; 3]) -> [f32; 3] {
    let (lw, lh) = level_size(k);
    let (u, v) = latlong_uv(d);
    let (taps, tx, ty) = bilinear_taps(u, v, lw, lh);
    let c = taps.map(|(x, y)| {
        let t = w.load_vec4((level_offset(k) + y * lw + x) as usize);
        [t[0], t[1], t[2]]
    });
    blend(c, tx, ty)
}

/// Prefiltered radiance around `d` for GGX roughness α: bilinear in the two
/// nearest levels, linear between them.
pub fn sample(w: &Words<'_>, d: [f32; 3], alpha: f32) -> [f32; 3] {
    let lod = alpha_lod(alpha);
    let k0 = (lod.floor() as u32).min(LEVELS - 1);
    let k1 = (k0 + 1).min(LEVELS - 1);
    let t = lod - k0 as f32;
    let (a, b) = (sample_level(w, k0, d), sample_level(w, k1, d));
    std::array::from_fn(|k| a[k] + (b[k] - a[k]) * t)
}

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
/// [`super::chiang::chiang`]:
///
/// - **Weight**: R's and TRT's directional albedo at θ_o, pbrt-v4's A_p
///   averaged over the fibre offset h ([`super::chiang::reflected_albedo`]).
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
    color: [f32; 3],
    roughness: f32,
) -> SpecularLobe {
    let sin_o = dot(t, v).clamp(-1.0, 1.0);
    let bm = roughness.clamp(0.02, 1.0);
    let v0 = {
        let x = 0.726 * bm + 0.812 * bm * bm + 3.7 * bm.powi(20);
        x * x
    };
    let alpha = 2.0f32.to_radians();
    let (w_r, a_trt) = reflected_albedo(sin_o, &Material { color, roughness });
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
    color: [f32; 3],
    roughness: f32,
) -> [f32; 3] {
    let lobe = specular_lobe(t, v, n, color, roughness);
    let l = sample(w, lobe.direction, lobe.alpha);
    std::array::from_fn(|k| l[k] * lobe.weight[k])
}

// ---------------------------------------------------------------------------
// Upload: prefiltering and SH projection (CPU only).

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

/// The levels as `env.prefiltered`'s words.
pub fn words(levels: &[Level]) -> Vec<u32> {
    debug_assert_eq!(levels.len(), LEVELS as usize);
    levels
        .iter()
        .flat_map(|l| &l.texels)
        .flat_map(|c| [c[0], c[1], c[2], 1.0])
        .map(f32::to_bits)
        .collect()
}

/// The environment's radiance scale: `color × intensity`.
fn env_scale(scene: &Scene) -> Option<[f32; 3]> {
    let e = scene.desc.environment.as_ref()?;
    Some(e.color.map(|c| c * e.intensity))
}

/// `env.prefiltered` for a scene (see the module comment).
pub fn prefiltered_words(scene: &Scene) -> Vec<u32> {
    let constant = |c: [f32; 3]| {
        (0..LEVELS)
            .map(|k| {
                let (w, h) = level_size(k);
                Level {
                    width: w,
                    height: h,
                    texels: vec![c; (w * h) as usize],
                }
            })
            .collect::<Vec<_>>()
    };
    let levels = match (env_scale(scene), &scene.environment_map) {
        (Some(s), Some(map)) => prefilter(map, s),
        (Some(s), None) => constant(s),
        (None, _) => constant([0.0; 3]),
    };
    words(&levels)
}

/// `env.sh`: 9 × (rgb, pad) L2 SH radiance coefficients for a scene.
pub fn sh_words(scene: &Scene) -> Vec<u32> {
    let mut sh = [[0f32; 3]; 9];
    match (env_scale(scene), &scene.environment_map) {
        (Some(s), Some(map)) => sh = project_sh(map, s),
        // A constant radiance c has only L00 = c · 4π · Y00.
        (Some(s), None) => sh[0] = s.map(|c| c * 4.0 * PI * 0.282_095),
        (None, _) => {}
    }
    sh.iter()
        .flat_map(|c| [c[0], c[1], c[2], 0.0])
        .map(f32::to_bits)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU32, AtomicU64};

    fn atomics(words: &[u32]) -> Vec<AtomicU32> {
        words.iter().map(|&w| AtomicU32::new(w)).collect()
    }

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
    fn layout_is_fixed_and_documented() {
        assert_eq!(TEXELS, 11_136);
        assert_eq!(BYTES, 178_176);
        assert_eq!(
            (0..=LEVELS).map(level_offset).collect::<Vec<_>>(),
            [0, 8192, 10240, 10752, 10880, 11008, 11136]
        );
        assert_eq!((level_size(3), level_size(5)), ((16, 8), (16, 8)));
        for k in 0..LEVELS {
            assert!((alpha_lod(level_alpha(k)) - k as f32).abs() < 1e-5);
        }
    }

    #[test]
    fn lookup_convention_matches_the_loader() {
        for (u, v) in [(0.1f32, 0.2f32), (0.5, 0.5), (0.9, 0.7), (0.26, 0.95)] {
            let d = envmap::direction(u, v).to_array();
            let (u2, v2) = latlong_uv(d);
            assert!((u - u2).abs() < 1e-5 && (v - v2).abs() < 1e-5);
        }
    }

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
        let e = super::super::shade::sh_irradiance(&sh, [0.0, 1.0, 0.0]);
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

    #[test]
    fn lookup_reads_texels_and_blends_levels() {
        let levels: Vec<Level> = (0..LEVELS)
            .map(|k| {
                let (w, h) = level_size(k);
                let mut texels = vec![[k as f32; 3]; (w * h) as usize];
                if k == 0 {
                    texels[(10 * w + 33) as usize] = [7.0, 8.0, 9.0];
                }
                Level {
                    width: w,
                    height: h,
                    texels,
                }
            })
            .collect();
        let words = words(&levels);
        assert_eq!(words.len() as u64 * 4, BYTES);
        let (a, oob) = (atomics(&words), AtomicU64::new(0));
        let w = Words::new(&a, &oob);
        let d = envmap::texel_direction(WIDTH, HEIGHT, 33, 10).to_array();
        let got = sample(&w, d, 0.0);
        assert!((got[1] - 8.0).abs() < 1e-3, "{got:?}");
        // Halfway between levels 2 and 3 (away from the marked texel).
        let r = 2.5 / (LEVELS - 1) as f32;
        let got = sample(&w, [0.0, 0.0, 1.0], r * r);
        assert!((got[0] - 2.5).abs() < 1e-4, "{got:?}");
        // Seams: straight up, straight down, and across u = 0.
        for d in [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]] {
            assert!((sample(&w, d, 1.0)[0] - 5.0).abs() < 1e-5);
        }
        assert_eq!(oob.load(std::sync::atomic::Ordering::Relaxed), 0);
    }

    #[test]
    fn the_stand_in_lobe_mirrors_the_view_and_widens_with_roughness() {
        let t = [0.0, 1.0, 0.0];
        let v = normalize([0.0, 0.3, 1.0]);
        let n = view_facing_normal(t, v);
        assert!((dot(n, [0.0, 0.0, 1.0]) - 1.0).abs() < 1e-6);
        let dark = [0.02, 0.015, 0.01];
        let lobe = specular_lobe(t, v, n, dark, 0.3);
        // The lobe sits on the specular cone (sin θ_l = −sin θ_o) shifted by
        // the A-weighted mean of R's +2α and TRT's −4α; dark hair: nearly R's.
        let sin_o = dot(t, v);
        let shift = dot(lobe.direction, t) + sin_o;
        let (f, trt) = reflected_albedo(
            sin_o,
            &Material {
                color: dark,
                roughness: 0.3,
            },
        );
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
        let blond = specular_lobe(t, v, n, [0.8, 0.6, 0.35], 0.3);
        assert!(blond.weight[0] > blond.weight[2] && blond.weight[2] > lobe.weight[2]);
        assert!(dot(blond.direction, t) < dot(lobe.direction, t));
        assert!(blond.alpha > lobe.alpha);
        // Rougher hair, wider lobe; capped at α = 1.
        let rough = specular_lobe(t, v, n, dark, 0.6);
        assert!(rough.alpha > lobe.alpha && specular_lobe(t, v, n, dark, 1.0).alpha <= 1.0);
    }

    #[test]
    fn uniform_radiance_returns_the_attenuations() {
        let c = [0.3, 0.4, 0.5];
        let levels: Vec<Level> = (0..LEVELS)
            .map(|k| {
                let (w, h) = level_size(k);
                Level {
                    width: w,
                    height: h,
                    texels: vec![c; (w * h) as usize],
                }
            })
            .collect();
        let (a, oob) = (atomics(&words(&levels)), AtomicU64::new(0));
        let w = Words::new(&a, &oob);
        let (t, v) = ([1.0, 0.0, 0.0], normalize([0.5, 0.2, 1.0]));
        let n = view_facing_normal(t, v);
        let lobe = specular_lobe(t, v, n, [0.5, 0.4, 0.3], 0.35);
        let s = specular(&w, t, v, n, [0.5, 0.4, 0.3], 0.35);
        for k in 0..3 {
            assert!((s[k] - c[k] * lobe.weight[k]).abs() < 1e-6, "{s:?}");
        }
    }
}
