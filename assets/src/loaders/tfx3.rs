//! TressFX 3 binary layout: a 296-byte header (f32 version, u32 numGuideHairStrands,
//! u32 numVerticesPerStrand, u32 numFollowHairsPerGuideHair, u32 bothEndsImmovable,
//! `u32 reserved1[31]`, then at byte 144 the offsets of vertices, per-strand thickness,
//! per-strand texcoords, per-vertex colours, guide-strand data and per-vertex texcoords,
//! `u32 reserved2[32]`); positions are float3.

use super::reader::Reader;
use super::tfx4::{TfxArrays, check_version};
use crate::error::FormatError;
use crate::groom::Groom;

pub const HEADER_SIZE: usize = 296;

pub fn parse(data: &[u8]) -> Result<Groom, FormatError> {
    let mut r = Reader::new(data);
    let version = r.f32("version")?;
    check_version(version, 3.0)?;
    let strands = r.u32("numGuideHairStrands")? as u64;
    let per_strand = r.u32("numVerticesPerStrand")? as u64;
    r.seek(144, "array offsets")?;
    let mut off = [0usize; 6];
    for o in off.iter_mut() {
        *o = r.u32("array offsets")? as usize;
    }
    r.seek(HEADER_SIZE, "reserved header words")?;
    TfxArrays {
        strands,
        per_strand,
        positions: (144, off[0]),
        position_size: 12,
        strand_thickness: (148, off[1]),
        strand_uv: (152, off[2]),
        vertex_color: (156, off[3]),
        vertex_uv: (164, off[5]),
        header_size: HEADER_SIZE,
    }
    .read(&mut r)
}
