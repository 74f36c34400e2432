//! Sampling the hair texture (`patches.texture`): the CPU mirror of
//! `sample_hair` in `shaders/scheuermann/hair.wgsl`, operation for
//! operation.
//!
//! The texture is a storage buffer of RGBA8 texels (base, alpha, shift,
//! sparkle; [`HairTexture`]) filtered in the shader, not a sampled image:
//! the CPU simulator then filters exactly as the GPUs do, where hardware
//! samplers round their weights to a vendor's fixed-point precision.
//!
//! Mips run along u only: strands run along v, so the footprint across them
//! is what grows with distance. The level comes from the strip's texel
//! density across u and the view depth, not from screen-space derivatives:
//! the CPU simulator shades one fragment at a time and has no 2×2 quads to
//! difference. It ignores foreshortening of strips seen edge-on, which
//! derivatives would catch, so those alias a little more than hardware
//! mipmapping would.

use glam::{Vec2, Vec4};
use strandgraph_assets::hairpatch::HairTexture;

pub const WIDTH: u32 = HairTexture::WIDTH;
pub const HEIGHT: u32 = HairTexture::HEIGHT;
pub const LEVELS: u32 = HairTexture::LEVELS;

/// Index of the first texel of `level` (levels back to back).
pub fn level_offset(level: u32) -> usize {
    HairTexture::level_offset(level)
}

/// WGSL `mix`: `a · (1 − t) + b · t`.
fn mix(a: Vec4, b: Vec4, t: f32) -> Vec4 {
    a * (1.0 - t) + b * t
}

/// WGSL `unpack4x8unorm`.
fn unpack(w: u32) -> Vec4 {
    Vec4::from_array([0, 8, 16, 24].map(|s| ((w >> s) & 0xFF) as f32 / 255.0))
}

/// Texel `(x, y)` of `level`, coordinates clamped to the level's edges.
fn texel(fetch: &impl Fn(usize) -> u32, level: u32, x: i32, y: i32) -> Vec4 {
    let w = (WIDTH >> level) as i32;
    let xi = x.clamp(0, w - 1) as usize;
    let yi = y.clamp(0, HEIGHT as i32 - 1) as usize;
    unpack(fetch(level_offset(level) + yi * w as usize + xi))
}

/// Bilinear filtering within one level.
pub fn sample_level(fetch: &impl Fn(usize) -> u32, level: u32, uv: Vec2) -> Vec4 {
    let x = uv.x * (WIDTH >> level) as f32 - 0.5;
    let y = uv.y * HEIGHT as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (ix, iy) = (x0 as i32, y0 as i32);
    let top = mix(
        texel(fetch, level, ix, iy),
        texel(fetch, level, ix + 1, iy),
        fx,
    );
    let bottom = mix(
        texel(fetch, level, ix, iy + 1),
        texel(fetch, level, ix + 1, iy + 1),
        fx,
    );
    mix(top, bottom, fy)
}

/// The mip level for a fragment: log2 of texels per pixel across the strip,
/// from its texel density (texels per metre) and clip w (view depth).
pub fn lod(texels_per_metre: f32, clip_w: f32, pixels_per_unit: f32, bias: f32) -> f32 {
    let texels_per_pixel = texels_per_metre * clip_w / pixels_per_unit;
    (texels_per_pixel.max(1.0).log2() + bias).clamp(0.0, (LEVELS - 1) as f32)
}

/// Trilinear along u: the two levels around `lod`, blended.
pub fn sample(fetch: &impl Fn(usize) -> u32, uv: Vec2, lod: f32) -> Vec4 {
    let l0 = lod.floor() as u32;
    let l1 = (l0 + 1).min(LEVELS - 1);
    mix(
        sample_level(fetch, l0, uv),
        sample_level(fetch, l1, uv),
        lod - lod.floor(),
    )
}

/// The texture as `patches.texture` holds it: one RGBA8 word per texel.
pub fn words(texture: &HairTexture) -> Vec<u32> {
    texture
        .texels
        .iter()
        .map(|&t| u32::from_le_bytes(t))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_are_back_to_back() {
        for l in 0..LEVELS {
            // `level_offset` in the WGSL.
            let wgsl = HEIGHT * (2 * WIDTH - 2 * (WIDTH >> l));
            assert_eq!(level_offset(l), wgsl as usize, "level {l}");
        }
        let total: u32 = (0..LEVELS).map(|l| (WIDTH >> l) * HEIGHT).sum();
        assert_eq!(
            level_offset(LEVELS - 1) + HEIGHT as usize,
            total as usize,
            "the last level is one texel wide"
        );
        assert_eq!(
            words(&HairTexture::generate(1)).len(),
            total as usize,
            "the generated texture fills every level"
        );
    }

    #[test]
    fn texel_centres_return_the_texel_and_midpoints_average() {
        let t = HairTexture::generate(3);
        let w = words(&t);
        let fetch = |i: usize| w[i];
        let (x, y) = (37u32, 50u32);
        let centre = Vec2::new(
            (x as f32 + 0.5) / WIDTH as f32,
            (y as f32 + 0.5) / HEIGHT as f32,
        );
        let at = |x: u32| unpack(w[(y * WIDTH + x) as usize]);
        assert!(
            (sample_level(&fetch, 0, centre) - at(x))
                .abs()
                .max_element()
                < 1e-6
        );
        let between = centre + Vec2::new(0.5 / WIDTH as f32, 0.0);
        let expect = (at(x) + at(x + 1)) * 0.5;
        assert!(
            (sample_level(&fetch, 0, between) - expect)
                .abs()
                .max_element()
                < 1e-5
        );
    }

    #[test]
    fn lod_grows_with_distance_and_stays_in_range() {
        let near = lod(6400.0, 0.3, 1300.0, 0.0);
        let far = lod(6400.0, 3.0, 1300.0, 0.0);
        assert!((far - near - 10f32.log2()).abs() < 1e-4, "{near} {far}");
        assert_eq!(lod(1.0, 0.1, 1300.0, 0.0), 0.0);
        assert_eq!(lod(1e9, 100.0, 1.0, 0.0), (LEVELS - 1) as f32);
    }
}
