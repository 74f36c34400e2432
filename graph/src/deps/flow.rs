//! Per-resource data flow: which passes read, write and update each
//! resource, and the read-after-write and write-after-read edges that
//! follow from its lifetime class (see the parent module for the rules).
//! Write-after-write edges need the order these edges imply, so they are
//! derived afterwards ([`super::analyse`]).

use super::{Edge, Hazard};
use crate::error::{ErrorKind, GraphError, GraphErrors};
use crate::resolve::{Access, Graph, PassId, Resource, ResourceId};
use crate::schema::{AccessMode, LifetimeClass};
use crate::source::Span;
use std::collections::BTreeSet;

/// A resource's users, by access mode.
pub(super) struct Users {
    pub(super) readers: Vec<(PassId, Access)>,
    pub(super) writers: Vec<(PassId, Access)>,
    pub(super) updaters: Vec<(PassId, Access)>,
}

/// Who touches each resource, in one sweep over all accesses.
pub(super) fn users(g: &Graph) -> Vec<Users> {
    let mut all: Vec<Users> = (0..g.resources.len())
        .map(|_| Users {
            readers: vec![],
            writers: vec![],
            updaters: vec![],
        })
        .collect();
    for (p, pass) in g.passes.iter().enumerate() {
        for a in &pass.accesses {
            let u = &mut all[a.resource];
            match a.mode {
                AccessMode::Read => u.readers.push((p, *a)),
                AccessMode::Write => u.writers.push((p, *a)),
                AccessMode::Atomic => u.updaters.push((p, *a)),
            }
        }
    }
    all
}

/// The read-after-write and write-after-read edges each resource's users
/// imply, or every read the graph cannot satisfy.
pub(super) fn data_flow_edges(g: &Graph, all_users: &[Users]) -> Result<Vec<Edge>, GraphErrors> {
    let mut flow = Flow {
        g,
        edges: Vec::new(),
        errors: Vec::new(),
    };
    for (r, u) in all_users.iter().enumerate() {
        let res = ResourceUse::new(g, r, u);
        flow.atomic_updates(&res);
        flow.reads(&res);
        flow.in_place_writes(&res);
        flow.unwritten_history(&res);
    }
    if !flow.errors.is_empty() {
        return Err(GraphErrors(flow.errors));
    }
    Ok(flow.edges)
}

/// One resource, who touches it, and how its lifetime class orders them.
struct ResourceUse<'g> {
    r: ResourceId,
    res: &'g Resource,
    u: &'g Users,
    /// Readers see the previous frame, so writers wait for them.
    history: bool,
    /// The caller owns the memory (imported or history, not a version).
    external: bool,
    /// Caller-owned and neither written nor updated: its readers need no edges.
    pure_input: bool,
}

impl<'g> ResourceUse<'g> {
    fn new(g: &'g Graph, r: ResourceId, u: &'g Users) -> Self {
        let res = &g.resources[r];
        let class = res.decl.lifetime();
        let root = res.version_of.is_none();
        let external = root && class != LifetimeClass::Transient;
        Self {
            r,
            res,
            u,
            history: root && class == LifetimeClass::History,
            external,
            pure_input: external && u.writers.is_empty() && u.updaters.is_empty(),
        }
    }

    fn edge(&self, from: PassId, to: PassId, hazard: Hazard) -> Edge {
        Edge {
            from,
            to,
            resource: self.r,
            hazard,
        }
    }
}

/// Edges and errors gathered while sweeping the resources.
struct Flow<'g> {
    g: &'g Graph,
    edges: Vec<Edge>,
    errors: Vec<GraphError>,
}

