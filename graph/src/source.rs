//! Source text, byte spans and a locator that maps RON value paths to spans.
//!
//! `ron` reports positions for syntax and type errors but keeps none for the
//! values it produced, and serde offers no way to ask. The compiler's own
//! errors (an unknown resource, a cycle) must still point at the offending
//! text, so after a successful parse we tokenise the same text once more and
//! record the span of every value under its serde path, for example
//! `passes[3].reads[1]`. The file already parsed as RON, so the tokeniser only
//! has to handle valid RON.

use std::collections::HashMap;
use std::sync::Arc;

/// A byte range in a source file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct Span {
    pub start: usize,
    pub end: usize,
}

impl Span {
    pub fn new(start: usize, end: usize) -> Self {
        Self { start, end }
    }
    pub fn len(&self) -> usize {
        self.end - self.start
    }
    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }
}

impl From<Span> for miette::SourceSpan {
    fn from(s: Span) -> Self {
        (s.start, s.len()).into()
    }
}

/// A named source file held in memory.
#[derive(Debug, Clone)]
pub struct Source {
    pub name: String,
    pub text: Arc<str>,
}

impl Source {
    pub fn new(name: impl Into<String>, text: impl Into<Arc<str>>) -> Self {
        Self {
            name: name.into(),
            text: text.into(),
        }
    }

    /// 1-based line and column (in characters) of a byte offset.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let col = before[line_start..].chars().count() + 1;
        (line, col)
    }

    /// Byte offset of a 1-based line and column, as `ron` reports them.
    pub fn offset_of(&self, line: usize, col: usize) -> usize {
        let mut offset = 0;
        for (i, l) in self.text.split_inclusive('\n').enumerate() {
            if i + 1 == line {
                let within: usize = l
                    .chars()
                    .take(col.saturating_sub(1))
                    .map(char::len_utf8)
                    .sum();
                return offset + within;
            }
            offset += l.len();
        }
        self.text.len()
    }

    pub fn named_source(&self) -> miette::NamedSource<Arc<str>> {
        miette::NamedSource::new(&self.name, self.text.clone()).with_language("ron")
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Open(char),
    Close,
    Comma,
    Colon,
    /// A string literal (its unescaped content is not needed, only the raw text).
    Str(String),
    /// Identifier, number, `true`/`false`, char literal.
    Word(String),
}

fn tokenize(text: &str) -> Vec<(Tok, Span)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        match c {
            b' ' | b'\t' | b'\r' | b'\n' => i += 1,
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                // RON block comments nest.
                let mut depth = 0usize;
                while i < b.len() {
                    if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
                        depth += 1;
                        i += 2;
                    } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        i += 1;
                    }
                }
            }
            b'#' => {
                // `#![enable(...)]` extension attributes carry no values.
                while i < b.len() && b[i] != b']' {
                    i += 1;
                }
                i += 1;
            }
            b'(' | b'[' | b'{' => {
                out.push((Tok::Open(c as char), Span::new(i, i + 1)));
                i += 1;
            }
            b')' | b']' | b'}' => {
                out.push((Tok::Close, Span::new(i, i + 1)));
                i += 1;
            }
            b',' => {
                out.push((Tok::Comma, Span::new(i, i + 1)));
                i += 1;
            }
            b':' => {
                out.push((Tok::Colon, Span::new(i, i + 1)));
                i += 1;
            }
            b'"' => {
                let start = i;
                i += 1;
                while i < b.len() && b[i] != b'"' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                i = (i + 1).min(b.len());
                let raw = &text[start + 1..i.saturating_sub(1).max(start + 1)];
                out.push((Tok::Str(raw.to_string()), Span::new(start, i)));
            }
            b'r' if matches!(b.get(i + 1), Some(b'"' | b'#')) => {
                let start = i;
                i += 1;
                let mut hashes = 0;
                while b.get(i) == Some(&b'#') {
                    hashes += 1;
                    i += 1;
                }
                i += 1; // opening quote
                let body = i;
                let closing: String = std::iter::once('"')
                    .chain("#".repeat(hashes).chars())
                    .collect();
                let end = text[i..].find(&closing).map_or(b.len(), |p| i + p);
                i = (end + closing.len()).min(b.len());
                out.push((Tok::Str(text[body..end].to_string()), Span::new(start, i)));
            }
            b'\'' => {
                let start = i;
                i += 1;
                while i < b.len() && b[i] != b'\'' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                i = (i + 1).min(b.len());
                out.push((Tok::Word(text[start..i].to_string()), Span::new(start, i)));
            }
            _ => {
                let start = i;
                while i < b.len() && !b" \t\r\n()[]{},:\"".contains(&b[i]) {
                    i += 1;
                }
                if i == start {
                    i += 1; // unknown byte: skip it rather than loop
                    continue;
                }
                out.push((Tok::Word(text[start..i].to_string()), Span::new(start, i)));
            }
        }
    }
    out
}

/// Spans of every value in a RON document, keyed by serde path.
///
/// Paths read like field accesses: `resources[2].name`, `passes[0].params.tile_size`.
#[derive(Debug, Default, Clone)]
pub struct Locator {
    spans: HashMap<String, Span>,
    /// Spans of struct field names and map keys, by the path of their value.
    keys: HashMap<String, Span>,
}

