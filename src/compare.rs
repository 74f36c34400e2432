//! Comparing rendered images across backends with NVIDIA's FLIP (Andersson
//! et al. 2020, through the `nv-flip` crate): a perceptual per-pixel error
//! in [0, 1], pooled to a mean. The differential tests and
//! `render --backend all` use it on the sRGB pictures they write.

use image::{RgbImage, RgbaImage};

/// How two pictures of the same size differ.
#[derive(Debug, Clone)]
pub struct ImageDiff {
    /// Mean FLIP error over all pixels (0: identical).
    pub mean: f32,
    /// The largest per-pixel FLIP error, and where.
    pub max: f32,
    pub max_at: (u32, u32),
    /// The FLIP error map in the magma colour map, to look at.
    pub error_map: RgbImage,
    errors: Vec<f32>,
}

impl ImageDiff {
    /// Pixels whose FLIP error exceeds `bound`.
    pub fn pixels_over(&self, bound: f32) -> usize {
        self.errors.iter().filter(|&&e| e > bound).count()
    }
}

fn rgb(img: &RgbaImage) -> nv_flip::FlipImageRgb8 {
    let data: Vec<u8> = img.pixels().flat_map(|p| [p[0], p[1], p[2]]).collect();
    nv_flip::FlipImageRgb8::with_data(img.width(), img.height(), &data)
}

/// Coverage error: the mean absolute difference of two coverage (alpha)
/// maps over the pixels where either has hair; 0 where neither has any,
/// `None` when the sizes differ.
pub fn coverage_error(reference: &[f32], test: &[f32]) -> Option<f32> {
    if reference.len() != test.len() {
        return None;
    }
    let (sum, n) = reference
        .iter()
        .zip(test)
        .filter(|(r, t)| **r > 0.0 || **t > 0.0)
        .fold((0.0f64, 0u64), |(s, n), (r, t)| {
            (s + f64::from((r - t).abs()), n + 1)
        });
    Some(if n == 0 { 0.0 } else { (sum / n as f64) as f32 })
}

