//! Wavefront OBJ meshes through `tobj`, triangulated. A line scan first reports bad
//! vertices and face indices with their line and column, which `tobj` does not.

use glam::Vec3;

use crate::error::{FormatError, FormatErrorKind, Location};
use crate::mesh::TriMesh;

/// Scans `v` and `f` lines for unparsable or non-finite numbers and out-of-range indices.
fn prescan(text: &str) -> Result<(), FormatError> {
    let mut vertices: i64 = 0;
    let mut texcoords: i64 = 0;
    let mut normals: i64 = 0;
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let col = |t: &str| t.as_ptr() as usize - line.as_ptr() as usize + 1;
        let mut toks = line.split_ascii_whitespace();
        match toks.next() {
            Some("v") => {
                for k in 0..3 {
                    let t = toks.next().ok_or_else(|| {
                        FormatError::syntax(
                            Location::LineCol(ln, line.len() + 1),
                            format!("vertex needs 3 coordinates, found {k}"),
                        )
                    })?;
                    let v: f32 = t.parse().map_err(|_| {
                        FormatError::syntax(
                            Location::LineCol(ln, col(t)),
                            format!("vertex coordinate {t:?} is not a number"),
                        )
                    })?;
                    if !v.is_finite() {
                        return Err(FormatError::new(
                            Location::LineCol(ln, col(t)),
                            FormatErrorKind::NonFinite {
                                what: "vertex",
                                index: vertices as u64,
                            },
                        ));
                    }
                }
                vertices += 1;
            }
            Some("vt") => texcoords += 1,
            Some("vn") => normals += 1,
            Some("f") => {
                let mut n = 0;
                for t in toks {
                    n += 1;
                    // v, v/vt, v//vn or v/vt/vn; the vertex index is required.
                    for (k, idx) in t.split('/').enumerate() {
                        if k > 0 && idx.is_empty() {
                            continue;
                        }
                        let (what, count) = match k {
                            0 => ("vertex", vertices),
                            1 => ("texcoord", texcoords),
                            _ => ("normal", normals),
                        };
                        let v: i64 = idx.parse().map_err(|_| {
                            FormatError::syntax(
                                Location::LineCol(ln, col(t)),
                                format!("face vertex {t:?} has a bad {what} index"),
                            )
                        })?;
                        let resolved = if v < 0 { count + v } else { v - 1 };
                        if k > 2 || v == 0 || resolved < 0 || resolved >= count {
                            return Err(FormatError::new(
                                Location::LineCol(ln, col(t)),
                                FormatErrorKind::Inconsistent(format!(
                                    "face {what} index {v} is out of range: {count} so far"
                                )),
                            ));
                        }
                    }
                }
                if n < 3 {
                    return Err(FormatError::syntax(
                        Location::Line(ln),
                        format!("a face needs at least 3 vertices, found {n}"),
                    ));
                }
            }
            _ => {}
        }
    }
    Ok(())
}

pub fn parse(data: &[u8]) -> Result<TriMesh, FormatError> {
    let text = std::str::from_utf8(data).map_err(|e| {
        FormatError::at_byte(
            e.valid_up_to(),
            FormatErrorKind::Syntax("not UTF-8 text".into()),
        )
    })?;
    prescan(text)?;
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &opts, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| FormatError::syntax(Location::File, format!("OBJ: {e}")))?;
    let mut mesh = TriMesh::default();
    for m in &models {
        let base = mesh.positions.len() as u32;
        let pos = &m.mesh.positions;
        mesh.positions
            .extend(pos.chunks_exact(3).map(Vec3::from_slice));
        let n = (pos.len() / 3) as u32;
        for t in m.mesh.indices.chunks_exact(3) {
            if t.iter().any(|&i| i >= n) {
                return Err(FormatError::new(
                    Location::File,
                    FormatErrorKind::Inconsistent(format!(
                        "model {:?} has an index out of range",
                        m.name
                    )),
                ));
            }
            mesh.triangles.push([base + t[0], base + t[1], base + t[2]]);
        }
    }
    if mesh.positions.is_empty() {
        return Err(FormatError::new(
            Location::File,
            FormatErrorKind::ZeroCount {
                field: "vertex count",
            },
        ));
    }
    if mesh.triangles.is_empty() {
        return Err(FormatError::new(
            Location::File,
            FormatErrorKind::ZeroCount {
                field: "face count",
            },
        ));
    }
    Ok(mesh)
}
