//! Cem Yuksel's cyHair `.hair` format: a 128-byte header, then the optional arrays in bit
//! order. Absent arrays take the header defaults.

use glam::Vec3;

use super::reader::{Reader, Writer, check_count};
use super::{MAX_POINTS, MAX_STRANDS};
use crate::error::{AssetError, FormatError, FormatErrorKind};
use crate::groom::Groom;

pub const HEADER_SIZE: usize = 128;
pub const BIT_SEGMENTS: u32 = 1;
pub const BIT_POINTS: u32 = 2;
pub const BIT_THICKNESS: u32 = 4;
pub const BIT_TRANSPARENCY: u32 = 8;
pub const BIT_COLORS: u32 = 16;

/// Parses a cyHair file. Positions are returned in file units (the caller scales).
pub fn parse(data: &[u8]) -> Result<Groom, FormatError> {
    let mut r = Reader::new(data);
    let magic = r.bytes(4, "magic \"HAIR\"")?;
    if magic != b"HAIR" {
        return Err(FormatError::at_byte(
            0,
            FormatErrorKind::BadMagic {
                expected: "\"HAIR\"".into(),
                found: format!("{:?}", String::from_utf8_lossy(magic)),
            },
        ));
    }
    let hair_count = r.u32("hair_count")? as u64;
    let point_count = r.u32("point_count")? as u64;
    let arrays = r.u32("arrays bitmask")?;
    let d_segments = r.u32("d_segments")?;
    let d_thickness = r.f32("d_thickness")?;
    let d_transparency = r.f32("d_transparency")?;
    let d_color = [r.f32("d_color")?, r.f32("d_color")?, r.f32("d_color")?];
    r.bytes(88, "info")?;

    check_count(4, "hair_count", hair_count, MAX_STRANDS)?;
    check_count(8, "point_count", point_count, MAX_POINTS)?;
    if arrays & !0x1f != 0 {
        return Err(FormatError::at_byte(
            12,
            FormatErrorKind::Inconsistent(format!("unknown array bits {arrays:#x}")),
        ));
    }
    if arrays & BIT_POINTS == 0 {
        return Err(FormatError::at_byte(
            12,
            FormatErrorKind::Inconsistent("the file has no points array".into()),
        ));
    }
    for (off, v, what) in [
        (20, d_thickness, "default thickness"),
        (24, d_transparency, "default transparency"),
        (28, d_color[0], "default colour"),
        (32, d_color[1], "default colour"),
        (36, d_color[2], "default colour"),
    ] {
        if !v.is_finite() {
            return Err(FormatError::at_byte(
                off,
                FormatErrorKind::NonFinite { what, index: 0 },
            ));
        }
    }

    // Validate every array against the file length before allocating anything.
    let mut end = HEADER_SIZE;
    let mut plan = |bit: u32, field_off: usize, field: &'static str, count: u64, size: u64| {
        if arrays & bit == 0 {
            return Ok(None);
        }
        r.check_array(field_off, field, end, count, size)?;
        let start = end;
        end += (count * size) as usize;
        Ok::<_, FormatError>(Some(start))
    };
    let seg_at = plan(BIT_SEGMENTS, 4, "hair_count", hair_count, 2)?;
    let pts_at = plan(BIT_POINTS, 8, "point_count", point_count, 12)?;
    let thick_at = plan(BIT_THICKNESS, 8, "point_count", point_count, 4)?;
    let transp_at = plan(BIT_TRANSPARENCY, 8, "point_count", point_count, 4)?;
    let color_at = plan(BIT_COLORS, 8, "point_count", point_count, 12)?;
    let (h, p) = (hair_count as usize, point_count as usize);

    // Strand offsets: from the segments array (checked to fit above) or from d_segments
    // (checked against point_count, which was checked to fit, before allocating).
    let offsets = if let Some(at) = seg_at {
        r.seek(at, "segments")?;
        let mut offsets = Vec::with_capacity(h + 1);
        offsets.push(0u32);
        let mut total = 0u64;
        for i in 0..h {
            let seg = r.u16("segments")? as u64;
            total += seg + 1;
            if total > point_count {
                return Err(FormatError::at_byte(
                    at + 2 * i,
                    FormatErrorKind::Inconsistent(format!(
                        "segments of strands 0..={i} need {total} points, point_count is {point_count}"
                    )),
                ));
            }
            offsets.push(total as u32);
        }
        if total != point_count {
            return Err(FormatError::at_byte(
                8,
                FormatErrorKind::Inconsistent(format!(
                    "point_count is {point_count} but the segments array sums to {total} points"
                )),
            ));
        }
        offsets
    } else {
        let per = d_segments as u64 + 1;
        if hair_count.checked_mul(per) != Some(point_count) {
            return Err(FormatError::at_byte(
                16,
                FormatErrorKind::Inconsistent(format!(
                    "{hair_count} strands of d_segments {d_segments} do not make point_count {point_count}"
                )),
            ));
        }
        (0..=h).map(|s| (s as u64 * per) as u32).collect()
    };

    let mut g = Groom {
        strand_offsets: offsets,
        ..Default::default()
    };
    if let Some(at) = pts_at {
        r.seek(at, "points")?;
        let f = r.finite_f32s(3 * p, 3, "point")?;
        g.positions = f.chunks_exact(3).map(Vec3::from_slice).collect();
    }
    g.thickness = match thick_at {
        Some(at) => {
            r.seek(at, "thickness")?;
            r.finite_f32s(p, 1, "thickness")?
        }
        None => vec![d_thickness; p],
    };
    g.transparency = Some(match transp_at {
        Some(at) => {
            r.seek(at, "transparency")?;
            r.finite_f32s(p, 1, "transparency")?
        }
        None => vec![d_transparency; p],
    });
    g.colors = Some(match color_at {
        Some(at) => {
            r.seek(at, "colours")?;
            let f = r.finite_f32s(3 * p, 3, "colour")?;
            f.chunks_exact(3).map(Vec3::from_slice).collect()
        }
        None => vec![Vec3::from_array(d_color); p],
    });
    Ok(g)
}

