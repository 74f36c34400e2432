//! The probe lookup: bilinear reads of the prefiltered lat-long levels and
//! the blend between levels. `shaders/lipp/probe.wgsl` ports these
//! operation for operation.

use super::{LEVELS, PI, alpha_lod, level_offset, level_size};
use crate::kernel::Words;

/// Lat-long (u, v) of unit direction `d` (`envmap::uv`).
pub fn latlong_uv(d: [f32; 3]) -> (f32, f32) {
    let u = 0.5 + d[0].atan2(-d[2]) / (2.0 * PI);
    let v = d[1].clamp(-1.0, 1.0).acos() / PI;
    (u, v)
}

/// Bilinear texel coordinates at (u, v) of a w × h lat-long grid: the four
/// (x, y) (x wraps around, y clamps at the poles) and the fractions. `w` is
/// a power of two (every level's is, `level_widths_are_powers_of_two`), so x
/// wraps with a mask, as the WGSL does: there an integer remainder by a
/// width the compiler does not know is a long instruction sequence.
pub(super) fn bilinear_taps(u: f32, v: f32, w: u32, h: u32) -> ([(u32, u32); 4], f32, f32) {
    let fx = u * w as f32 - 0.5;
    let fy = v * h as f32 - 0.5;
    let (x0, y0) = (fx.floor(), fy.floor());
    let (tx, ty) = (fx - x0, fy - y0);
    let (x0, y0) = (x0 as i32, y0 as i32);
    // x0 >= -1 (u >= 0): -1 wraps to w - 1, as rem_euclid would.
    let xa = (x0 as u32) & (w - 1);
    let xb = ((x0 + 1) as u32) & (w - 1);
    let ya = y0.clamp(0, h as i32 - 1) as u32;
    let yb = (y0 + 1).clamp(0, h as i32 - 1) as u32;
    ([(xa, ya), (xb, ya), (xa, yb), (xb, yb)], tx, ty)
}

/// The four taps' colours (in [`bilinear_taps`]' order) blended by the
/// fractions.
pub(super) fn blend(c: [[f32; 3]; 4], tx: f32, ty: f32) -> [f32; 3] {
    std::array::from_fn(|k| {
        let top = c[0][k] + (c[1][k] - c[0][k]) * tx;
        let bottom = c[2][k] + (c[3][k] - c[2][k]) * tx;
        top + (bottom - top) * ty
    })
}

/// Bilinear radiance of prefiltered level `k` at lat-long (u, v).
pub fn sample_level(w: &Words<'_>, k: u32, (u, v): (f32, f32)) -> [f32; 3] {
    let (lw, lh) = level_size(k);
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
    let uv = latlong_uv(d);
    let (a, b) = (sample_level(w, k0, uv), sample_level(w, k1, uv));
    std::array::from_fn(|k| a[k] + (b[k] - a[k]) * t)
}

#[cfg(test)]
mod tests {
    use super::super::{BYTES, HEIGHT, Level, WIDTH, atomics, words};
    use super::*;
    use std::sync::atomic::AtomicU64;
    use strandgraph_assets::loaders::envmap;

    /// bilinear_taps wraps x with a mask (and the WGSL with it).
    #[test]
    fn level_widths_are_powers_of_two() {
        for k in 0..LEVELS {
            assert!(level_size(k).0.is_power_of_two(), "level {k}");
        }
        // Across the seam both ways, as rem_euclid wraps.
        let (taps, _, _) = bilinear_taps(0.0, 0.5, 16, 8);
        assert_eq!((taps[0].0, taps[1].0), (15, 0));
        let (taps, _, _) = bilinear_taps(0.999, 0.5, 16, 8);
        assert_eq!((taps[0].0, taps[1].0), (15, 0));
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
}
