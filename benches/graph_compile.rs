//! Graph compiler benchmarks: a synthetic 1,000-pass graph end to end
//! (parse, validate, schedule, lifetimes, sync), memory planning for it, and
//! the shipped Kulikov graph.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use strandgraph_graph::synthetic::Spec;
use strandgraph_graph::{Quantities, compile_str};

fn compile_benches(c: &mut Criterion) {
    let text = Spec::random(1000, 42).to_ron();
    let kinds = Spec::kinds();
    c.bench_function("compile/synthetic_1000_passes", |b| {
        b.iter(|| {
            compile_str("synthetic.ron", black_box(&text), &kinds, 1)
                .expect("synthetic graph compiles")
        })
    });
    let plan = compile_str("synthetic.ron", &text, &kinds, 1).expect("synthetic graph compiles");
    let q = Quantities::example();
    c.bench_function("instantiate/synthetic_1000_passes", |b| {
        b.iter(|| plan.instantiate(black_box(&q)).expect("sizes resolve"))
    });

    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/graphs/kulikov.ron");
    let kulikov = std::fs::read_to_string(path).expect("kulikov.ron is shipped");
    c.bench_function("compile/kulikov", |b| {
        b.iter(|| {
            compile_str(path, black_box(&kulikov), &strandgraph_passes::Registry, 1)
                .expect("kulikov compiles")
        })
    });
}

criterion_group!(benches, compile_benches);
criterion_main!(benches);
