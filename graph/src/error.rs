//! Diagnostics: every error names the file, line and column, and the things involved.

use crate::source::{Source, Span};
use miette::{Diagnostic, LabeledSpan, NamedSource, SourceCode};
use std::fmt;
use std::sync::Arc;

/// What went wrong; tests and tools match on this rather than on wording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum ErrorKind {
    Io,
    /// Not valid RON, or not the graph schema.
    Syntax,
    DuplicateName,
    UnknownResource,
    UnknownPassKind,
    /// A pass parameter its kind does not take, of the wrong type, or out of range.
    BadParam,
    /// An access the resource type cannot take (sampling a buffer), or a bad usage prefix.
    BadAccess,
    /// A transient (or atomic update) read before any pass writes it.
    ReadBeforeWrite,
    Cycle,
    /// Two writers of one resource with no order between them.
    UnorderedWriters,
    /// A pass on a queue that cannot perform one of its accesses.
    QueueCannotAccess,
    OutputNotWritten,
    /// A size that overflows or is zero once the scene's quantities are known.
    Size,
}

impl ErrorKind {
    fn code(self) -> &'static str {
        match self {
            ErrorKind::Io => "graph::io",
            ErrorKind::Syntax => "graph::syntax",
            ErrorKind::DuplicateName => "graph::duplicate_name",
            ErrorKind::UnknownResource => "graph::unknown_resource",
            ErrorKind::UnknownPassKind => "graph::unknown_pass_kind",
            ErrorKind::BadParam => "graph::bad_param",
            ErrorKind::BadAccess => "graph::bad_access",
            ErrorKind::ReadBeforeWrite => "graph::read_before_write",
            ErrorKind::Cycle => "graph::cycle",
            ErrorKind::UnorderedWriters => "graph::unordered_writers",
            ErrorKind::QueueCannotAccess => "graph::queue_cannot_access",
            ErrorKind::OutputNotWritten => "graph::output_not_written",
            ErrorKind::Size => "graph::size",
        }
    }
}

/// One diagnostic with its location in a graph file.
#[derive(Debug, Clone)]
pub struct GraphError {
    pub kind: ErrorKind,
    pub message: String,
    pub file: String,
    /// 1-based.
    pub line: usize,
    /// 1-based, in characters.
    pub col: usize,
    source: NamedSource<Arc<str>>,
    labels: Vec<LabeledSpan>,
    help: Option<String>,
}

impl GraphError {
    /// An error whose primary location is `span` in `src`.
    pub fn new(kind: ErrorKind, src: &Source, span: Span, message: impl Into<String>) -> Self {
        let (line, col) = src.line_col(span.start);
        Self {
            kind,
            message: message.into(),
            file: src.name.clone(),
            line,
            col,
            source: src.named_source(),
            labels: vec![LabeledSpan::new_primary_with_span(
                Some("here".into()),
                span,
            )],
            help: None,
        }
    }

    /// Replaces the primary label's text.
    pub fn primary(mut self, text: impl Into<String>) -> Self {
        if let Some(first) = self.labels.first_mut() {
            *first = LabeledSpan::new_primary_with_span(Some(text.into()), *first.inner());
        }
        self
    }

    /// Adds a secondary label pointing at related text.
    pub fn label(mut self, span: Span, text: impl Into<String>) -> Self {
        self.labels
            .push(LabeledSpan::new_with_span(Some(text.into()), span));
        self
    }

    pub fn help(mut self, text: impl Into<String>) -> Self {
        self.help = Some(text.into());
        self
    }
}

impl fmt::Display for GraphError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}:{}: {}",
            self.file, self.line, self.col, self.message
        )
    }
}

impl std::error::Error for GraphError {}

impl Diagnostic for GraphError {
    fn code<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        Some(Box::new(self.kind.code()))
    }
    fn help<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        self.help
            .as_ref()
            .map(|h| Box::new(h) as Box<dyn fmt::Display>)
    }
    fn source_code(&self) -> Option<&dyn SourceCode> {
        Some(&self.source)
    }
    fn labels(&self) -> Option<Box<dyn Iterator<Item = LabeledSpan> + '_>> {
        Some(Box::new(self.labels.iter().cloned()))
    }
}

/// All errors found in one compile; validation reports as many as it can at once.
#[derive(Debug, Clone)]
pub struct GraphErrors(pub Vec<GraphError>);

impl GraphErrors {
    pub fn first(&self) -> &GraphError {
        &self.0[0]
    }
    pub fn kinds(&self) -> Vec<ErrorKind> {
        self.0.iter().map(|e| e.kind).collect()
    }
}

impl From<GraphError> for GraphErrors {
    fn from(e: GraphError) -> Self {
        GraphErrors(vec![e])
    }
}

impl fmt::Display for GraphErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.first())?;
        if self.0.len() > 1 {
            write!(f, " (and {} more)", self.0.len() - 1)?;
        }
        Ok(())
    }
}

impl std::error::Error for GraphErrors {}

impl Diagnostic for GraphErrors {
    fn code<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        self.first().code()
    }
    fn help<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        self.first().help()
    }
    fn source_code(&self) -> Option<&dyn SourceCode> {
        self.first().source_code()
    }
    fn labels(&self) -> Option<Box<dyn Iterator<Item = LabeledSpan> + '_>> {
        self.first().labels()
    }
    fn related<'a>(&'a self) -> Option<Box<dyn Iterator<Item = &'a dyn Diagnostic> + 'a>> {
        if self.0.len() < 2 {
            return None;
        }
        Some(Box::new(self.0[1..].iter().map(|e| e as &dyn Diagnostic)))
    }
}
