//! TressFX 4 binary layout: a 160-byte header (f32 version, u32 numHairStrands,
//! u32 numVerticesPerStrand, u32 offsets of positions, strand UVs, vertex UVs, strand
//! thickness and vertex colours, 0 = absent; `u32 reserved[32]`), positions as float4
//! (w = inverse mass).

use glam::{Vec2, Vec3};

use super::reader::{Reader, Writer, check_count};
use super::{MAX_POINTS_PER_STRAND, MAX_STRANDS};
use crate::error::{AssetError, FormatError, FormatErrorKind};
use crate::groom::{DEFAULT_THICKNESS, Groom};

pub const HEADER_SIZE: usize = 160;

pub(crate) fn check_version(v: f32, major: f32) -> Result<(), FormatError> {
    if !(v >= major && v < major + 1.0) {
        return Err(FormatError::at_byte(
            0,
            FormatErrorKind::BadMagic {
                expected: format!("TressFX version {major}.x"),
                found: format!("{v}"),
            },
        ));
    }
    Ok(())
}

/// Shared reading of the arrays of the TressFX 3 and 4 binary layouts.
pub(crate) struct TfxArrays {
    pub strands: u64,
    pub per_strand: u64,
    pub positions: (usize, usize), // (header field offset, file offset)
    pub position_size: u64,        // 12 (float3) or 16 (float4)
    pub strand_uv: (usize, usize),
    pub vertex_uv: (usize, usize),
    pub strand_thickness: (usize, usize),
    pub vertex_color: (usize, usize),
    pub header_size: usize,
}

impl TfxArrays {
    pub fn read(&self, r: &mut Reader) -> Result<Groom, FormatError> {
        check_count(4, "number of strands", self.strands, MAX_STRANDS)?;
        check_count(
            8,
            "numVerticesPerStrand",
            self.per_strand,
            MAX_POINTS_PER_STRAND,
        )?;
        let points = self.strands * self.per_strand;
        let arrays = [
            (
                "vertex positions",
                self.positions,
                points,
                self.position_size,
                true,
            ),
            ("strand UVs", self.strand_uv, self.strands, 8, false),
            ("vertex UVs", self.vertex_uv, points, 8, false),
            (
                "strand thicknesses",
                self.strand_thickness,
                self.strands,
                4,
                false,
            ),
            ("vertex colours", self.vertex_color, points, 16, false),
        ];
        for (name, (field_off, at), count, size, required) in arrays {
            if at == 0 && !required {
                continue;
            }
            if at < self.header_size {
                return Err(FormatError::at_byte(
                    field_off,
                    FormatErrorKind::Inconsistent(format!(
                        "array offset {at} points into the {}-byte header",
                        self.header_size
                    )),
                ));
            }
            r.check_array(field_off, name, at, count, size)?;
        }
        let (s, n) = (self.strands as usize, self.per_strand as usize);
        let p = s * n;
        r.seek(self.positions.1, "positions")?;
        let group = (self.position_size / 4) as usize;
        let f = r.finite_f32s(p * group, group, "vertex position")?;
        let mut g = Groom {
            positions: f.chunks_exact(group).map(Vec3::from_slice).collect(),
            strand_offsets: (0..=s).map(|i| (i * n) as u32).collect(),
            ..Default::default()
        };
        g.thickness = if self.strand_thickness.1 != 0 {
            r.seek(self.strand_thickness.1, "strand thickness")?;
            let t = r.finite_f32s(s, 1, "strand thickness")?;
            t.iter().flat_map(|&t| std::iter::repeat_n(t, n)).collect()
        } else {
            vec![DEFAULT_THICKNESS; p]
        };
        if self.strand_uv.1 != 0 {
            r.seek(self.strand_uv.1, "strand UVs")?;
            let f = r.finite_f32s(2 * s, 2, "strand UV")?;
            g.strand_uvs = Some(f.chunks_exact(2).map(Vec2::from_slice).collect());
        }
        if self.vertex_color.1 != 0 {
            r.seek(self.vertex_color.1, "vertex colours")?;
            let f = r.finite_f32s(4 * p, 4, "vertex colour")?;
            g.colors = Some(f.chunks_exact(4).map(Vec3::from_slice).collect());
        }
        Ok(g)
    }
}

pub fn parse(data: &[u8]) -> Result<Groom, FormatError> {
    let mut r = Reader::new(data);
    let version = r.f32("version")?;
    check_version(version, 4.0)?;
    let strands = r.u32("numHairStrands")? as u64;
    let per_strand = r.u32("numVerticesPerStrand")? as u64;
    let mut off = [0usize; 5];
    for o in off.iter_mut() {
        *o = r.u32("array offsets")? as usize;
    }
    r.bytes(HEADER_SIZE - r.pos(), "reserved header words")?;
    TfxArrays {
        strands,
        per_strand,
        positions: (12, off[0]),
        position_size: 16,
        strand_uv: (16, off[1]),
        vertex_uv: (20, off[2]),
        strand_thickness: (24, off[3]),
        vertex_color: (28, off[4]),
        header_size: HEADER_SIZE,
    }
    .read(&mut r)
}

/// Writes a groom with a fixed point count per strand as TressFX 4: positions (w = 0 at
/// the root, 1 elsewhere), strand UVs when present, per-strand thickness (the root's).
pub fn write(g: &Groom) -> Result<Vec<u8>, AssetError> {
    g.validate().map_err(AssetError::Invalid)?;
    let n = g.uniform_points_per_strand().ok_or_else(|| {
        AssetError::Invalid("TressFX needs the same point count in every strand".into())
    })?;
    let s = g.strand_count();
    let pos_at = HEADER_SIZE;
    let uv_at = pos_at + s * n * 16;
    let thick_at = uv_at + if g.strand_uvs.is_some() { s * 8 } else { 0 };
    let mut w = Writer::default();
    w.f32(4.0);
    w.u32(s as u32);
    w.u32(n as u32);
    w.u32(pos_at as u32);
    w.u32(if g.strand_uvs.is_some() {
        uv_at as u32
    } else {
        0
    });
    w.u32(0);
    w.u32(thick_at as u32);
    w.u32(0);
    w.zeros(HEADER_SIZE - w.buf.len());
    for (i, p) in g.positions.iter().enumerate() {
        p.to_array().iter().for_each(|&v| w.f32(v));
        w.f32(if i % n == 0 { 0.0 } else { 1.0 });
    }
    if let Some(uv) = &g.strand_uvs {
        uv.iter().for_each(|u| {
            w.f32(u.x);
            w.f32(u.y)
        });
    }
    for st in 0..s {
        w.f32(g.thickness[st * n]);
    }
    Ok(w.buf)
}
