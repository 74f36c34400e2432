//! Where a GPU output may differ from the CPU's, and why. Everything not
//! listed here compares under [`default_rule`]: buffers bit-exact, float
//! images within a few ULPs. Every exception states what differs and the
//! measurement behind its bound; `outliers` is the fraction of elements
//! allowed outside the rule (0: none).

use super::compare::{Rule, default_rule};
use strandgraph_graph::schema::ResourceDecl;

/// How one output is judged.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Judgement {
    pub rule: Rule,
    /// Fraction of elements allowed outside `rule`.
    pub outliers: f64,
    /// Why it is looser than the resource's default, if it is.
    pub why: Option<&'static str>,
}

/// The judgement for output `binding` of a pass of `kind`.
pub fn rule(kind: &str, binding: &str, decl: &ResourceDecl) -> Judgement {
    EXCEPTIONS
        .iter()
        .find(|e| e.kind == kind && e.binding == binding)
        .map_or(
            Judgement {
                rule: default_rule(decl),
                outliers: 0.0,
                why: None,
            },
            |e| Judgement {
                rule: e.rule,
                outliers: e.outliers,
                why: Some(e.why),
            },
        )
}

/// Inputs a backend must produce itself: the isolated pass is given this
/// backend's own output of the named upstream pass kind instead of the
/// CPU's words, and why.
pub fn own_input(kind: &str, binding: &str) -> Option<(&'static str, &'static str)> {
    OWN_INPUTS
        .iter()
        .find(|o| o.0 == kind && o.1 == binding)
        .map(|o| (o.2, o.3))
}

static OWN_INPUTS: &[(&str, &str, &str, &str)] = &[(
    "scene.opaque",
    "scene.depth",
    "scene.depth_prepass",
    "a depth-equal test passes only against depth from the same rasterizer: each backend shades over its own prepass depth",
)];

struct Exception {
    kind: &'static str,
    binding: &'static str,
    rule: Rule,
    outliers: f64,
    why: &'static str,
}

static EXCEPTIONS: &[Exception] = &[];
