//! Loaders for real groom and mesh formats. Each parses from bytes (for fuzzing) and
//! every error carries a byte offset or a line.

pub mod cyhair;
pub mod envmap;
pub mod obj;
pub mod reader;
pub mod tfx2;
pub mod tfx3;
pub mod tfx4;

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{AssetError, FormatError, FormatErrorKind, Location};
use crate::groom::Groom;
use crate::mesh::TriMesh;

/// The most strands any header may declare.
pub const MAX_STRANDS: u64 = 20_000_000;
/// The most points any header may declare.
pub const MAX_POINTS: u64 = 500_000_000;
/// The most points one strand may have.
pub const MAX_POINTS_PER_STRAND: u64 = 65_536;

/// The length unit of a file's coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum Units {
    #[default]
    Metres,
    Centimetres,
    Millimetres,
    /// Multiply by this to get metres.
    Scale(f32),
}

impl Units {
    pub fn to_metres(self) -> f32 {
        match self {
            Units::Metres => 1.0,
            Units::Centimetres => 0.01,
            Units::Millimetres => 0.001,
            Units::Scale(s) => s,
        }
    }
}

/// Options for loading a groom file.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoadOptions {
    pub units: Units,
    /// Overrides the strand thickness (metres) when set.
    pub thickness: Option<f32>,
}

/// The groom and mesh file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    CyHair,
    Tfx2,
    Tfx3,
    Tfx4,
    Obj,
}

impl Format {
    /// Detects the format from the file contents and extension.
    pub fn detect(path: &Path, data: &[u8]) -> Result<Format, FormatError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        match ext.as_str() {
            "hair" => Ok(Format::CyHair),
            "obj" => Ok(Format::Obj),
            "tfx" => {
                if data.starts_with(b"version") {
                    return Ok(Format::Tfx2);
                }
                let v = data
                    .get(0..4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .ok_or_else(|| {
                        FormatError::at_byte(
                            0,
                            FormatErrorKind::Truncated {
                                what: "TressFX version",
                                needed: 4,
                                available: data.len() as u64,
                            },
                        )
                    })?;
                if (3.0..4.0).contains(&v) {
                    Ok(Format::Tfx3)
                } else if (4.0..5.0).contains(&v) {
                    Ok(Format::Tfx4)
                } else {
                    Err(FormatError::at_byte(
                        0,
                        FormatErrorKind::BadMagic {
                            expected: "TressFX text \"version\" or binary version 3.x/4.x".into(),
                            found: format!("{v}"),
                        },
                    ))
                }
            }
            _ => Err(FormatError::new(
                Location::File,
                FormatErrorKind::Syntax(format!(
                    "unknown file type {ext:?} (expected .hair, .tfx or .obj)"
                )),
            )),
        }
    }
}

pub fn read_file(path: &Path) -> Result<Vec<u8>, AssetError> {
    std::fs::read(path).map_err(|source| AssetError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Parses groom bytes of a known format into metres.
pub fn parse_groom(format: Format, data: &[u8], opts: &LoadOptions) -> Result<Groom, FormatError> {
    let mut g = match format {
        Format::CyHair => cyhair::parse(data)?,
        Format::Tfx2 => tfx2::parse(data)?,
        Format::Tfx3 => tfx3::parse(data)?,
        Format::Tfx4 => tfx4::parse(data)?,
        Format::Obj => {
            return Err(FormatError::new(
                Location::File,
                FormatErrorKind::Syntax("an OBJ file is a mesh, not a groom".into()),
            ));
        }
    };
    let s = opts.units.to_metres();
    // Thickness is given in metres by the files we know, so only positions scale.
    g.positions.iter_mut().for_each(|p| *p *= s);
    if let Some(t) = opts.thickness {
        g.thickness.iter_mut().for_each(|x| *x = t);
    }
    Ok(g)
}

/// Loads a groom file (.hair, .tfx), detecting the TressFX layout from its contents.
pub fn load_groom(path: &Path, opts: &LoadOptions) -> Result<Groom, AssetError> {
    let data = read_file(path)?;
    let _span = tracing::debug_span!("load_groom", path = %path.display()).entered();
    Format::detect(path, &data)
        .and_then(|f| parse_groom(f, &data, opts))
        .map_err(|e| AssetError::format(path, e))
}

/// Loads an OBJ mesh, scaled to metres.
pub fn load_mesh(path: &Path, units: Units) -> Result<TriMesh, AssetError> {
    let data = read_file(path)?;
    let mut m = obj::parse(&data).map_err(|e| AssetError::format(path, e))?;
    let s = units.to_metres();
    m.positions.iter_mut().for_each(|p| *p *= s);
    Ok(m)
}
