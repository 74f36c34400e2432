//! Error types. Every loader reports *what* is wrong and *where*: a byte offset for
//! binary formats, a line (and column where known) for text formats.

use std::fmt;
use std::path::PathBuf;

/// Where in a file a problem was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// Byte offset from the start of a binary file.
    Byte(usize),
    /// 1-based line of a text file.
    Line(usize),
    /// 1-based line and column of a text file.
    LineCol(usize, usize),
    /// The whole file (for example: it holds no triangles).
    File,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Byte(b) => write!(f, "byte {b}"),
            Location::Line(l) => write!(f, "line {l}"),
            Location::LineCol(l, c) => write!(f, "line {l}, column {c}"),
            Location::File => write!(f, "file"),
        }
    }
}

/// What is wrong with a file's contents.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FormatErrorKind {
    #[error("file ends early: needed {needed} bytes for {what}, {available} available")]
    Truncated {
        what: &'static str,
        needed: u64,
        available: u64,
    },
    #[error("{field} = {count} needs {needed} {unit}, but the file holds only {available}")]
    CountExceedsFile {
        field: &'static str,
        count: u64,
        needed: u64,
        available: u64,
        unit: &'static str,
    },
    #[error("{field} is zero")]
    ZeroCount { field: &'static str },
    #[error("{field} = {value} is absurd (at most {max} allowed)")]
    AbsurdCount {
        field: &'static str,
        value: u64,
        max: u64,
    },
    #[error("{what} {index} is not finite (NaN or Inf)")]
    NonFinite { what: &'static str, index: u64 },
    #[error("wrong magic: expected {expected}, found {found}")]
    BadMagic { expected: String, found: String },
    #[error("{0}")]
    Syntax(String),
    #[error("{0}")]
    Inconsistent(String),
}

/// A problem in a file's contents, with its location.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{location}: {kind}")]
pub struct FormatError {
    pub location: Location,
    pub kind: FormatErrorKind,
}

impl FormatError {
    pub fn new(location: Location, kind: FormatErrorKind) -> Self {
        Self { location, kind }
    }
    pub fn at_byte(offset: usize, kind: FormatErrorKind) -> Self {
        Self::new(Location::Byte(offset), kind)
    }
    pub fn at_line(line: usize, kind: FormatErrorKind) -> Self {
        Self::new(Location::Line(line), kind)
    }
    pub fn syntax(location: Location, msg: impl Into<String>) -> Self {
        Self::new(location, FormatErrorKind::Syntax(msg.into()))
    }
}

/// Any failure to load an asset or scene; the message names the file.
#[derive(Debug, thiserror::Error)]
pub enum AssetError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Bad contents of a groom or mesh file. Displays as `path: byte N: ...` or `path:LINE: ...`.
    #[error("{}{}", path.display(), format_location(error))]
    Format { path: PathBuf, error: FormatError },
    /// A scene file that does not parse or names something impossible. Displays as `path:line:col: ...`.
    #[error("{}:{line}:{col}: {message}", path.display())]
    Scene {
        path: PathBuf,
        line: usize,
        col: usize,
        message: String,
    },
    /// A request that cannot be carried out (for example writing a variable-length groom as TressFX).
    #[error("{0}")]
    Invalid(String),
}

fn format_location(e: &FormatError) -> String {
    match e.location {
        Location::Line(l) => format!(":{l}: {}", e.kind),
        Location::LineCol(l, c) => format!(":{l}:{c}: {}", e.kind),
        Location::Byte(b) => format!(": byte {b}: {}", e.kind),
        Location::File => format!(": {}", e.kind),
    }
}

impl AssetError {
    pub fn format(path: impl Into<PathBuf>, error: FormatError) -> Self {
        AssetError::Format {
            path: path.into(),
            error,
        }
    }
    /// The format error inside, if any (tests match on its kind).
    pub fn format_error(&self) -> Option<&FormatError> {
        match self {
            AssetError::Format { error, .. } => Some(error),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_file_and_location() {
        let e = AssetError::format(
            "a/b.tfx",
            FormatError::at_byte(
                12,
                FormatErrorKind::ZeroCount {
                    field: "numHairStrands",
                },
            ),
        );
        assert_eq!(e.to_string(), "a/b.tfx: byte 12: numHairStrands is zero");
        let e = AssetError::format(
            "h.tfx",
            FormatError::new(Location::LineCol(3, 7), FormatErrorKind::Syntax("x".into())),
        );
        assert_eq!(e.to_string(), "h.tfx:3:7: x");
    }
}
