//! The CPU simulator's Kulikov raster kernel in place: the mid view's frame
//! runs on a CPU session and only the `raster` pass's wall time is counted
//! (`iter_custom`), once per ablation switch of the kernel.
//!
//! `STRANDGRAPH_BENCH_SIZE` sets the resolution (default: `common::size`).

mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use std::time::Duration;
use strandgraph::frame::{override_param, prepare};
use strandgraph::runner::{self, Backend, OpenOptions};

const SWITCHES: [(&str, &[&str]); 3] = [
    ("all_optimisations", &[]),
    ("no_loop_flattening", &["raster.loop_flattening=false"]),
    ("no_last_layer_cull", &["raster.last_layer_cull=false"]),
];

fn raster_benches(c: &mut Criterion) {
    let graph = common::root("scenes/graphs/kulikov.ron");
    let p = prepare(&common::view("mid"), Some(&graph), Some(common::size()))
        .unwrap_or_else(|e| panic!("{e:?}"));
    let mut group = c.benchmark_group("cpu_raster_kernel");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(200))
        .measurement_time(Duration::from_secs(2));
    for (name, overrides) in SWITCHES {
        let mut plan = p.plan.clone();
        for o in overrides {
            override_param(&mut plan, o).unwrap_or_else(|e| panic!("{e:?}"));
        }
        let mut runner = runner::open(Backend::Cpu, &plan, &p.instance, OpenOptions::default())
            .unwrap_or_else(|e| panic!("{e:?}"));
        group.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let ms: f64 = (0..iters)
                    .map(|_| {
                        let frame = runner.run(&p.upload).unwrap_or_else(|e| panic!("{e:?}"));
                        frame
                            .iter()
                            .filter(|t| t.name == "raster")
                            .filter_map(|t| t.millis)
                            .sum::<f64>()
                    })
                    .sum();
                Duration::from_secs_f64(ms * 1e-3)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, raster_benches);
criterion_main!(benches);