struct Frame {
    /// Path of the value this group belongs to.
    path: String,
    /// Next positional index inside a list or tuple.
    next_index: usize,
    /// Field or map key seen just before the value that is about to start.
    pending_key: Option<String>,
    /// Value started at the word before `(`, closed with this group.
    value_start: usize,
}

impl Locator {
    pub fn new(text: &str) -> Self {
        let toks = tokenize(text);
        let mut spans = HashMap::new();
        let mut keys = HashMap::new();
        let mut stack: Vec<Frame> = vec![Frame {
            path: String::new(),
            next_index: 0,
            pending_key: Some(String::new()),
            value_start: 0,
        }];
        let mut i = 0;
        while i < toks.len() {
            let (tok, span) = &toks[i];
            let next_is_colon = matches!(toks.get(i + 1), Some((Tok::Colon, _)));
            match tok {
                Tok::Word(w) | Tok::Str(w) if next_is_colon => {
                    if let Some(top) = stack.last_mut() {
                        let path = if top.path.is_empty() {
                            w.clone()
                        } else {
                            format!("{}.{w}", top.path)
                        };
                        keys.insert(path, *span);
                        top.pending_key = Some(w.clone());
                    }
                    i += 2;
                    continue;
                }
                Tok::Comma | Tok::Colon => {}
                Tok::Close => {
                    if let Some(frame) = stack.pop() {
                        spans.insert(frame.path, Span::new(frame.value_start, span.end));
                    }
                }
                Tok::Open(_) | Tok::Word(_) | Tok::Str(_) => {
                    let Some(top) = stack.last_mut() else { break };
                    let path = match top.pending_key.take() {
                        Some(k) if top.path.is_empty() => k,
                        Some(k) if k.is_empty() => top.path.clone(),
                        Some(k) => format!("{}.{k}", top.path),
                        None => {
                            let p = format!("{}[{}]", top.path, top.next_index);
                            top.next_index += 1;
                            p
                        }
                    };
                    // A word directly followed by a group is a struct or enum
                    // name: the group is part of the same value.
                    let opens_group = matches!(toks.get(i + 1), Some((Tok::Open(_), _)));
                    match tok {
                        Tok::Open(_) => stack.push(Frame {
                            path,
                            next_index: 0,
                            pending_key: None,
                            value_start: span.start,
                        }),
                        Tok::Word(_) if opens_group => {
                            stack.push(Frame {
                                path,
                                next_index: 0,
                                pending_key: None,
                                value_start: span.start,
                            });
                            i += 1; // consume the opening bracket
                        }
                        _ => {
                            spans.insert(path, *span);
                        }
                    }
                }
            }
            i += 1;
        }
        Self { spans, keys }
    }

    /// The span of the key (field name or map key) whose value is at `path`.
    pub fn key_span(&self, path: &str) -> Option<Span> {
        self.keys.get(path).copied()
    }

    /// The span of the value at `path`, or of its nearest enclosing value.
    pub fn span(&self, path: &str) -> Span {
        let mut p = path;
        loop {
            if let Some(s) = self.spans.get(p) {
                return *s;
            }
            match p.rfind(['.', '[']) {
                Some(i) => p = &p[..i],
                None => return self.spans.get("").copied().unwrap_or_default(),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOC: &str = r##"// a comment with "quotes" and (parens)
Graph(
    name: "g", /* nested /* comment */ */
    resources: [
        Buffer(name: "a", size: PerElement(Strands, 16)),
        Image(name: r#"b"#, format: Rgba8Unorm),
    ],
    passes: [
        Pass(name: "p", params: {"tile": 64, "flags": [true, false]}, reads: ["a", "indirect:b"]),
    ],
)"##;

    fn text_at(path: &str) -> &'static str {
        let s = Locator::new(DOC).span(path);
        &DOC[s.start..s.end]
    }

    #[test]
    fn finds_values_by_path() {
        assert_eq!(text_at("name"), "\"g\"");
        assert_eq!(text_at("resources[0].name"), "\"a\"");
        assert_eq!(text_at("resources[0].size"), "PerElement(Strands, 16)");
        assert_eq!(text_at("resources[0].size[1]"), "16");
        assert_eq!(text_at("resources[1].name"), "r#\"b\"#");
        assert_eq!(text_at("passes[0].params.tile"), "64");
        assert_eq!(text_at("passes[0].params.flags[1]"), "false");
        assert_eq!(text_at("passes[0].reads[1]"), "\"indirect:b\"");
        let key = Locator::new(DOC).key_span("passes[0].params.tile").unwrap();
        assert_eq!(&DOC[key.start..key.end], "\"tile\"");
    }

    #[test]
    fn falls_back_to_enclosing_value() {
        assert_eq!(
            text_at("passes[0].writes[3]"),
            &DOC[DOC.find("Pass(").unwrap()..DOC.rfind("]),").unwrap() + 2]
        );
    }

    #[test]
    fn line_and_column() {
        let src = Source::new("x.ron", "ab\ncdé\nf");
        assert_eq!(src.line_col(0), (1, 1));
        assert_eq!(src.line_col(4), (2, 2));
        assert_eq!(src.offset_of(3, 1), src.text.len() - 1);
        assert_eq!(src.offset_of(2, 3), 5);
    }
}