impl Flow<'_> {
    fn read_before_write(&self, span: Span, message: String) -> GraphError {
        GraphError::new(ErrorKind::ReadBeforeWrite, &self.g.source, span, message)
    }

    /// Access `a` needs contents no pass writes.
    fn unwritten(&self, res: &ResourceUse<'_>, a: Access, message: String) -> GraphError {
        self.read_before_write(a.span, message)
            .label(res.res.span, "declared here")
    }

    /// `p` reads what each of `sources` wrote.
    fn read_after(&mut self, res: &ResourceUse<'_>, sources: Vec<PassId>, p: PassId) {
        let edges = sources
            .into_iter()
            .map(|w| res.edge(w, p, Hazard::ReadAfterWrite));
        self.edges.extend(edges);
    }

    /// Atomic updates need initialised memory: they follow every writer.
    fn atomic_updates(&mut self, res: &ResourceUse<'_>) {
        for &(p, a) in &res.u.updaters {
            let sources = other_passes(&res.u.writers, p);
            if sources.is_empty() && !res.external {
                let message = format!(
                    "pass `{}` updates transient `{}` atomically, but no pass writes it first",
                    self.g.passes[p].name, res.res.name
                );
                let error = self
                    .unwritten(res, a, message)
                    .help("add a pass that clears it, e.g. kind `common.clear`");
                self.errors.push(error);
            }
            self.read_after(res, sources, p);
        }
    }

    /// Readers follow every writer and updater, except of history, whose
    /// writers follow its readers instead; a pure input needs neither.
    fn reads(&mut self, res: &ResourceUse<'_>) {
        if res.pure_input {
            return;
        }
        for &(p, a) in &res.u.readers {
            let sources = other_passes(res.u.writers.iter().chain(&res.u.updaters), p);
            if res.history {
                let writers: BTreeSet<PassId> = sources.into_iter().collect();
                let edges = writers
                    .into_iter()
                    .map(|w| res.edge(p, w, Hazard::WriteAfterRead));
                self.edges.extend(edges);
                continue;
            }
            if sources.is_empty() {
                let message = format!(
                    "pass `{}` reads `{}`, but no pass writes it",
                    self.g.passes[p].name, res.res.name
                );
                let error = self.unwritten(res, a, message);
                self.errors.push(error);
            }
            self.read_after(res, sources, p);
        }
    }

    /// An in-place write (`a -> b`) is the last use of version `a`: every
    /// other reader of `a` runs first, and only one pass may consume it.
    fn in_place_writes(&mut self, res: &ResourceUse<'_>) {
        let (g, r) = (self.g, res.r);
        let mut consumers: Vec<(PassId, Access)> = res
            .u
            .readers
            .iter()
            .filter(|(p, _)| {
                g.passes[*p].accesses.iter().any(|w| {
                    w.mode.writes() && w.resource != r && g.physical(w.resource) == g.physical(r)
                })
            })
            .copied()
            .collect();
        // A pass that lists `a` in `reads` as well as in `a -> b` consumes it once.
        consumers.dedup_by_key(|(p, _)| *p);
        if let [(a, _), (b, acc_b), ..] = consumers.as_slice() {
            self.errors.push(GraphError::new(
                ErrorKind::UnorderedWriters,
                &g.source,
                acc_b.span,
                format!(
                    "passes `{}` and `{}` both write `{}` in place; only one pass may make a new version of it",
                    g.passes[*a].name, g.passes[*b].name, res.res.name
                ),
            ));
        }
        for &(c, _) in &consumers {
            let edges = res
                .u
                .readers
                .iter()
                .filter(|(p, _)| *p != c)
                .map(|(p, _)| res.edge(*p, c, Hazard::WriteAfterRead));
            self.edges.extend(edges);
        }
    }

    fn unwritten_history(&mut self, res: &ResourceUse<'_>) {
        let u = res.u;
        if res.history
            && u.writers.is_empty()
            && u.updaters.is_empty()
            && let Some(&(p, a)) = u.readers.first()
        {
            let message = format!(
                "pass `{}` reads history `{}`, which no pass ever writes",
                self.g.passes[p].name, res.res.name
            );
            let error = self.read_before_write(a.span, message);
            self.errors.push(error);
        }
    }
}

/// The passes among `users` other than `p`, in order.
fn other_passes<'u>(
    users: impl IntoIterator<Item = &'u (PassId, Access)>,
    p: PassId,
) -> Vec<PassId> {
    users
        .into_iter()
        .map(|(w, _)| *w)
        .filter(|w| *w != p)
        .collect()
}
