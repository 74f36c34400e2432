//! Dependencies between passes, derived from data flow.
//!
//! The graph is a data-flow graph, not a list: declaration order does not
//! order passes. Per resource, each frame has one version:
//! - a **transient** is produced by its writers (which must be ordered among
//!   themselves), then updated by its atomic passes (which commute), then read;
//! - an **imported** resource that no pass writes is a pure input; one that
//!   passes write behaves like a transient whose memory the caller owns;
//! - a **history** resource's readers see the previous frame's contents, so
//!   every writer waits for every reader (write-after-read);
//! - a **version** (`"depth:scene.depth -> scene.depth.hair"` in `writes`)
//!   names the contents after an in-place write: readers of the old name run
//!   before the writer, readers of the new name after it. This is how a pass
//!   updates memory other passes read both before and after.
//!
//! Anything else (a read with no writer, a cycle, two unordered writers) is an
//! error. Atomic updaters that nothing orders are serialised in topological
//! order: their results commute, but Vulkan still wants a barrier between them.

mod flow;

use crate::error::{ErrorKind, GraphError, GraphErrors};
use crate::reach::Reach;
use crate::resolve::{Graph, PassId, ResourceId};
use flow::{Users, data_flow_edges, users};
use serde::Serialize;
use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap};

/// The kind of memory hazard a dependency protects against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub enum Hazard {
    ReadAfterWrite,
    WriteAfterRead,
    WriteAfterWrite,
}

impl Hazard {
    pub fn short(self) -> &'static str {
        match self {
            Hazard::ReadAfterWrite => "RAW",
            Hazard::WriteAfterRead => "WAR",
            Hazard::WriteAfterWrite => "WAW",
        }
    }
}

/// `to` must wait for `from` because of `resource`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Edge {
    pub from: PassId,
    pub to: PassId,
    pub resource: ResourceId,
    pub hazard: Hazard,
}

/// Every dependency edge and a deterministic topological order of all passes.
#[derive(Debug, Clone)]
pub struct Dependencies {
    pub edges: Vec<Edge>,
    /// All passes; ties broken by declaration order.
    pub order: Vec<PassId>,
}

/// Data-flow edges first; the order they imply then orders the writers
/// (WAW) and serialises the atomic updaters.
pub fn analyse(g: &Graph) -> Result<Dependencies, GraphErrors> {
    let all_users = users(g);
    let mut edges = data_flow_edges(g, &all_users)?;
    sort_edges(&mut edges);
    let order = topological_order(g.passes.len(), &edges)
        .map_err(|cycle| cycle_error(g, &edges, &cycle))?;
    // Reachability over the data-flow edges alone: what orders the writers.
    let reach = Reach::new(g.passes.len(), &order, edges.iter().map(|e| (e.from, e.to)));
    let position = positions(&order);
    edges.extend(writer_edges(g, &all_users, &reach, &position)?);
    edges.extend(updater_edges(&all_users, &position));
    sort_edges(&mut edges);
    Ok(Dependencies { edges, order })
}

/// Sorted by pass pair and resource (stable, so hazards keep their order), without repeats.
fn sort_edges(edges: &mut Vec<Edge>) {
    edges.sort_by_key(|e| (e.from, e.to, e.resource));
    edges.dedup();
}

/// Writers must be ordered by the rest of the graph (`reach`); ordered ones
/// get a WAW edge, unordered ones are an error.
fn writer_edges(
    g: &Graph,
    all_users: &[Users],
    reach: &Reach,
    position: &[usize],
) -> Result<Vec<Edge>, GraphErrors> {
    let mut edges = Vec::new();
    let mut errors = Vec::new();
    for (r, u) in all_users.iter().enumerate() {
        let mut writers = u.writers.clone();
        writers.sort_by_key(|(p, _)| position[*p]);
        for (i, &(a, acc_a)) in writers.iter().enumerate() {
            for &(b, acc_b) in &writers[i + 1..] {
                if reach.reaches(a, b) {
                    edges.push(Edge {
                        from: a,
                        to: b,
                        resource: r,
                        hazard: Hazard::WriteAfterWrite,
                    });
                } else {
                    errors.push(
                        GraphError::new(
                            ErrorKind::UnorderedWriters,
                            &g.source,
                            acc_b.span,
                            format!(
                                "passes `{}` and `{}` both write `{}`, but nothing orders them",
                                g.passes[a].name, g.passes[b].name, g.resources[r].name
                            ),
                        )
                        .label(acc_a.span, "also written here")
                        .help(
                            "make one read something the other writes, or write separate resources",
                        ),
                    );
                }
            }
        }
    }
    if !errors.is_empty() {
        return Err(GraphErrors(errors));
    }
    Ok(edges)
}

