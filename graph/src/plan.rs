//! The compiler's entry points and its product, the [`Plan`].

use crate::alias::Aliasing;
use crate::cull::{Culled, cull};
use crate::deps::analyse;
use crate::error::{ErrorKind, GraphError, GraphErrors};
use crate::lifetime::{Lifetime, lifetimes};
use crate::registry::PassRegistry;
use crate::resolve::{Graph, PassId, resolve};
use crate::schedule::{Lane, SyncPoint, schedule};
use crate::schema::GraphDesc;
use crate::source::{Locator, Source, Span};
use crate::sync::{Dependency, dependencies};
use crate::unroll::unroll;
use serde::Serialize;
use std::path::Path;

/// A compiled graph: what every backend executes without analysing the graph again.
///
/// Sizes are still symbolic; [`Plan::instantiate`] resolves them for a scene
/// and plans memory.
#[derive(Debug, Clone, Serialize)]
pub struct Plan {
    #[serde(flatten)]
    pub graph: Graph,
    /// `live[p]`: pass `p` runs (it was not culled).
    pub live: Vec<bool>,
    /// Live passes in one topological order.
    pub order: Vec<PassId>,
    pub lanes: Vec<Lane>,
    /// Every dependency between live passes, with barrier information.
    pub dependencies: Vec<Dependency>,
    /// Cross-queue dependencies after transitive reduction.
    pub sync_points: Vec<SyncPoint>,
    /// Transients used by live passes.
    pub lifetimes: Vec<Lifetime>,
    pub culled: Vec<Culled>,
    /// Which transients may share bytes; [`Plan::instantiate`] and the
    /// backends' re-placements plan memory with it (`Plan::plan_memory`).
    /// Set it before instantiating.
    pub aliasing: Aliasing,
}

impl Plan {
    pub fn pass_name(&self, p: PassId) -> &str {
        &self.graph.passes[p].name
    }
    pub fn resource_name(&self, r: usize) -> &str {
        &self.graph.resources[r].name
    }
    /// Position of a live pass in [`Plan::order`].
    pub fn position(&self, p: PassId) -> Option<usize> {
        self.order.iter().position(|&x| x == p)
    }
}

/// Compiles graph text; `name` is used in diagnostics. `models` is the
/// scene's hair model count, which the per-model block is unrolled for
/// ([`crate::unroll`]); graphs without one ignore it.
pub fn compile_str(
    name: &str,
    text: &str,
    registry: &dyn PassRegistry,
    models: u32,
) -> Result<Plan, GraphErrors> {
    let src = Source::new(name, text);
    let desc: GraphDesc = ron::from_str(text).map_err(|e| syntax_error(&src, &e))?;
    let loc = Locator::new(text);
    compile(&desc, &src, &loc, registry, models)
}

/// Reads and compiles a graph file (see [`compile_str`]).
pub fn compile_file(
    path: &Path,
    registry: &dyn PassRegistry,
    models: u32,
) -> Result<Plan, GraphErrors> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| {
        GraphError::new(
            ErrorKind::Io,
            &Source::new(&name, ""),
            Span::default(),
            format!("cannot read: {e}"),
        )
    })?;
    compile_str(&name, &text, registry, models)
}

fn compile(
    desc: &GraphDesc,
    src: &Source,
    loc: &Locator,
    registry: &dyn PassRegistry,
    models: u32,
) -> Result<Plan, GraphErrors> {
    let graph = unroll(resolve(desc, src, loc, registry)?, models)?;
    let deps = analyse(&graph)?;
    let (live, culled) = cull(&graph, &deps);
    let sched = schedule(&graph, &deps, &live);
    let lifetimes = lifetimes(&graph, &sched);
    let dependencies = dependencies(&graph, &deps.edges, &live);
    debug_assert!(
        dependencies
            .iter()
            .all(|d| sched.happens_before.reaches(d.from, d.to))
    );
    Ok(Plan {
        live,
        order: sched.order,
        lanes: sched.lanes,
        dependencies,
        sync_points: sched.sync_points,
        lifetimes,
        culled,
        aliasing: Aliasing::default(),
        graph,
    })
}

fn syntax_error(src: &Source, e: &ron::error::SpannedError) -> GraphErrors {
    let start = src.offset_of(e.span.start.line, e.span.start.col);
    let end = src.offset_of(e.span.end.line, e.span.end.col).max(start);
    GraphError::new(
        ErrorKind::Syntax,
        src,
        Span::new(start, end),
        e.code.to_string(),
    )
    .into()
}
