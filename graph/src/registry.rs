//! The pass-kind registry the compiler validates against.
//!
//! `graph/` knows no pass: `passes/` implements [`PassRegistry`] and the
//! compiler only asks whether a kind exists. Tests use [`KindList`].

/// What the compiler may ask about a pass kind.
pub trait PassRegistry {
    /// Whether `kind` (e.g. `"kulikov.raster"`) names a registered pass.
    fn contains(&self, kind: &str) -> bool;
    /// Every registered kind, for "did you mean" suggestions.
    fn kinds(&self) -> Vec<&str>;
}

/// A registry that is just a list of names.
#[derive(Debug, Clone, Default)]
pub struct KindList(pub Vec<String>);

impl KindList {
    pub fn new<I: IntoIterator<Item = S>, S: Into<String>>(kinds: I) -> Self {
        KindList(kinds.into_iter().map(Into::into).collect())
    }
}

impl PassRegistry for KindList {
    fn contains(&self, kind: &str) -> bool {
        self.0.iter().any(|k| k == kind)
    }
    fn kinds(&self) -> Vec<&str> {
        self.0.iter().map(String::as_str).collect()
    }
}

/// Accepts every kind: for tools that inspect a graph without the registry.
#[derive(Debug, Clone, Copy, Default)]
pub struct AnyKind;

impl PassRegistry for AnyKind {
    fn contains(&self, _: &str) -> bool {
        true
    }
    fn kinds(&self) -> Vec<&str> {
        Vec::new()
    }
}

/// The registered kind closest to `wanted`, if any is close enough to be a typo.
pub fn suggest<'a>(registry: &'a dyn PassRegistry, wanted: &str) -> Option<&'a str> {
    registry
        .kinds()
        .into_iter()
        .map(|k| (strsim::jaro_winkler(k, wanted), k))
        .filter(|(score, _)| *score > 0.85)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, k)| k)
}
