//! Culling: passes that contribute to no output are dropped, with a reason.

use crate::deps::{Dependencies, Hazard};
use crate::resolve::{Graph, PassId};
use crate::schema::{AccessMode, LifetimeClass};
use serde::Serialize;

/// A pass the plan does not run, and why.
#[derive(Debug, Clone, Serialize)]
pub struct Culled {
    pub pass: PassId,
    pub reason: String,
}

/// Marks the passes needed for the outputs.
///
/// Roots are the writers of outputs. A needed pass needs the passes whose
/// results it consumes (read-after-write and write-after-write edges, not
/// write-after-read: a reader does not need the writer that waits for it),
/// and the writers of any history resource it reads, which produce the next
/// frame's contents.
pub fn cull(g: &Graph, deps: &Dependencies) -> (Vec<bool>, Vec<Culled>) {
    let n = g.passes.len();
    let mut needed = vec![false; n];
    let mut stack: Vec<PassId> = Vec::new();
    let writes = |p: PassId, r: usize| {
        g.passes[p]
            .accesses
            .iter()
            .any(|a| a.resource == r && a.mode.writes())
    };
    for &(r, _) in &g.outputs {
        stack.extend((0..n).filter(|&p| writes(p, r)));
    }
    let mut preds = vec![Vec::new(); n];
    for e in deps
        .edges
        .iter()
        .filter(|e| e.hazard != Hazard::WriteAfterRead)
    {
        preds[e.to].push(e.from);
    }
    while let Some(p) = stack.pop() {
        if std::mem::replace(&mut needed[p], true) {
            continue;
        }
        stack.extend(preds[p].iter().copied().filter(|&q| !needed[q]));
        for a in &g.passes[p].accesses {
            let history = g.resources[a.resource].decl.lifetime() == LifetimeClass::History;
            if history && a.mode == AccessMode::Read {
                stack.extend((0..n).filter(|&q| !needed[q] && writes(q, a.resource)));
            }
        }
    }
    let culled = (0..n)
        .filter(|&p| !needed[p])
        .map(|p| {
            let written: Vec<&str> = g.passes[p]
                .accesses
                .iter()
                .filter(|a| a.mode.writes())
                .map(|a| g.resources[a.resource].name.as_str())
                .collect();
            let reason = if written.is_empty() {
                "writes nothing".to_string()
            } else {
                format!(
                    "nothing that reaches an output reads what it writes ({})",
                    written.join(", ")
                )
            };
            Culled { pass: p, reason }
        })
        .collect();
    (needed, culled)
}
