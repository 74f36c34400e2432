//! Rendered images (graph outputs read back as words) to 8-bit pictures.

use half::f16;
use image::{Rgb32FImage, Rgba32FImage, RgbaImage};
use strandgraph_graph::Plan;
use strandgraph_graph::schema::{ImageFormat, ResourceDecl};

pub use crate::tonemap::Tonemap;

/// How linear images become display pictures.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Display {
    pub tonemap: Tonemap,
    /// Exposure in EV (stops) applied before the tone mapper.
    pub exposure: f32,
}

impl Display {
    /// No tone mapping and no exposure: clip and sRGB-encode (what the
    /// image-comparing tests calibrated their thresholds on).
    pub const CLIP: Display = Display {
        tonemap: Tonemap::None,
        exposure: 0.0,
    };
}

/// An image resource's words as a picture; `None` for buffers and formats we
/// do not display. Float images go through `display`'s tone mapper.
pub fn to_picture(
    plan: &Plan,
    resource: usize,
    words: &[u32],
    width: u32,
    height: u32,
    display: Display,
) -> Option<RgbaImage> {
    let format = picture_format(plan, resource)?;
    let texels = (width * height) as usize;
    let mut img = RgbaImage::new(width, height);
    match format {
        ImageFormat::Rgba16Float if words.len() >= 2 * texels => {
            for (i, px) in img.pixels_mut().enumerate() {
                let (lo, hi) = (words[2 * i], words[2 * i + 1]);
                let c =
                    [lo & 0xFFFF, lo >> 16, hi & 0xFFFF].map(|h| f16::from_bits(h as u16).to_f32());
                let [r, g, b] = display.tonemap.display8(c, display.exposure);
                *px = image::Rgba([r, g, b, 255]);
            }
        }
        ImageFormat::Rgba8Unorm if words.len() >= texels => {
            for (i, px) in img.pixels_mut().enumerate() {
                *px = image::Rgba(words[i].to_le_bytes());
            }
        }
        _ => return None,
    }
    Some(img)
}

/// The format of image resource `resource` when it makes a picture:
/// `Rgba16Float` (scene-linear, tone-mapped) or `Rgba8Unorm` (shown as it
/// is); `None` for buffers and other formats.
pub fn picture_format(plan: &Plan, resource: usize) -> Option<ImageFormat> {
    let r = plan.graph.physical(resource);
    match plan.graph.resources[r].decl {
        ResourceDecl::Image { format, .. }
            if matches!(format, ImageFormat::Rgba16Float | ImageFormat::Rgba8Unorm) =>
        {
            Some(format)
        }
        _ => None,
    }
}

/// An `Rgba16Float` image resource as linear float RGBA, for EXR; `None`
/// for other formats.
pub fn to_linear(
    plan: &Plan,
    resource: usize,
    words: &[u32],
    width: u32,
    height: u32,
) -> Option<Rgba32FImage> {
    let r = plan.graph.physical(resource);
    let ResourceDecl::Image {
        format: ImageFormat::Rgba16Float,
        ..
    } = plan.graph.resources[r].decl
    else {
        return None;
    };
    let texels = (width * height) as usize;
    if words.len() < 2 * texels {
        return None;
    }
    let data = words[..2 * texels]
        .iter()
        .flat_map(|w| [w & 0xFFFF, w >> 16])
        .map(|h| f16::from_bits(h as u16).to_f32())
        .collect();
    Rgba32FImage::from_raw(width, height, data)
}

/// A depth image of f32 NDC depth (`perspective_rh`; 1 where nothing was drawn)
/// as linear view depth in metres, in all three channels (the `image`
/// crate writes EXR as RGB or RGBA); the far plane where nothing was drawn.
pub fn depth_to_view(
    words: &[u32],
    near: f32,
    far: f32,
    width: u32,
    height: u32,
) -> Option<Rgb32FImage> {
    let texels = (width * height) as usize;
    let data = words
        .get(..texels)?
        .iter()
        .flat_map(|&w| {
            let z = f32::from_bits(w).clamp(0.0, 1.0);
            // Written as a blend rather than `far - z * (far - near)`: the
            // subtraction cancels catastrophically near z = 1 in f32.
            let d = near * far / (far * (1.0 - z) + near * z);
            [d, d, d]
        })
        .collect();
    Rgb32FImage::from_raw(width, height, data)
}

/// Per-pixel motion (two f32 per pixel, x and y in pixels) as RGB with
/// R = x, G = y, B = 0, for EXR.
pub fn motion_image(words: &[u32], width: u32, height: u32) -> Option<Rgb32FImage> {
    let texels = (width * height) as usize;
    let data = words
        .get(..2 * texels)?
        .chunks(2)
        .flat_map(|m| [f32::from_bits(m[0]), f32::from_bits(m[1]), 0.0])
        .collect();
    Rgb32FImage::from_raw(width, height, data)
}

/// The first image output of `plan` that makes a picture, read from a
/// session by `read`: what `render` writes as its main image.
pub fn main_picture(
    plan: &Plan,
    width: u32,
    height: u32,
    display: Display,
    read: impl Fn(&str) -> Option<Vec<u32>>,
) -> Option<Picture> {
    plan.graph.outputs.iter().find_map(|&(r, _)| {
        let words = read(&plan.graph.resources[r].name)?;
        Some(Picture {
            image: to_picture(plan, r, &words, width, height, display)?,
            coverage: coverage(plan, r, &words, width, height),
        })
    })
}

/// A graph's main image as a viewer sees it, and the hair's coverage.
#[derive(Debug, Clone)]
pub struct Picture {
    pub image: RgbaImage,
    /// Per pixel, row by row: the image's alpha, which every pipeline keeps
    /// as the coverage of its hair (0 where the opaque scene shows, 1 under
    /// opaque hair; docs/reference.md). `None` for an image without alpha.
    pub coverage: Option<Vec<f32>>,
}

/// The alpha channel of an `Rgba16Float` image resource.
pub fn coverage(
    plan: &Plan,
    resource: usize,
    words: &[u32],
    width: u32,
    height: u32,
) -> Option<Vec<f32>> {
    let r = plan.graph.physical(resource);
    let ResourceDecl::Image { format, .. } = plan.graph.resources[r].decl else {
        return None;
    };
    let texels = (width * height) as usize;
    (format == ImageFormat::Rgba16Float && words.len() >= 2 * texels).then(|| {
        (0..texels)
            .map(|i| f16::from_bits((words[2 * i + 1] >> 16) as u16).to_f32())
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_converts_to_view_distance() {
        let (n, f) = (0.02, 500.0);
        let p = glam_free_projection_depth(3.0, n, f);
        let img = depth_to_view(&[p.to_bits(), 1.0f32.to_bits()], n, f, 2, 1).unwrap();
        assert!((img.get_pixel(0, 0)[0] - 3.0).abs() < 1e-3);
        assert!((img.get_pixel(1, 0)[0] - f).abs() < 1e-2);
        assert!(depth_to_view(&[0], n, f, 2, 1).is_none());
    }

    /// NDC depth of view distance `d` under `perspective_rh` (z in [0, 1]).
    fn glam_free_projection_depth(d: f32, n: f32, f: f32) -> f32 {
        (f / (n - f) * -d + n * f / (n - f)) / d
    }
}
