//! Environment maps: equirectangular (latitude-longitude) HDR images, OpenEXR
//! (`.exr`) or Radiance RGBE (`.hdr`), decoded with the `image` crate into
//! linear RGB radiance.
//!
//! The header is checked before anything is allocated from it: a map must be
//! twice as wide as tall (that is what makes it equirectangular) and at most
//! [`MAX_WIDTH`] × [`MAX_HEIGHT`]; the decoder itself runs under an allocation
//! limit. Texels must be finite; negative ones are clamped to zero.
//!
//! Convention (y up, right-handed like the scenes): texel row 0 is the top
//! (+y), u = 0.5 looks down −z and u = 0.75 down +x:
//! direction(u, v) = (sin θ sin φ, cos θ, −sin θ cos φ) with θ = π v,
//! φ = 2π (u − 0.5). [`direction`] and [`uv`] are inverses.
//!
//! [`studio`] is the procedural map committed as `scenes/env/studio.exr`
//! (regenerate with `cargo test -p strandgraph-assets --lib write_studio_exr
//! -- --ignored`).

use std::f32::consts::PI;
use std::path::Path;

use glam::Vec3;

use crate::error::{AssetError, FormatError, FormatErrorKind, Location};
use crate::smoothstep;

/// The widest map accepted (a probe keeps far less: the Lipp prefilter
/// resamples to 128 × 64).
pub const MAX_WIDTH: u32 = 4096;
/// The tallest map accepted.
pub const MAX_HEIGHT: u32 = 2048;
/// What the decoder may allocate at once (the largest map as rgba f32 is 128 MiB).
const MAX_ALLOC: u64 = 256 << 20;

/// A latitude-longitude radiance map, row-major, row 0 at the top (+y).
#[derive(Debug, Clone, PartialEq)]
pub struct EnvMap {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 3]>,
}

/// The unit direction at lat-long coordinates (u, v) ∈ [0, 1]².
pub fn direction(u: f32, v: f32) -> Vec3 {
    let (theta, phi) = (PI * v, 2.0 * PI * (u - 0.5));
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3::new(st * sp, ct, -st * cp)
}

/// The lat-long coordinates (u, v) of unit direction `d` (inverse of [`direction`]).
pub fn uv(d: Vec3) -> (f32, f32) {
    let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    (u, v)
}

impl EnvMap {
    /// A map of `width` × `height` from a radiance function of direction,
    /// sampled at texel centres.
    pub fn from_fn(width: u32, height: u32, f: impl Fn(Vec3) -> [f32; 3]) -> EnvMap {
        let texels = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| f(texel_direction(width, height, x, y)))
            .collect();
        EnvMap {
            width,
            height,
            texels,
        }
    }

    /// A map of one colour.
    pub fn constant(width: u32, height: u32, c: [f32; 3]) -> EnvMap {
        EnvMap {
            width,
            height,
            texels: vec![c; (width * height) as usize],
        }
    }

    pub fn texel(&self, x: u32, y: u32) -> [f32; 3] {
        self.texels[(y * self.width + x) as usize]
    }
}

/// The direction through the centre of texel (x, y) of a `width` × `height` map.
pub fn texel_direction(width: u32, height: u32, x: u32, y: u32) -> Vec3 {
    direction(
        (x as f32 + 0.5) / width as f32,
        (y as f32 + 0.5) / height as f32,
    )
}

/// The solid angle of one texel of row `y`: (2π / width) (cos θ_top − cos θ_bottom).
/// A row's texels sum to 4π over the map.
pub fn texel_solid_angle(width: u32, height: u32, y: u32) -> f32 {
    let t0 = PI * y as f32 / height as f32;
    let t1 = PI * (y + 1) as f32 / height as f32;
    2.0 * PI / width as f32 * (t0.cos() - t1.cos())
}

/// The two container formats we read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Exr,
    Hdr,
}

