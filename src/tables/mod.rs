//! README tables generated from committed measurements, so that every number
//! in README traces to a file under `benches/results/`.
//!
//! A generated block in a Markdown file starts with a marker that names its
//! generator and inputs, and ends with `<!-- end generated -->`:
//!
//! ```text
//! <!-- generated: agree benches/results/agree-h100/showcase.json -->
//! ...the table...
//! <!-- end generated -->
//! ```
//!
//! `strandgraph tables README.md` rewrites every block from its inputs;
//! `--check` fails if any block differs from what its inputs give (CI runs
//! it, `tests/readme_tables.rs`). Generators:
//! - `agree FILE.json...`: per-pass agreement ([`crate::agree::summary`]);
//! - `bench FILE.json`: frame medians per pipeline variant and view;
//! - `bench-flip FILE.json`: mean FLIP against the reference per variant
//!   and view, for the variants whose pipeline has one;
//! - `bench-motion FILE.json`: per cell, the simulation passes' time, the
//!   frame's, FLIP and flicker ([`motion`]);
//! - `bench-passes FILE.json VARIANT [VIEW...]`: one variant's per-pass
//!   medians per view, or only the views named (`_` in VARIANT stands for a
//!   space: `Kulikov:_all_optimisations`);
//! - `bench-delta BEFORE.json AFTER.json VARIANT VIEW`: one cell's per-pass
//!   medians in two runs of the same device, and the change.

pub mod bench;
mod motion;

use serde_json::Value;
use std::path::{Path, PathBuf};

const OPEN: &str = "<!-- generated: ";
const CLOSE: &str = "<!-- end generated -->";

/// One generated block of a document: where it sits and what makes it.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// Byte range of the block's body (between the two marker lines).
    pub body: std::ops::Range<usize>,
    /// 1-based line of the opening marker, for messages.
    pub line: usize,
    /// The generator and its arguments, as written in the marker.
    pub command: Vec<String>,
}

/// The generated blocks of `doc`, in order. An opening marker without a
/// closing one, or a nested one, is an error naming its line.
pub fn blocks(doc: &str) -> Result<Vec<Block>, String> {
    let mut out = Vec::new();
    let mut open: Option<(usize, usize, Vec<String>)> = None;
    let mut offset = 0;
    for (i, line) in doc.split_inclusive('\n').enumerate() {
        let text = line.trim();
        if let Some(rest) = text.strip_prefix(OPEN) {
            if let Some((l, ..)) = open {
                return Err(format!(
                    "line {}: a generated block opens inside the one opened at line {l}",
                    i + 1
                ));
            }
            let command = rest
                .strip_suffix("-->")
                .ok_or(format!("line {}: the marker does not end with -->", i + 1))?
                .split_whitespace()
                .map(str::to_string)
                .collect();
            open = Some((i + 1, offset + line.len(), command));
        } else if text == CLOSE {
            let (l, start, command) = open
                .take()
                .ok_or(format!("line {}: `{CLOSE}` closes no block", i + 1))?;
            out.push(Block {
                body: start..offset,
                line: l,
                command,
            });
        }
        offset += line.len();
    }
    match open {
        Some((l, ..)) => Err(format!("line {l}: the generated block is never closed")),
        None => Ok(out),
    }
}

/// What `command` generates; input paths resolve against `root`.
pub fn generate(command: &[String], root: &Path) -> Result<String, String> {
    let read = |rel: &str| -> Result<Value, String> {
        let path: PathBuf = root.join(rel);
        let text = std::fs::read_to_string(&path).map_err(|e| format!("{rel}: {e}"))?;
        serde_json::from_str(&text).map_err(|e| format!("{rel}: {e}"))
    };
    match command {
        [kind, files @ ..] if kind == "agree" && !files.is_empty() => {
            let mut md = String::new();
            for f in files {
                let title = Path::new(f)
                    .file_stem()
                    .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
                let table = crate::agree::summary::markdown(&title, &read(f)?)
                    .map_err(|e| format!("{f}: {e}"))?;
                md.push_str(&table);
                md.push('\n');
            }
            Ok(md)
        }
        [kind, file] if kind == "bench" => {
            bench::frame_table(&read(file)?).map_err(|e| format!("{file}: {e}"))
        }
        [kind, file] if kind == "bench-flip" => {
            bench::flip_table(&read(file)?).map_err(|e| format!("{file}: {e}"))
        }
        [kind, file] if kind == "bench-motion" => {
            motion::table(&read(file)?).map_err(|e| format!("{file}: {e}"))
        }
        [kind, file, variant, views @ ..] if kind == "bench-passes" => {
            bench::pass_table(&read(file)?, &variant.replace('_', " "), views)
                .map_err(|e| format!("{file}: {e}"))
        }
        [kind, before, after, variant, view] if kind == "bench-delta" => bench::delta_table(
            &read(before)?,
            &read(after)?,
            &variant.replace('_', " "),
            view,
        ),
        _ => Err(format!(
            "unknown generator `{}` (agree FILE.json..., bench FILE.json, bench-flip FILE.json, bench-motion FILE.json, bench-passes FILE.json VARIANT [VIEW...], bench-delta BEFORE.json AFTER.json VARIANT VIEW)",
            command.join(" ")
        )),
    }
}

/// `doc` with every generated block rewritten, and the lines of the blocks
/// that changed.
pub fn regenerate(doc: &str, root: &Path) -> Result<(String, Vec<usize>), String> {
    let mut out = String::with_capacity(doc.len());
    let mut changed = Vec::new();
    let mut at = 0;
    for b in blocks(doc)? {
        let body = generate(&b.command, root).map_err(|e| format!("line {}: {e}", b.line))?;
        let body = format!("\n{}\n", body.trim());
        if doc[b.body.clone()] != body {
            changed.push(b.line);
        }
        out.push_str(&doc[at..b.body.start]);
        out.push_str(&body);
        at = b.body.end;
    }
    out.push_str(&doc[at..]);
    Ok((out, changed))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_blocks_and_reports_unclosed_ones() {
        let doc = "a\n<!-- generated: bench x.json -->\nold\n<!-- end generated -->\nb\n";
        let b = blocks(doc).unwrap();
        assert_eq!(b.len(), 1);
        assert_eq!(b[0].line, 2);
        assert_eq!(b[0].command, ["bench", "x.json"]);
        assert_eq!(&doc[b[0].body.clone()], "old\n");
        let err = blocks("<!-- generated: bench x.json -->\nold\n").unwrap_err();
        assert!(
            err.contains("line 1") && err.contains("never closed"),
            "{err}"
        );
        let err = blocks("x\n<!-- end generated -->\n").unwrap_err();
        assert!(err.contains("line 2"), "{err}");
    }

    #[test]
    fn unknown_generator_is_an_error_naming_the_line() {
        let doc = "<!-- generated: plot x.json -->\n<!-- end generated -->\n";
        let err = regenerate(doc, Path::new(".")).unwrap_err();
        assert!(
            err.starts_with("line 1: unknown generator `plot x.json`"),
            "{err}"
        );
    }
}
