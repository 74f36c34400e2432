//! A plan of one pass: the pass as the full graph declares it (kind, queue,
//! params, usages), every resource it binds made `Imported` under the name
//! its kernel binds it by, and every resource it writes an output. Uploading
//! the words the CPU simulator saw just before the pass ran reproduces its
//! inputs exactly on any backend.

use miette::{IntoDiagnostic, Result, miette};
use strandgraph_graph::resolve::{Access, Graph, PassId};
use strandgraph_graph::schema::{
    AccessMode, GraphDesc, LifetimeClass, PassDecl, Repeat, ResourceDecl,
};
use strandgraph_graph::unroll::MODEL_INDEX;
use strandgraph_graph::{Plan, compile_str};
use strandgraph_passes::{Definitions, Registry, bind};

/// One binding of the isolated pass.
#[derive(Debug, Clone)]
pub struct Port {
    /// The name the kernel binds (and the isolated graph declares).
    pub name: String,
    pub decl: ResourceDecl,
    pub mode: AccessMode,
}

/// The isolated pass: its one-pass plan and its bindings.
pub struct Isolated {
    pub plan: Plan,
    pub ports: Vec<Port>,
    /// The graph text compiled into `plan` (printed when a check fails).
    pub text: String,
}

/// Isolates pass `p` of `plan`.
pub fn isolate(plan: &Plan, p: PassId) -> Result<Isolated> {
    let g = &plan.graph;
    let pass = &g.passes[p];
    let def = Registry.definition(&pass.kind).ok_or_else(|| {
        miette!(
            "pass `{}`: kind `{}` has no definition",
            pass.name,
            pass.kind
        )
    })?;
    let bound = bind::bind(def, g, p).into_diagnostic()?;
    let mut ports = Vec::new();
    let (mut reads, mut writes, mut atomics) = (Vec::new(), Vec::new(), Vec::new());
    for b in &bound {
        // The strongest access the pass makes to this memory: a pass that
        // reads `a` and writes `a -> b` binds `a` once, and writes it.
        let root = root_of(g, b.access.resource);
        let access = strongest(
            pass.accesses
                .iter()
                .filter(|a| root_of(g, a.resource) == root),
        )
        .unwrap_or(b.access);
        let entry = format!("{}:{}", access.usage.prefix(), b.name);
        match access.mode {
            AccessMode::Read => reads.push(entry),
            AccessMode::Write => writes.push(entry),
            AccessMode::Atomic => atomics.push(entry),
        }
        ports.push(Port {
            name: b.name.clone(),
            decl: imported(&g.resources[root].decl, &b.name),
            mode: access.mode,
        });
    }
    let desc = GraphDesc {
        name: format!("{} alone", pass.name),
        description: format!("pass `{}` of graph `{}`, isolated", pass.name, g.name),
        resources: ports.iter().map(|port| port.decl.clone()).collect(),
        passes: vec![PassDecl {
            name: pass.name.replace(['[', ']'], "_"),
            kind: pass.kind.clone(),
            queue: pass.queue,
            params: without_model_index(&pass.params),
            reads,
            writes,
            atomics,
            repeat: Repeat::Once,
            loop_bounding: pass.loop_bounding,
        }],
        outputs: ports
            .iter()
            .filter(|port| port.mode.writes())
            .map(|port| port.name.clone())
            .collect(),
    };
    let text = ron::ser::to_string_pretty(&desc, ron::ser::PrettyConfig::default())
        .map_err(|e| miette!("pass `{}`: isolating: {e}", pass.name))?;
    let mut plan = compile_str(&desc.name, &text, &Registry, 1)?;
    // The copy of a per-model pass keeps the model it ran for: a graph may
    // not set `model_index` (the per-model block does), so it is put back
    // on the compiled pass, as unrolling puts it.
    plan.graph.passes[0].params = pass.params.clone();
    Ok(Isolated { plan, ports, text })
}

/// `params` less the `model_index` that unrolling added.
fn without_model_index(params: &ron::Value) -> ron::Value {
    match params {
        ron::Value::Map(m) => {
            let mut m = m.clone();
            m.remove(&ron::Value::String(MODEL_INDEX.into()));
            ron::Value::Map(m)
        }
        other => other.clone(),
    }
}

/// The declared resource whose memory `r` is (through versions and per-model copies).
fn root_of(g: &Graph, r: usize) -> usize {
    let r = g.physical(r);
    g.resources[r].copy_of.map_or(r, |c| g.physical(c))
}

fn strongest<'a>(accesses: impl Iterator<Item = &'a Access>) -> Option<Access> {
    let rank = |m: AccessMode| match m {
        AccessMode::Read => 0,
        AccessMode::Atomic => 1,
        AccessMode::Write => 2,
    };
    accesses.copied().max_by_key(|a| rank(a.mode))
}

/// `decl` renamed and owned by the caller, so its contents can be uploaded.
fn imported(decl: &ResourceDecl, name: &str) -> ResourceDecl {
    let mut decl = decl.clone();
    match &mut decl {
        ResourceDecl::Buffer {
            name: n, lifetime, ..
        }
        | ResourceDecl::Image {
            name: n, lifetime, ..
        } => {
            *n = name.to_string();
            *lifetime = LifetimeClass::Imported;
        }
    }
    decl
}