fn detect(data: &[u8]) -> Result<Kind, FormatError> {
    if data.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        return Ok(Kind::Exr);
    }
    if data.starts_with(b"#?RADIANCE") || data.starts_with(b"#?RGBE") {
        return Ok(Kind::Hdr);
    }
    let found: String = data
        .iter()
        .take(10)
        .map(|b| {
            if b.is_ascii_graphic() {
                (*b as char).to_string()
            } else {
                format!("\\x{b:02x}")
            }
        })
        .collect();
    Err(FormatError::at_byte(
        0,
        FormatErrorKind::BadMagic {
            expected: "OpenEXR (76 2f 31 01) or Radiance HDR (\"#?RADIANCE\" / \"#?RGBE\")".into(),
            found: if found.is_empty() {
                "an empty file".into()
            } else {
                format!("{found:?}")
            },
        },
    ))
}

/// Checks a header's dimensions before anything is allocated from them.
fn check_dimensions(width: u32, height: u32) -> Result<(), FormatError> {
    let file = |kind| FormatError::new(Location::File, kind);
    for (field, value) in [("width", width), ("height", height)] {
        if value == 0 {
            return Err(file(FormatErrorKind::ZeroCount { field }));
        }
    }
    if width > MAX_WIDTH {
        return Err(file(FormatErrorKind::AbsurdCount {
            field: "width",
            value: width.into(),
            max: MAX_WIDTH.into(),
        }));
    }
    if height > MAX_HEIGHT {
        return Err(file(FormatErrorKind::AbsurdCount {
            field: "height",
            value: height.into(),
            max: MAX_HEIGHT.into(),
        }));
    }
    if width != 2 * height {
        return Err(file(FormatErrorKind::Inconsistent(format!(
            "{width}x{height} is not an equirectangular (latitude-longitude) map, which is twice as wide as tall"
        ))));
    }
    Ok(())
}

/// The byte offset of the `nth` (0-based) header attribute `name` of an
/// OpenEXR file (name, NUL, type name, NUL), else the whole file.
fn exr_attribute(data: &[u8], name: &str, type_name: &str, nth: usize) -> Location {
    let needle = [name.as_bytes(), b"\0", type_name.as_bytes(), b"\0"].concat();
    data.windows(needle.len())
        .enumerate()
        .filter(|(_, w)| *w == needle.as_slice())
        .nth(nth)
        .map_or(Location::File, |(i, _)| Location::Byte(i))
}

/// Checks every part of an OpenEXR file before the decoder sizes buffers by
/// it. `image` reports (and we check) the display window, but decodes the
/// data window with every channel: a 563-byte file whose data window was
/// 788,529,160 pixels wide made the B44 decompressor ask for 18.9 GB. Each
/// part's data window must fit [`MAX_WIDTH`] x [`MAX_HEIGHT`], and its
/// pixels times its channels' bytes must fit the decoder's allocation limit.
/// So must one block (a tile, or the scan lines compressed together), which
/// the decoder reserves before it reads the block: a 547-byte file with
/// 4 x 536,870,916-pixel tiles asked for 1.65 GB.
fn check_exr_parts(data: &[u8]) -> Result<(), FormatError> {
    let meta = exr::meta::MetaData::read_from_buffered(data, false).map_err(|e| {
        FormatError::new(
            Location::File,
            FormatErrorKind::Syntax(format!("cannot decode: {e}")),
        )
    })?;
    for (i, part) in meta.headers.iter().enumerate() {
        let (w, h) = (part.layer_size.x() as u64, part.layer_size.y() as u64);
        let window = || exr_attribute(data, "dataWindow", "box2i", i);
        for (field, value, max) in [
            ("dataWindow width", w, MAX_WIDTH),
            ("dataWindow height", h, MAX_HEIGHT),
        ] {
            if value > u64::from(max) {
                return Err(FormatError::new(
                    window(),
                    FormatErrorKind::AbsurdCount {
                        field,
                        value,
                        max: max.into(),
                    },
                ));
            }
        }
        let pixel_bytes = part.channels.bytes_per_pixel as u64;
        let bytes = w * h * pixel_bytes;
        if bytes > MAX_ALLOC {
            return Err(FormatError::new(
                exr_attribute(data, "channels", "chlist", i),
                FormatErrorKind::AbsurdCount {
                    field: "decoded bytes (dataWindow pixels x channel bytes)",
                    value: bytes,
                    max: MAX_ALLOC,
                },
            ));
        }
        let (block_pixels, at) = match part.blocks {
            exr::meta::BlockDescription::Tiles(t) => (
                t.tile_size.x() as u128 * t.tile_size.y() as u128,
                exr_attribute(data, "tiles", "tiledesc", i),
            ),
            exr::meta::BlockDescription::ScanLines => (
                part.compression.scan_lines_per_block() as u128 * u128::from(w),
                exr_attribute(data, "compression", "compression", i),
            ),
        };
        let block_bytes = block_pixels * u128::from(pixel_bytes);
        if block_bytes > u128::from(MAX_ALLOC) {
            return Err(FormatError::new(
                at,
                FormatErrorKind::AbsurdCount {
                    field: "block bytes (tile or scan-line block pixels x channel bytes)",
                    value: u64::try_from(block_bytes).unwrap_or(u64::MAX),
                    max: MAX_ALLOC,
                },
            ));
        }
    }
    Ok(())
}

