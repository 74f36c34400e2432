//! TressFX 2 ASCII layout: header lines (`version`, `scale`, `rotation`, `translation`,
//! ..., `numStrands N`, `is sorted`), then per strand `strand i numVerts n texcoord u v`
//! followed by n lines `x y z`. Real files hold oddities such as `texcoord 0.000000 000000`;
//! like the reference tools (sscanf), texcoords parse a numeric prefix and default to 0.

use glam::{EulerRot, Quat, Vec2, Vec3};

use super::{MAX_POINTS_PER_STRAND, MAX_STRANDS};
use crate::error::{FormatError, FormatErrorKind, Location};
use crate::groom::{DEFAULT_THICKNESS, Groom};

fn syntax(line: usize, col: usize, msg: impl Into<String>) -> FormatError {
    FormatError::syntax(Location::LineCol(line, col), msg)
}

/// Splits a line into (1-based column, token) pairs.
fn tokens(line: &str) -> impl Iterator<Item = (usize, &str)> {
    line.split_ascii_whitespace()
        .map(move |t| (t.as_ptr() as usize - line.as_ptr() as usize + 1, t))
}

fn float(
    line_no: usize,
    tok: Option<(usize, &str)>,
    what: &str,
    eol: usize,
) -> Result<f32, FormatError> {
    let (col, t) = tok.ok_or_else(|| syntax(line_no, eol, format!("missing {what}")))?;
    let v: f32 = t
        .parse()
        .map_err(|_| syntax(line_no, col, format!("{what} {t:?} is not a number")))?;
    if !v.is_finite() {
        return Err(FormatError::new(
            Location::LineCol(line_no, col),
            FormatErrorKind::NonFinite {
                what: "vertex coordinate",
                index: 0,
            },
        ));
    }
    Ok(v)
}

/// The numeric prefix of a token, as sscanf("%f") reads it; 0 when there is none.
fn lenient_float(t: Option<&str>) -> f32 {
    let t = t.unwrap_or("");
    (1..=t.len())
        .rev()
        .filter(|&i| t.is_char_boundary(i))
        .find_map(|i| t[..i].parse::<f32>().ok())
        .filter(|v| v.is_finite())
        .unwrap_or(0.0)
}

fn count(
    line_no: usize,
    tok: Option<(usize, &str)>,
    field: &'static str,
    max: u64,
    eol: usize,
) -> Result<u64, FormatError> {
    let (col, t) = tok.ok_or_else(|| syntax(line_no, eol, format!("missing {field}")))?;
    let v: u64 = t
        .parse()
        .map_err(|_| syntax(line_no, col, format!("{field} {t:?} is not a count")))?;
    let loc = Location::LineCol(line_no, col);
    if v == 0 {
        return Err(FormatError::new(loc, FormatErrorKind::ZeroCount { field }));
    }
    if v > max {
        return Err(FormatError::new(
            loc,
            FormatErrorKind::AbsurdCount {
                field,
                value: v,
                max,
            },
        ));
    }
    Ok(v)
}

