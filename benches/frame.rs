//! Frame time per backend, pipeline and view (close, mid, far).
//!
//! The CPU simulator is timed by wall clock around a frame. GPU backends are
//! timed by their per-pass GPU timestamps through `iter_custom`, not by CPU
//! wall time around a submit (ash: first begin to last end over its queues).
//! Backends that cannot open here (no Vulkan adapter) are skipped with a message,
//! as are pipelines whose passes have no kernels yet (Lipp).
//!
//! `STRANDGRAPH_BENCH_SIZE=1920x1080 cargo bench --bench frame` for Lipp's
//! resolution; the default is small (see `common::size`).

mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use std::time::Duration;
use strandgraph::frame::prepare;
use strandgraph::runner::{self, Backend, OpenOptions, frame_millis};

const PIPELINES: [(&str, &str); 2] = [
    ("kulikov", "scenes/graphs/kulikov.ron"),
    ("lipp", "scenes/graphs/lipp.ron"),
];

fn frame_benches(c: &mut Criterion) {
    let size = common::size();
    let mut group = c.benchmark_group("frame");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(200))
        .measurement_time(Duration::from_secs(2));
    for (pipeline, graph) in PIPELINES {
        let graph = common::root(graph);
        if let Some(why) = common::missing_kernel(&graph) {
            eprintln!("frame/*/{pipeline}: skipped: {why}");
            continue;
        }
        for view in common::VIEWS {
            let p = prepare(&common::view(view), Some(&graph), Some(size))
                .unwrap_or_else(|e| panic!("{view}: {e:?}"));
            for backend in [Backend::Cpu, Backend::Wgpu, Backend::Ash] {
                let id = format!("{}/{pipeline}/{view}", backend.name());
                let mut runner =
                    match runner::open(backend, &p.plan, &p.instance, OpenOptions::default()) {
                        Ok(r) => r,
                        Err(e) => {
                            eprintln!("frame/{id}: skipped: {e}");
                            continue;
                        }
                    };
                eprintln!("frame/{id}: {}", runner.device());
                let mut frame = || {
                    runner
                        .run(&p.upload)
                        .unwrap_or_else(|e| panic!("{id}: {e:?}"))
                };
                if backend.is_gpu() {
                    group.bench_function(&id, |b| {
                        b.iter_custom(|iters| {
                            let ms: f64 = (0..iters).map(|_| frame_millis(&frame())).sum();
                            Duration::from_secs_f64(ms * 1e-3)
                        })
                    });
                } else {
                    group.bench_function(&id, |b| b.iter(&mut frame));
                }
            }
        }
    }
    group.finish();
}

criterion_group!(benches, frame_benches);
criterion_main!(benches);
