//! What the frame benches share: where the checkout is, the bench size, and
//! which graphs can run yet. (Each bench uses part of it.)
#![allow(dead_code)]

use std::path::PathBuf;
use strandgraph_passes::{Definitions, Registry};

/// A path of the checkout: under the working directory when it is there
/// (the device machine runs the binaries from a copy of the tree), else
/// under the checkout the bench was built from.
pub fn root(rel: &str) -> PathBuf {
    let here = PathBuf::from(rel);
    if here.exists() {
        here
    } else {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
    }
}

/// `$STRANDGRAPH_BENCH_SIZE` (WxH), else 320x180: small enough that the
/// CPU simulator and lavapipe finish a criterion run in minutes. The device
/// script sets 1920x1080, Lipp's evaluation resolution.
pub fn size() -> (u32, u32) {
    std::env::var("STRANDGRAPH_BENCH_SIZE")
        .ok()
        .and_then(|s| strandgraph::frame::parse_size(&s).ok())
        .unwrap_or((320, 180))
}

/// The views of Lipp's evaluation.
pub const VIEWS: [&str; 3] = ["close", "mid", "far"];

pub fn view(name: &str) -> PathBuf {
    root(&format!("scenes/distances/{name}.ron"))
}

/// Why `graph` cannot run yet (a live pass kind without kernels), if so.
pub fn missing_kernel(graph: &std::path::Path) -> Option<String> {
    // Which kinds a graph uses does not depend on the model count.
    let plan = match strandgraph_graph::compile_file(graph, &Registry, 1) {
        Ok(p) => p,
        Err(e) => return Some(format!("{e}")),
    };
    plan.order
        .iter()
        .map(|&p| &plan.graph.passes[p])
        .find(|p| Registry.definition(&p.kind).is_none())
        .map(|p| format!("`{}` ({}) has no kernels yet", p.name, p.kind))
}