pub fn parse(data: &[u8]) -> Result<Groom, FormatError> {
    let text = std::str::from_utf8(data).map_err(|e| {
        FormatError::at_byte(
            e.valid_up_to(),
            FormatErrorKind::Syntax("not UTF-8 text".into()),
        )
    })?;
    let lines: Vec<&str> = text.lines().collect();
    let mut i = 0usize; // index into lines; line number is i + 1
    let first = lines.first().map(|l| l.trim()).unwrap_or("");
    if !first.starts_with("version") {
        return Err(FormatError::new(
            Location::Line(1),
            FormatErrorKind::BadMagic {
                expected: "\"version 2.0\"".into(),
                found: format!("{:?}", first.chars().take(20).collect::<String>()),
            },
        ));
    }
    let (mut scale, mut rot, mut trans) = (1.0f32, Vec3::ZERO, Vec3::ZERO);
    let mut num_strands = None;
    while let Some(line) = lines.get(i) {
        let ln = i + 1;
        let eol = line.len() + 1;
        let mut t = tokens(line);
        match t.next().map(|x| x.1) {
            Some("strand") => break,
            Some("scale") => scale = float(ln, t.next(), "scale", eol)?,
            Some("rotation") => {
                rot = Vec3::new(
                    float(ln, t.next(), "rotation", eol)?,
                    float(ln, t.next(), "rotation", eol)?,
                    float(ln, t.next(), "rotation", eol)?,
                )
            }
            Some("translation") => {
                trans = Vec3::new(
                    float(ln, t.next(), "translation", eol)?,
                    float(ln, t.next(), "translation", eol)?,
                    float(ln, t.next(), "translation", eol)?,
                )
            }
            Some("numStrands") => {
                num_strands = Some((ln, count(ln, t.next(), "numStrands", MAX_STRANDS, eol)?))
            }
            _ => {}
        }
        i += 1;
    }
    let (ns_line, n_strands) = num_strands.ok_or_else(|| {
        FormatError::at_line(
            i.min(lines.len()).max(1),
            FormatErrorKind::Syntax("no numStrands line before the first strand".into()),
        )
    })?;
    // Each strand needs at least two lines: validate before allocating.
    let remaining = lines.len().saturating_sub(i) as u64;
    if n_strands.saturating_mul(2) > remaining {
        return Err(FormatError::at_line(
            ns_line,
            FormatErrorKind::CountExceedsFile {
                field: "numStrands",
                count: n_strands,
                needed: n_strands.saturating_mul(2),
                available: remaining,
                unit: "lines",
            },
        ));
    }
    let rotation = Quat::from_euler(
        EulerRot::XYZ,
        rot.x.to_radians(),
        rot.y.to_radians(),
        rot.z.to_radians(),
    );
    let mut g = Groom {
        strand_offsets: Vec::with_capacity(n_strands as usize + 1),
        ..Default::default()
    };
    g.strand_offsets.push(0);
    let mut uvs = Vec::with_capacity(n_strands as usize);
    for s in 0..n_strands {
        let line = lines.get(i).ok_or_else(|| {
            FormatError::at_line(
                i + 1,
                FormatErrorKind::Truncated {
                    what: "strand header",
                    needed: n_strands,
                    available: s,
                },
            )
        })?;
        let ln = i + 1;
        let eol = line.len() + 1;
        let toks: Vec<(usize, &str)> = tokens(line).collect();
        let key = |k: &str| toks.iter().position(|&(_, t)| t == k);
        if toks.first().map(|t| t.1) != Some("strand") {
            return Err(syntax(
                ln,
                1,
                format!("expected `strand {s} numVerts n ...`"),
            ));
        }
        let nv_at = key("numVerts").ok_or_else(|| syntax(ln, eol, "missing numVerts"))?;
        let n = count(
            ln,
            toks.get(nv_at + 1).copied(),
            "numVerts",
            MAX_POINTS_PER_STRAND,
            eol,
        )?;
        let left = lines.len().saturating_sub(i + 1) as u64;
        if n > left {
            return Err(FormatError::new(
                Location::LineCol(ln, toks.get(nv_at + 1).map_or(eol, |t| t.0)),
                FormatErrorKind::CountExceedsFile {
                    field: "numVerts",
                    count: n,
                    needed: n,
                    available: left,
                    unit: "lines",
                },
            ));
        }
        let uv = key("texcoord").map_or(Vec2::ZERO, |k| {
            Vec2::new(
                lenient_float(toks.get(k + 1).map(|t| t.1)),
                lenient_float(toks.get(k + 2).map(|t| t.1)),
            )
        });
        uvs.push(uv);
        i += 1;
        for _ in 0..n {
            let line = lines.get(i).copied().unwrap_or("");
            let ln = i + 1;
            let eol = line.len() + 1;
            let mut t = tokens(line);
            let p = Vec3::new(
                float(ln, t.next(), "x", eol)?,
                float(ln, t.next(), "y", eol)?,
                float(ln, t.next(), "z", eol)?,
            );
            g.positions.push(rotation * (p * scale) + trans);
            i += 1;
        }
        g.strand_offsets.push(g.positions.len() as u32);
    }
    g.thickness = vec![DEFAULT_THICKNESS; g.positions.len()];
    g.strand_uvs = Some(uvs);
    Ok(g)
}

/// Writes a groom as TressFX 2 text (used by tests).
pub fn write(g: &Groom) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let max = (0..g.strand_count())
        .map(|i| g.strand_range(i).len())
        .max()
        .unwrap_or(0);
    let _ = write!(
        s,
        "version 2.0\nscale 1.0\nrotation 0 0 0\ntranslation 0 0 0\nbothEndsImmovable 0\n\
         maxNumVerticesInStrand {max}\nnumFollowHairsPerGuideHair 0\nmaxRadiusAroundGuideHair 0\n\
         numStrands {}\nis sorted 1\n",
        g.strand_count()
    );
    for i in 0..g.strand_count() {
        let uv = g.strand_uvs.as_ref().map_or(Vec2::ZERO, |u| u[i]);
        let _ = writeln!(
            s,
            "strand {i} numVerts {} texcoord {} {}",
            g.strand_range(i).len(),
            uv.x,
            uv.y
        );
        for p in g.strand(i) {
            let _ = writeln!(s, "{} {} {}", p.x, p.y, p.z);
        }
    }
    s
}