/// A mean FLIP for tables: three significant digits, so the far view's
/// errors (hair on a few thousand pixels, means near 4e-4) stay as
/// comparable as the close view's.
pub fn flip_text(x: f64) -> String {
    if !(x.is_finite() && x > 0.0) {
        return format!("{x}");
    }
    let decimals = (2 - x.log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

/// FLIP of `test` against `reference` at the default 67 pixels per degree
/// (a 0.7 m viewing distance from a 24" 4K screen, FLIP's default).
/// `None` when the sizes differ.
pub fn flip(reference: &RgbaImage, test: &RgbaImage) -> Option<ImageDiff> {
    if reference.dimensions() != test.dimensions() || reference.width() == 0 {
        return None;
    }
    let map = nv_flip::flip(
        rgb(reference),
        rgb(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let errors = map.to_vec();
    let w = reference.width();
    let (i, max) = errors
        .iter()
        .copied()
        .enumerate()
        .fold(
            (0, 0.0f32),
            |(bi, bm), (i, e)| if e > bm { (i, e) } else { (bi, bm) },
        );
    let mean = nv_flip::FlipPool::from_image(&map).mean();
    let colours = map.apply_color_lut(&nv_flip::magma_lut());
    let error_map = RgbImage::from_raw(colours.width(), colours.height(), colours.to_vec())?;
    Some(ImageDiff {
        mean,
        max,
        max_at: (i as u32 % w, i as u32 / w),
        error_map,
        errors,
    })
}

/// How a sequence changes from frame to frame against its reference: the
/// artefacts a still image hides (flicker, popping, a filter's instability).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Temporal {
    /// Flicker: the mean over pixels and consecutive frame pairs of
    /// `|ΔY − ΔY_ref|`, `ΔY` a pixel's change of display luma (Rec. 709
    /// weights on the encoded values, 0..1) from one frame to the next. 0
    /// when the sequence changes exactly as the reference does, whatever
    /// its error in each frame.
    pub flicker: f32,
    /// The reference's own change, the mean `|ΔY_ref|`: the scale of the
    /// motion the flicker is measured against.
    pub reference_motion: f32,
}

fn luma(p: &image::Rgba<u8>) -> f32 {
    (0.2126 * f32::from(p[0]) + 0.7152 * f32::from(p[1]) + 0.0722 * f32::from(p[2])) / 255.0
}

/// [`Temporal`] of `frames` against `reference`, frame for frame; `None`
/// for fewer than two frames, different counts or different sizes.
pub fn temporal(frames: &[&RgbaImage], reference: &[&RgbaImage]) -> Option<Temporal> {
    if frames.len() < 2 || frames.len() != reference.len() {
        return None;
    }
    let size = frames[0].dimensions();
    if frames
        .iter()
        .chain(reference)
        .any(|f| f.dimensions() != size)
    {
        return None;
    }
    let (mut flicker, mut motion, mut n) = (0.0f64, 0.0f64, 0u64);
    for (t, r) in frames.windows(2).zip(reference.windows(2)) {
        let pixels = t[0].pixels().zip(t[1].pixels());
        for ((a, b), (ra, rb)) in pixels.zip(r[0].pixels().zip(r[1].pixels())) {
            let (change, reference_change) = (luma(b) - luma(a), luma(rb) - luma(ra));
            flicker += f64::from((change - reference_change).abs());
            motion += f64::from(reference_change.abs());
            n += 1;
        }
    }
    let n = n.max(1) as f64;
    Some(Temporal {
        flicker: (flicker / n) as f32,
        reference_motion: (motion / n) as f32,
    })
}

#[cfg(test)]
mod tests {
    use image::{Rgba, RgbaImage};

    fn grey(v: u8) -> RgbaImage {
        RgbaImage::from_pixel(4, 2, Rgba([v, v, v, 255]))
    }

    #[test]
    fn temporal_measures_change_against_the_reference() {
        let (a, b, c) = (grey(0), grey(51), grey(102));
        // A constant error in every frame is no flicker.
        let t = super::temporal(&[&b, &c], &[&a, &b]).unwrap();
        assert!(t.flicker.abs() < 1e-6, "{t:?}");
        assert!((t.reference_motion - 0.2).abs() < 1e-3, "{t:?}");
        // Still where the reference moves, then jumping: 0.2 both times.
        let t = super::temporal(&[&a, &a, &c], &[&a, &b, &c]).unwrap();
        assert!((t.flicker - 0.2).abs() < 1e-3, "{t:?}");
        assert!(super::temporal(&[&a], &[&a]).is_none());
        assert!(super::temporal(&[&a, &b], &[&a]).is_none());
        let small = RgbaImage::new(1, 1);
        assert!(super::temporal(&[&a, &small], &[&a, &b]).is_none());
    }

    #[test]
    fn flip_text_keeps_three_significant_digits() {
        assert_eq!(super::flip_text(0.031_73), "0.0317");
        assert_eq!(super::flip_text(0.000_404_4), "0.000404");
        assert_eq!(super::flip_text(0.0), "0");
    }

    #[test]
    fn coverage_error_counts_only_pixels_with_hair() {
        assert_eq!(super::coverage_error(&[0.0, 0.0], &[0.0, 0.0]), Some(0.0));
        // One pixel with hair in the reference only, one in both.
        let e = super::coverage_error(&[0.5, 1.0, 0.0], &[0.0, 0.75, 0.0]).unwrap();
        assert!((e - 0.375).abs() < 1e-6, "{e}");
        assert_eq!(super::coverage_error(&[0.0], &[0.0, 1.0]), None);
    }

    use super::*;

    #[test]
    fn identical_images_have_no_error_and_changes_are_found() {
        let mut a = RgbaImage::new(32, 32);
        for (x, y, p) in a.enumerate_pixels_mut() {
            *p = image::Rgba([(x * 8) as u8, (y * 8) as u8, 128, 255]);
        }
        let same = flip(&a, &a.clone()).unwrap();
        assert_eq!(same.mean, 0.0);
        assert_eq!(same.pixels_over(0.0), 0);
        let mut b = a.clone();
        b.put_pixel(20, 10, image::Rgba([255, 255, 255, 255]));
        let d = flip(&a, &b).unwrap();
        assert!(d.mean > 0.0 && d.max > 0.3, "mean {} max {}", d.mean, d.max);
        assert_eq!(d.max_at, (20, 10));
        assert!(flip(&a, &RgbaImage::new(8, 8)).is_none());
    }
}
