//! Fuzz `--param` (`strandgraph_passes::params::override_param`): the
//! `PASS.PARAM=VALUE` / `IMAGE.samples=N` syntax and its application to a
//! compiled shipped graph's typed parameters, checked by the real pass
//! registry. The first byte picks the graph (every `scenes/graphs/*.ron`,
//! with one or two hair models); the rest is up to 8 overrides, one a line,
//! applied in turn.
//!
//! An override that fails names itself (`--param SPEC: ...`) and leaves the
//! plan as it was (every pass's parameters, every image's sample count). One
//! that succeeds leaves the parameters it wrote readable by the pass's kind
//! (entry point, CPU kernel, GPU block, raster state), the plan still
//! instantiates, and applying it again changes nothing.
#![no_main]

use std::hash::{DefaultHasher, Hash, Hasher};
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use strandgraph_graph::schema::ResourceDecl;
use strandgraph_graph::{Plan, Quantities, compile_str};
use strandgraph_passes::Registry;
use strandgraph_passes::params::override_param;
use strandgraph_passes::shipped::GRAPHS;

/// Each graph compiled for one and for two hair models (index 2g + m - 1).
fn plans() -> &'static [Plan] {
    static PLANS: OnceLock<Vec<Plan>> = OnceLock::new();
    PLANS.get_or_init(|| {
        GRAPHS
            .iter()
            .flat_map(|(name, text)| {
                (1..=2).map(move |models| {
                    compile_str(name, text, &Registry, models)
                        .unwrap_or_else(|e| panic!("{name}: {e:?}"))
                })
            })
            .collect()
    })
}

fn quantities(models: u64) -> Quantities {
    Quantities {
        strands: 64,
        vertices: 512,
        segments: 448,
        bundles: 8,
        mesh_strands: 64,
        models,
        patches: 8,
        triangles: 32,
        lights: 2,
        width: 64,
        height: 36,
    }
}

/// What an override may change, cheaply: a hash of each pass's parameters
/// and each resource's sample count (0 for a buffer).
#[derive(PartialEq)]
struct Snapshot {
    params: Vec<u64>,
    samples: Vec<u32>,
}

fn snapshot(plan: &Plan) -> Snapshot {
    let g = &plan.graph;
    let hash = |v: &ron::Value| {
        let mut h = DefaultHasher::new();
        v.hash(&mut h);
        h.finish()
    };
    Snapshot {
        params: g.passes.iter().map(|p| hash(&p.params)).collect(),
        samples: g
            .resources
            .iter()
            .map(|r| match r.decl {
                ResourceDecl::Image { samples, .. } => samples,
                ResourceDecl::Buffer { .. } => 0,
            })
            .collect(),
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&pick, text)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(text) else {
        return;
    };
    let plans = plans();
    let index = pick as usize % plans.len();
    let q = quantities(1 + (index % 2) as u64);
    let mut plan = plans[index].clone();
    for spec in text.split('\n').take(8) {
        let before = snapshot(&plan);
        match override_param(&mut plan, spec) {
            Err(e) => {
                assert!(e.starts_with(&format!("--param {spec}: ")), "{e}");
                assert!(
                    snapshot(&plan) == before,
                    "a failed override changed the plan: {e}"
                );
            }
            Ok(()) => {
                let after = snapshot(&plan);
                // The passes the override wrote: their kind must read them.
                let changed =
                    (0..after.params.len()).filter(|&p| after.params[p] != before.params[p]);
                for p in changed {
                    let pass = &plan.graph.passes[p];
                    let def = Registry.get(&pass.kind).expect("a compiled kind");
                    let name = &pass.name;
                    if let Err(e) = def.entry(&pass.params) {
                        panic!("after `{spec}`, pass `{name}`'s parameters do not read: {e:?}");
                    }
                    if let Err(e) = def.cpu_kernel(&pass.params) {
                        panic!("after `{spec}`, pass `{name}` has no CPU kernel: {e:?}");
                    }
                    let _ = def.gpu_params(&pass.params, &q);
                    let _ = def.raster(&pass.params, &q);
                }
                let _ = plan.instantiate(&q);
                // Idempotent: applying it again succeeds and changes nothing.
                assert_eq!(override_param(&mut plan, spec), Ok(()));
                assert!(snapshot(&plan) == after, "`{spec}` twice");
            }
        }
    }
});