fn decode_error(e: image::ImageError) -> FormatError {
    FormatError::new(
        Location::File,
        FormatErrorKind::Syntax(format!("cannot decode: {e}")),
    )
}

/// Decodes an equirectangular `.exr` or `.hdr` file's bytes.
pub fn parse(data: &[u8]) -> Result<EnvMap, FormatError> {
    use image::{DynamicImage, ImageDecoder, Limits};
    let kind = detect(data)?;
    let mut limits = Limits::default();
    limits.max_image_width = Some(MAX_WIDTH);
    limits.max_image_height = Some(MAX_HEIGHT);
    limits.max_alloc = Some(MAX_ALLOC);
    let image = match kind {
        Kind::Exr => {
            check_exr_parts(data)?;
            let cursor = std::io::Cursor::new(data);
            let mut d =
                image::codecs::openexr::OpenExrDecoder::new(cursor).map_err(decode_error)?;
            let (w, h) = d.dimensions();
            check_dimensions(w, h)?;
            d.set_limits(limits).map_err(decode_error)?;
            DynamicImage::from_decoder(d)
        }
        Kind::Hdr => {
            // The decoder knows only the "#?RADIANCE" signature: an "#?RGBE"
            // file (the other one Radiance tools write) is read with it in
            // its place.
            let renamed: Vec<u8>;
            let bytes = match data.strip_prefix(b"#?RGBE") {
                Some(rest) => {
                    renamed = [b"#?RADIANCE".as_slice(), rest].concat();
                    &renamed[..]
                }
                None => data,
            };
            let cursor = std::io::Cursor::new(bytes);
            let mut d = image::codecs::hdr::HdrDecoder::new(cursor).map_err(decode_error)?;
            let (w, h) = d.dimensions();
            check_dimensions(w, h)?;
            d.set_limits(limits).map_err(decode_error)?;
            DynamicImage::from_decoder(d)
        }
    }
    .map_err(decode_error)?;
    let (width, height) = (image.width(), image.height());
    let texels: Vec<[f32; 3]> = match image {
        DynamicImage::ImageRgb32F(b) => bytemuck_rgb(b.into_raw(), 3),
        DynamicImage::ImageRgba32F(b) => bytemuck_rgb(b.into_raw(), 4),
        other => bytemuck_rgb(other.into_rgb32f().into_raw(), 3),
    };
    let mut map = EnvMap {
        width,
        height,
        texels,
    };
    for (i, t) in map.texels.iter_mut().enumerate() {
        if !t.iter().all(|c| c.is_finite()) {
            return Err(FormatError::new(
                Location::File,
                FormatErrorKind::NonFinite {
                    what: "texel",
                    index: i as u64,
                },
            ));
        }
        *t = t.map(|c| c.max(0.0));
    }
    Ok(map)
}

