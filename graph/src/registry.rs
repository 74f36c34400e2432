//! The pass-kind registry the compiler validates against.
//!
//! `graph/` knows no pass: `passes/` implements [`PassRegistry`] and the
//! compiler only asks whether a kind exists and whether a pass's parameters
//! suit its kind. Tests use [`KindList`].

/// What is wrong with a pass's parameters.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamProblem {
    /// The offending key, a path inside the pass's `params` (`"tile"`), or
    /// empty when the whole block is wrong (not a map).
    pub key: String,
    /// What was expected; for an unknown key, the closest valid one.
    pub message: String,
}

/// What the compiler may ask about a pass kind.
pub trait PassRegistry {
    /// Whether `kind` (e.g. `"kulikov.raster"`) names a registered pass.
    fn contains(&self, kind: &str) -> bool;
    /// Every registered kind, for "did you mean" suggestions.
    fn kinds(&self) -> Vec<&str>;
    /// Checks a pass's parameters as the graph file wrote them. The default
    /// accepts anything (registries that know only names).
    fn check_params(&self, kind: &str, params: &ron::Value) -> Result<(), ParamProblem> {
        let _ = (kind, params);
        Ok(())
    }
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
