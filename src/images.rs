//! Rendered images (graph outputs read back as words) to 8-bit pictures.

use half::f16;
use image::RgbaImage;
use strandgraph_graph::Plan;
use strandgraph_graph::schema::{ImageFormat, ResourceDecl};

/// Linear to sRGB, for display.
fn srgb(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let s = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// An image resource's words as a picture; `None` for buffers and formats we do not display.
pub fn to_picture(
    plan: &Plan,
    resource: usize,
    words: &[u32],
    width: u32,
    height: u32,
) -> Option<RgbaImage> {
    let r = plan.graph.physical(resource);
    let ResourceDecl::Image { format, .. } = plan.graph.resources[r].decl else {
        return None;
    };
    let texels = (width * height) as usize;
    let mut img = RgbaImage::new(width, height);
    match format {
        ImageFormat::Rgba16Float if words.len() >= 2 * texels => {
            for (i, px) in img.pixels_mut().enumerate() {
                let (lo, hi) = (words[2 * i], words[2 * i + 1]);
                let c =
                    [lo & 0xFFFF, lo >> 16, hi & 0xFFFF].map(|h| f16::from_bits(h as u16).to_f32());
                *px = image::Rgba([srgb(c[0]), srgb(c[1]), srgb(c[2]), 255]);
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