/// Writes a groom as cyHair with every array present (colours and transparency when the
/// groom has them).
pub fn write(g: &Groom) -> Result<Vec<u8>, AssetError> {
    g.validate().map_err(AssetError::Invalid)?;
    let mut w = Writer::default();
    let mut bits = BIT_SEGMENTS | BIT_POINTS | BIT_THICKNESS;
    if g.transparency.is_some() {
        bits |= BIT_TRANSPARENCY;
    }
    if g.colors.is_some() {
        bits |= BIT_COLORS;
    }
    w.buf.extend_from_slice(b"HAIR");
    w.u32(g.strand_count() as u32);
    w.u32(g.point_count() as u32);
    w.u32(bits);
    w.u32(0);
    w.f32(g.thickness.first().copied().unwrap_or(1.0));
    w.f32(0.0);
    for _ in 0..3 {
        w.f32(1.0);
    }
    let mut info = [0u8; 88];
    let text = b"strandgraph";
    info[..text.len()].copy_from_slice(text);
    w.buf.extend_from_slice(&info);
    for s in 0..g.strand_count() {
        let seg = g.strand_range(s).len() - 1;
        let seg = u16::try_from(seg).map_err(|_| {
            AssetError::Invalid(format!("strand {s} has too many points for cyHair"))
        })?;
        w.u16(seg);
    }
    g.positions
        .iter()
        .for_each(|p| p.to_array().iter().for_each(|&v| w.f32(v)));
    g.thickness.iter().for_each(|&v| w.f32(v));
    if let Some(t) = &g.transparency {
        t.iter().for_each(|&v| w.f32(v));
    }
    if let Some(c) = &g.colors {
        c.iter()
            .for_each(|p| p.to_array().iter().for_each(|&v| w.f32(v)));
    }
    Ok(w.buf)
}
