//! Where a GPU output may differ from the CPU's, and why. Everything not
//! listed here compares under [`default_rule`]: buffers bit-exact, float
//! images within a few ULPs.

use super::compare::{Rule, default_rule};
use strandgraph_graph::schema::ResourceDecl;

/// The rule for output `binding` of a pass of `kind`, and the reason when
/// it is looser than the default.
pub fn rule(kind: &str, binding: &str, decl: &ResourceDecl) -> (Rule, Option<&'static str>) {
    EXCEPTIONS
        .iter()
        .find(|e| e.kind == kind && e.binding == binding)
        .map_or((default_rule(decl), None), |e| (e.rule, Some(e.why)))
}

struct Exception {
    kind: &'static str,
    binding: &'static str,
    rule: Rule,
    why: &'static str,
}

static EXCEPTIONS: &[Exception] = &[];