/// Atomic updaters commute; serialise them along the topological order
/// (edges forward in that order cannot create a cycle).
fn updater_edges(all_users: &[Users], position: &[usize]) -> Vec<Edge> {
    let mut edges = Vec::new();
    for (r, u) in all_users.iter().enumerate() {
        let mut ups: Vec<PassId> = u.updaters.iter().map(|(p, _)| *p).collect();
        ups.sort_by_key(|p| position[*p]);
        ups.dedup();
        edges.extend(ups.windows(2).map(|w| Edge {
            from: w[0],
            to: w[1],
            resource: r,
            hazard: Hazard::WriteAfterWrite,
        }));
    }
    edges
}

pub(crate) fn positions(order: &[PassId]) -> Vec<usize> {
    let mut pos = vec![usize::MAX; order.iter().max().map_or(0, |m| m + 1)];
    for (i, &p) in order.iter().enumerate() {
        pos[p] = i;
    }
    pos
}

/// Kahn's algorithm, smallest declaration index first, so the order is
/// stable and reads like the file. On a cycle, returns the passes left over.
pub(crate) fn topological_order(n: usize, edges: &[Edge]) -> Result<Vec<PassId>, Vec<PassId>> {
    let mut indegree = vec![0usize; n];
    let mut succ = vec![Vec::new(); n];
    let mut seen = BTreeSet::new();
    for e in edges {
        if seen.insert((e.from, e.to)) {
            indegree[e.to] += 1;
            succ[e.from].push(e.to);
        }
    }
    let mut ready: BinaryHeap<Reverse<PassId>> =
        (0..n).filter(|&p| indegree[p] == 0).map(Reverse).collect();
    let mut order = Vec::with_capacity(n);
    while let Some(Reverse(p)) = ready.pop() {
        order.push(p);
        for &s in &succ[p] {
            indegree[s] -= 1;
            if indegree[s] == 0 {
                ready.push(Reverse(s));
            }
        }
    }
    if order.len() == n {
        Ok(order)
    } else {
        Err((0..n).filter(|&p| indegree[p] > 0).collect())
    }
}

/// Names one cycle among the passes Kahn's algorithm could not order.
fn cycle_error(g: &Graph, edges: &[Edge], stuck: &[PassId]) -> GraphErrors {
    use petgraph::graph::DiGraph;
    let mut dg = DiGraph::<PassId, ResourceId>::new();
    let nodes: Vec<_> = (0..g.passes.len()).map(|p| dg.add_node(p)).collect();
    for e in edges {
        if stuck.contains(&e.from) && stuck.contains(&e.to) {
            dg.add_edge(nodes[e.from], nodes[e.to], e.resource);
        }
    }
    // Within a strongly connected component, walk until a pass repeats.
    let scc = petgraph::algo::tarjan_scc(&dg)
        .into_iter()
        .find(|c| c.len() > 1)
        .unwrap_or_default();
    let mut path: Vec<(PassId, ResourceId)> = Vec::new();
    let mut at = scc.iter().map(|n| dg[*n]).min().unwrap_or(stuck[0]);
    loop {
        if let Some(i) = path.iter().position(|(p, _)| *p == at) {
            path.drain(..i);
            break;
        }
        let next = dg
            .edges(nodes[at])
            .filter(|e| scc.contains(&petgraph::visit::EdgeRef::target(e)))
            .map(|e| (dg[petgraph::visit::EdgeRef::target(&e)], *e.weight()))
            .min();
        let Some((to, r)) = next else { break };
        path.push((at, r));
        at = to;
    }
    let Some(&(first, _)) = path.first() else {
        return GraphError::new(
            ErrorKind::Cycle,
            &g.source,
            g.passes[stuck[0]].span,
            "passes form a cycle",
        )
        .into();
    };
    let chain: Vec<String> = path
        .iter()
        .map(|(p, r)| format!("`{}` -({})->", g.passes[*p].name, g.resources[*r].name))
        .chain(std::iter::once(format!("`{}`", g.passes[first].name)))
        .collect();
    let mut e = GraphError::new(
        ErrorKind::Cycle,
        &g.source,
        g.passes[first].span,
        format!("passes form a cycle: {}", chain.join(" ")),
    )
    .primary("this pass depends on itself");
    for (p, _) in path.iter().skip(1) {
        e = e.label(g.passes[*p].span, "on the cycle");
    }
    e.into()
}