/// Groups `channels` floats per texel into rgb.
fn bytemuck_rgb(raw: Vec<f32>, channels: usize) -> Vec<[f32; 3]> {
    raw.chunks_exact(channels)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

/// Loads an equirectangular `.exr` or `.hdr` environment map.
pub fn load(path: &Path) -> Result<EnvMap, AssetError> {
    let data = super::read_file(path)?;
    let _span = tracing::debug_span!("load_env_map", path = %path.display()).entered();
    parse(&data).map_err(|e| AssetError::format(path, e))
}

/// A rectangular softbox seen from the origin: `centre` direction, half
/// extents in degrees along the horizontal and vertical, soft edges.
fn softbox(d: Vec3, centre: Vec3, half_h_deg: f32, half_v_deg: f32) -> f32 {
    let c = centre.normalize();
    let right = Vec3::Y.cross(c).normalize();
    let up = c.cross(right);
    let z = d.dot(c);
    if z <= 0.0 {
        return 0.0;
    }
    let h = d.dot(right).atan2(z).to_degrees().abs();
    let v = d.dot(up).atan2(z).to_degrees().abs();
    let edge = 1.5;
    (1.0 - smoothstep(half_h_deg - edge, half_h_deg + edge, h))
        * (1.0 - smoothstep(half_v_deg - edge, half_v_deg + edge, v))
}

/// Our procedural studio: a warm key softbox front-right above the horizon,
/// a cool strip light behind, a sky from a warm horizon glow to a blue
/// zenith, and a dark floor. Mean radiance is about 0.6.
pub fn studio(d: Vec3) -> [f32; 3] {
    let d = d.normalize();
    let y = d.y;
    let base = if y >= 0.0 {
        let zenith = Vec3::new(0.18, 0.30, 0.62);
        let horizon = Vec3::new(0.85, 0.55, 0.30);
        let t = y.sqrt();
        horizon.lerp(zenith, t) + Vec3::new(0.9, 0.5, 0.2) * (-y / 0.05).exp()
    } else {
        let floor = Vec3::new(0.05, 0.045, 0.04);
        floor * (1.0 - 0.6 * smoothstep(0.0, 1.0, -y)) + Vec3::new(0.3, 0.2, 0.1) * (y / 0.03).exp()
    };
    let key = softbox(d, Vec3::new(0.55, 0.45, 0.7), 18.0, 12.0) * Vec3::new(9.0, 8.4, 7.6);
    let rim = softbox(d, Vec3::new(-0.25, 0.3, -0.9), 6.0, 25.0) * Vec3::new(2.6, 3.2, 4.2);
    (base + key + rim).to_array()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minimal OpenEXR file: rgb f16, ZIP compressed.
    fn exr_bytes(w: usize, h: usize, f: impl Fn(usize, usize) -> [f32; 3] + Sync) -> Vec<u8> {
        use exr::prelude::*;
        let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
            let c = f(p.x(), p.y());
            (
                half::f16::from_f32(c[0]),
                half::f16::from_f32(c[1]),
                half::f16::from_f32(c[2]),
            )
        });
        let image = Image::from_encoded_channels((w, h), Encoding::SMALL_LOSSLESS, channels);
        let mut out = std::io::Cursor::new(Vec::new());
        image.write().to_buffered(&mut out).unwrap();
        out.into_inner()
    }

    fn hdr_bytes(w: usize, h: usize, f: impl Fn(usize, usize) -> [f32; 3]) -> Vec<u8> {
        let data: Vec<image::Rgb<f32>> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| image::Rgb(f(x, y)))
            .collect();
        let mut out = Vec::new();
        image::codecs::hdr::HdrEncoder::new(&mut out)
            .encode(&data, w, h)
            .unwrap();
        out
    }

    #[test]
    fn direction_and_uv_are_inverses_and_follow_the_convention() {
        let forward = direction(0.5, 0.5);
        assert!((forward - Vec3::NEG_Z).length() < 1e-6, "{forward}");
        assert!((direction(0.75, 0.5) - Vec3::X).length() < 1e-6);
        assert!((direction(0.3, 0.0) - Vec3::Y).length() < 1e-6);
        for (u, v) in [(0.1, 0.2), (0.5, 0.5), (0.9, 0.7), (0.26, 0.95)] {
            let (u2, v2) = uv(direction(u, v));
            assert!(
                (u - u2).abs() < 1e-5 && (v - v2).abs() < 1e-5,
                "{u} {v} -> {u2} {v2}"
            );
        }
    }

    #[test]
    fn solid_angles_sum_to_the_sphere() {
        let (w, h) = (64, 32);
        let total: f32 = (0..h).map(|y| texel_solid_angle(w, h, y) * w as f32).sum();
        assert!((total - 4.0 * PI).abs() < 1e-4, "{total}");
    }

    #[test]
    fn exr_round_trips() {
        let bytes = exr_bytes(8, 4, |x, y| [x as f32, y as f32 * 0.5, 2.0]);
        let m = parse(&bytes).unwrap();
        assert_eq!((m.width, m.height), (8, 4));
        assert_eq!(m.texel(5, 3), [5.0, 1.5, 2.0]);
    }

    #[test]
    fn hdr_round_trips_within_rgbe_precision() {
        let bytes = hdr_bytes(16, 8, |x, y| [x as f32 * 0.25, 1.0, y as f32 + 0.5]);
        let m = parse(&bytes).unwrap();
        assert_eq!((m.width, m.height), (16, 8));
        let t = m.texel(6, 7);
        let want = [1.5, 1.0, 7.5];
        for k in 0..3 {
            assert!(
                (t[k] - want[k]).abs() <= want[k] / 128.0,
                "{t:?} vs {want:?}"
            );
        }
    }

    fn format_error(bytes: &[u8]) -> FormatError {
        parse(bytes).expect_err("a malformed map must not load")
    }

    #[test]
    fn malformed_files_are_errors_that_say_what_is_wrong() {
        // Not an image at all, and an empty file.
        let e = format_error(b"P6 not an hdr");
        assert!(matches!(e.kind, FormatErrorKind::BadMagic { .. }), "{e}");
        assert!(e.to_string().contains("OpenEXR"), "{e}");
        assert!(format_error(b"").to_string().contains("empty file"));
        // A truncated EXR and a truncated HDR.
        let exr = exr_bytes(32, 16, |_, _| [1.0; 3]);
        let e = format_error(&exr[..exr.len() / 2]);
        assert!(e.to_string().contains("cannot decode"), "{e}");
        let hdr = hdr_bytes(32, 16, |_, _| [1.0; 3]);
        let e = format_error(&hdr[..hdr.len() - 40]);
        assert!(e.to_string().contains("cannot decode"), "{e}");
        // Not 2:1.
        let e = format_error(&exr_bytes(8, 8, |_, _| [1.0; 3]));
        assert!(e.to_string().contains("twice as wide as tall"), "{e}");
        // A non-finite texel (f16 infinity), by its index.
        let e = format_error(&exr_bytes(8, 4, |x, y| {
            [if (x, y) == (3, 1) { f32::INFINITY } else { 1.0 }; 3]
        }));
        assert_eq!(
            e.kind,
            FormatErrorKind::NonFinite {
                what: "texel",
                index: 11
            }
        );
    }

    #[test]
    fn absurd_headers_are_refused_before_allocating() {
        // A Radiance header claiming 200,000 x 100,000 texels with no data.
        let bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 200000\n";
        let e = format_error(bytes);
        assert_eq!(
            e.kind,
            FormatErrorKind::AbsurdCount {
                field: "width",
                value: 200_000,
                max: MAX_WIDTH.into()
            },
            "{e}"
        );
        let e = format_error(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 3000 +X 4000\n");
        assert!(
            matches!(
                e.kind,
                FormatErrorKind::AbsurdCount {
                    field: "height",
                    ..
                }
            ),
            "{e}"
        );
    }

    /// Found by the envmap_hdr fuzz target's seeds: `detect` accepted the
    /// "#?RGBE" signature, but the decoder reads only "#?RADIANCE", so such
    /// a file was "cannot decode: Radiance HDR signature not found".
    #[test]
    fn the_rgbe_signature_decodes_as_radiance() {
        let radiance = hdr_bytes(8, 4, |x, y| [x as f32, 0.5, y as f32]);
        let rgbe = [b"#?RGBE".as_slice(), &radiance[b"#?RADIANCE".len()..]].concat();
        assert_eq!(parse(&rgbe).unwrap(), parse(&radiance).unwrap());
        // An uncompressed 4 x 2 file with a comment and an exposure line.
        let mut flat =
            b"#?RGBE\n# hand-written\nEXPOSURE=1.0\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n".to_vec();
        for _ in 0..8 {
            flat.extend([128, 64, 32, 129]);
        }
        let m = parse(&flat).unwrap();
        assert_eq!((m.width, m.height), (4, 2));
        assert_eq!(m.texel(3, 1), [1.0, 0.5, 0.25]);
    }

    /// Found by the envmap_exr fuzz target (an out-of-memory crash): the
    /// data window, which the decoder sizes its buffers by, was not checked,
    /// only the display window `image` reports.
    #[test]
    fn an_exr_data_window_past_the_bounds_is_refused_where_it_is() {
        let mut bytes = exr_bytes(8, 4, |_, _| [1.0; 3]);
        let Location::Byte(at) = exr_attribute(&bytes, "dataWindow", "box2i", 0) else {
            panic!("no dataWindow attribute")
        };
        // name, type, 4-byte size, then xMin yMin xMax yMax.
        let x_max = at + "dataWindow\0box2i\0".len() + 4 + 8;
        bytes[x_max..x_max + 4].copy_from_slice(&788_529_159i32.to_le_bytes());
        let e = format_error(&bytes);
        assert_eq!(
            e,
            FormatError::new(
                Location::Byte(at),
                FormatErrorKind::AbsurdCount {
                    field: "dataWindow width",
                    value: 788_529_160,
                    max: MAX_WIDTH.into()
                }
            )
        );
        // A data window inside the bounds passes the check and reaches the
        // decoder, which finds the file's blocks too short for it.
        bytes[x_max..x_max + 4].copy_from_slice(&15i32.to_le_bytes());
        let e = parse(&bytes);
        assert!(
            e.as_ref()
                .is_err_and(|e| e.to_string().contains("cannot decode")),
            "{e:?}"
        );
    }

    /// Found by the envmap_exr fuzz target (the fuzzer's input, 563 bytes):
    /// a B44 block whose deltas take a pixel below zero. exr's unpack14
    /// computes in u32 and relies on wrap-around, as OpenEXR's C++ does, so
    /// with overflow checks (dev builds, tests, fuzzing) it panicked with
    /// "attempt to subtract with overflow" where release decodes garbage.
    /// The root Cargo.toml keeps exr's arithmetic as in release.
    #[test]
    fn a_b44_block_that_wraps_around_does_not_panic() {
        let bytes = include_bytes!("testdata/b44_wrapping.exr");
        if let Ok(m) = parse(bytes) {
            assert_eq!(m.texels.len(), (m.width * m.height) as usize);
        }
    }

    /// Found by the envmap_exr fuzz target (an out-of-memory crash; the
    /// fuzzer's input is testdata/tile_size.exr): a tile's size, which the
    /// decoder reserves for each block before reading it, was not checked.
    #[test]
    fn an_exr_tile_past_the_allocation_limit_is_refused_where_it_is() {
        let e = format_error(include_bytes!("testdata/tile_size.exr"));
        assert!(
            matches!(e.kind, FormatErrorKind::AbsurdCount { field, .. } if field.starts_with("block bytes")),
            "{e}"
        );
        // The same in a file written by exr: 4 x 4 tiles made 65536 x 65536.
        use exr::prelude::*;
        let channels = SpecificChannels::rgb(|_: Vec2<usize>| (1.0f32, 1.0f32, 1.0f32));
        let encoding = Encoding {
            compression: Compression::ZIP16,
            blocks: Blocks::Tiles(Vec2(4, 4)),
            line_order: LineOrder::Increasing,
        };
        let mut out = std::io::Cursor::new(Vec::new());
        Image::from_encoded_channels((8, 4), encoding, channels)
            .write()
            .to_buffered(&mut out)
            .unwrap();
        let mut bytes = out.into_inner();
        assert!(parse(&bytes).is_ok());
        let Location::Byte(at) = exr_attribute(&bytes, "tiles", "tiledesc", 0) else {
            panic!("no tiles attribute")
        };
        let size = at + "tiles\0tiledesc\0".len() + 4;
        bytes[size..size + 4].copy_from_slice(&65536u32.to_le_bytes());
        bytes[size + 4..size + 8].copy_from_slice(&65536u32.to_le_bytes());
        assert_eq!(
            format_error(&bytes),
            FormatError::new(
                Location::Byte(at),
                FormatErrorKind::AbsurdCount {
                    field: "block bytes (tile or scan-line block pixels x channel bytes)",
                    value: 65536 * 65536 * 12,
                    max: MAX_ALLOC,
                }
            )
        );
    }

    #[test]
    fn negative_texels_are_clamped() {
        let m = parse(&exr_bytes(4, 2, |_, _| [-1.0, 0.5, 0.0])).unwrap();
        assert!(m.texels.iter().all(|t| *t == [0.0, 0.5, 0.0]));
    }

    #[test]
    fn load_names_the_file() {
        let e = load(Path::new("/nonexistent/env/studio.exr")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/env/studio.exr"), "{e}");
        let dir = std::env::temp_dir().join(format!("strandgraph-envmap-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bad.exr");
        std::fs::write(&path, b"garbage").unwrap();
        let e = load(&path).unwrap_err().to_string();
        assert!(
            e.starts_with(&path.display().to_string()) && e.contains("wrong magic"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The committed map: 128 x 64 texels of [`studio`].
    const STUDIO_SIZE: (u32, u32) = (128, 64);

    fn studio_path() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/env/studio.exr")
    }

    /// Regenerates `scenes/env/studio.exr` (f16, ZIP).
    #[test]
    #[ignore = "writes scenes/env/studio.exr"]
    fn write_studio_exr() {
        let (w, h) = STUDIO_SIZE;
        let m = EnvMap::from_fn(w, h, studio);
        let bytes = exr_bytes(w as usize, h as usize, |x, y| m.texel(x as u32, y as u32));
        std::fs::write(studio_path(), bytes).unwrap();
    }

    #[test]
    fn committed_studio_map_is_the_generator_output() {
        let m = load(&studio_path()).unwrap();
        assert_eq!((m.width, m.height), STUDIO_SIZE);
        let want = EnvMap::from_fn(m.width, m.height, studio);
        for (a, b) in m.texels.iter().zip(&want.texels) {
            for k in 0..3 {
                // f16: 11 significant bits.
                assert!((a[k] - b[k]).abs() <= b[k] * 1e-3 + 1e-6, "{a:?} vs {b:?}");
            }
        }
        // Brighter than the floor above the horizon, and the key box is the brightest.
        let mean: f32 = m.texels.iter().map(|t| t[1]).sum::<f32>() / m.texels.len() as f32;
        let max = m.texels.iter().map(|t| t[1]).fold(0.0, f32::max);
        assert!(
            mean > 0.2 && mean < 2.0 && max > 5.0,
            "mean {mean} max {max}"
        );
    }
}
