//! The executor with small test kernels: aliasing must not change results,
//! sync points must order queues, and failures must be errors, not hangs.

use std::time::Duration;
use strandgraph_cpu::{CpuBackend, CpuError, Inputs};
use strandgraph_graph::{KindList, Plan, Quantities, compile_str};
use strandgraph_passes::kernel::Ctx;
use strandgraph_passes::{
    Binding, CpuKernel, Definitions, Dispatch, ParamError, Params, PassDef, Shader,
};

const GROUP: usize = 64;

fn hash(x: u32) -> u32 {
    let mut h = x.wrapping_mul(0x9E37_79B1);
    h ^= h >> 15;
    h.wrapping_mul(0x85EB_CA77)
}

/// `test.fill`: every written resource gets hash(seed + i); optionally sleeps first.
struct Fill;
/// `test.mix`: writes `out[i] = a[i] * 3 + b[i]` for its one written resource.
struct Mix;
/// `test.sum`: atomically adds all of `c` into word 0 of `total`.
struct Sum;

struct FillKernel {
    seed: u32,
    sleep_ms: u32,
}
struct MixKernel;
struct SumKernel;

fn shader() -> Shader {
    Shader {
        file: "test.wgsl",
        entry: "main",
        fragment: None,
    }
}

impl PassDef for Fill {
    fn kind(&self) -> &'static str {
        "test.fill"
    }
    fn bindings(&self) -> Option<&'static [Binding]> {
        None
    }
    fn workgroup_size(&self) -> u32 {
        GROUP as u32
    }
    fn dispatch(&self) -> Dispatch {
        Dispatch::CoverWrites {
            words_per_group: GROUP as u32,
        }
    }
    fn shader(&self) -> Shader {
        shader()
    }
    fn cpu_kernel(&self, params: &ron::Value) -> Result<Box<dyn CpuKernel>, ParamError> {
        let p = Params::new("test.fill", params)?;
        Ok(Box::new(FillKernel {
            seed: p.u32("seed", 0)?,
            sleep_ms: p.u32("sleep_ms", 0)?,
        }))
    }
}

impl CpuKernel for FillKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        if group == 0 && self.sleep_ms > 0 {
            std::thread::sleep(Duration::from_millis(u64::from(self.sleep_ms)));
        }
        for w in ctx.bindings.values() {
            for i in group as usize * GROUP..((group as usize + 1) * GROUP).min(w.len()) {
                w.store(i, hash(self.seed.wrapping_add(i as u32)));
            }
        }
    }
}

impl PassDef for Mix {
    fn kind(&self) -> &'static str {
        "test.mix"
    }
    fn bindings(&self) -> Option<&'static [Binding]> {
        use strandgraph_graph::AccessMode::*;
        Some(&[
            Binding {
                name: "a",
                mode: Read,
                min_words: 0,
            },
            Binding {
                name: "b",
                mode: Read,
                min_words: 0,
            },
            Binding {
                name: "out",
                mode: Write,
                min_words: 0,
            },
        ])
    }
    fn workgroup_size(&self) -> u32 {
        GROUP as u32
    }
    fn dispatch(&self) -> Dispatch {
        Dispatch::PerElement {
            quantity: strandgraph_graph::schema::Quantity::Strands,
            per_group: GROUP as u32,
        }
    }
    fn shader(&self) -> Shader {
        shader()
    }
    fn cpu_kernel(&self, _: &ron::Value) -> Result<Box<dyn CpuKernel>, ParamError> {
        Ok(Box::new(MixKernel))
    }
}

impl CpuKernel for MixKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let (a, b, out) = (ctx.words("a"), ctx.words("b"), ctx.words("out"));
        for i in group as usize * GROUP..((group as usize + 1) * GROUP).min(out.len()) {
            out.store(i, a.load(i).wrapping_mul(3).wrapping_add(b.load(i)));
        }
    }
}

impl PassDef for Sum {
    fn kind(&self) -> &'static str {
        "test.sum"
    }
    fn bindings(&self) -> Option<&'static [Binding]> {
        use strandgraph_graph::AccessMode::*;
        Some(&[
            Binding {
                name: "c",
                mode: Read,
                min_words: 0,
            },
            Binding {
                name: "total",
                mode: Atomic,
                min_words: 0,
            },
        ])
    }
    fn workgroup_size(&self) -> u32 {
        GROUP as u32
    }
    fn dispatch(&self) -> Dispatch {
        Dispatch::PerElement {
            quantity: strandgraph_graph::schema::Quantity::Strands,
            per_group: GROUP as u32,
        }
    }
    fn shader(&self) -> Shader {
        shader()
    }
    fn cpu_kernel(&self, _: &ron::Value) -> Result<Box<dyn CpuKernel>, ParamError> {
        Ok(Box::new(SumKernel))
    }
}

impl CpuKernel for SumKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let (src, total) = (ctx.words("c"), ctx.words("total"));
        let s = (group as usize * GROUP..((group as usize + 1) * GROUP).min(src.len()))
            .map(|i| src.load(i))
            .fold(0u32, u32::wrapping_add);
        total.fetch_add(0, s);
    }
}

struct TestDefs;
impl Definitions for TestDefs {
    fn definition(&self, kind: &str) -> Option<&dyn PassDef> {
        match kind {
            "test.fill" => Some(&Fill),
            "test.mix" => Some(&Mix),
            "test.sum" => Some(&Sum),
            _ => strandgraph_passes::Registry.definition(kind),
        }
    }
}

fn kinds() -> KindList {
    KindList::new(["test.fill", "test.mix", "test.sum", "common.clear"])
}

fn quantities() -> Quantities {
    Quantities {
        strands: 4096,
        ..Quantities::example()
    }
}

/// Fills and a mix whose transients alias (`c` reuses the bytes of `a` or
/// `b`), ending in a checksum of `c`.
const CHAIN: &str = r#"Graph(
    name: "chain",
    resources: [
        Buffer(name: "a", size: PerElement(Strands, 4)),
        Buffer(name: "b", size: PerElement(Strands, 4)),
        Buffer(name: "c", size: PerElement(Strands, 4)),
        Buffer(name: "out", size: PerElement(Strands, 4), lifetime: Imported),
        Buffer(name: "total", size: Bytes(4), lifetime: Imported),
    ],
    passes: [
        Pass(name: "fa", kind: "test.fill", params: {"seed": 1}, writes: ["a"]),
        Pass(name: "fb", kind: "test.fill", params: {"seed": 2}, writes: ["b"]),
        Pass(name: "mix", kind: "test.mix", reads: ["a", "b"], writes: ["out"]),
        Pass(name: "fc", kind: "test.fill", params: {"seed": 3}, reads: ["out"], writes: ["c"]),
        Pass(name: "clear", kind: "common.clear", writes: ["total"]),
        Pass(name: "sum", kind: "test.sum", reads: ["c"], atomics: ["total"]),
    ],
    outputs: ["out", "total"],
)"#;

fn chain_plan() -> Plan {
    compile_str("chain.ron", CHAIN, &kinds(), 1).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn aliasing_does_not_change_results() {
    let plan = chain_plan();
    let inst = plan.instantiate(&quantities()).unwrap();
    assert!(
        inst.memory.bytes_with_aliasing < inst.memory.bytes_without_aliasing,
        "the test graph must actually alias something"
    );
    let run = |alias: bool| {
        let backend = CpuBackend {
            alias,
            ..CpuBackend::default()
        };
        let frame = backend
            .execute_with(&TestDefs, &plan, &inst, &Inputs::default())
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            frame
                .memory
                .out_of_bounds
                .load(std::sync::atomic::Ordering::Relaxed),
            0
        );
        (
            frame.read(&plan, "out").unwrap(),
            frame.read(&plan, "total").unwrap(),
        )
    };
    let (aliased, unaliased) = (run(true), run(false));
    assert_eq!(aliased, unaliased);
    // And the result is the computation, not zeros.
    let expected: Vec<u32> = (0..4096)
        .map(|i| hash(1 + i).wrapping_mul(3).wrapping_add(hash(2 + i)))
        .collect();
    assert_eq!(aliased.0, expected);
    let c_sum = (0..4096u32)
        .map(|i| hash(3 + i))
        .fold(0u32, u32::wrapping_add);
    assert_eq!(aliased.1[0], c_sum);
}

const CROSS_QUEUE: &str = r#"Graph(
    name: "cross",
    resources: [
        Buffer(name: "a", size: PerElement(Strands, 4)),
        Buffer(name: "b", size: PerElement(Strands, 4), lifetime: Imported),
        Buffer(name: "out", size: PerElement(Strands, 4), lifetime: Imported),
    ],
    passes: [
        Pass(name: "slow", kind: "test.fill", queue: Graphics, params: {"seed": 9, "sleep_ms": 300}, writes: ["a"]),
        Pass(name: "mix", kind: "test.mix", queue: AsyncCompute, reads: ["a", "b"], writes: ["out"]),
    ],
    outputs: ["out"],
)"#;

#[test]
fn queues_wait_at_sync_points_and_a_missing_one_is_a_race() {
    let plan = compile_str("cross.ron", CROSS_QUEUE, &kinds(), 1).unwrap();
    assert_eq!(plan.sync_points.len(), 1);
    let inst = plan.instantiate(&quantities()).unwrap();
    let backend = CpuBackend::default();
    let good = backend
        .execute_with(&TestDefs, &plan, &inst, &Inputs::default())
        .unwrap();
    let out = good.read(&plan, "out").unwrap();
    assert_eq!(out[7], hash(9 + 7).wrapping_mul(3));

    // Without the sync point the async queue reads `a` before the slow pass wrote it.
    let mut broken = plan.clone();
    broken.sync_points.clear();
    let raced = backend
        .execute_with(&TestDefs, &broken, &inst, &Inputs::default())
        .unwrap();
    assert_ne!(
        raced.read(&plan, "out").unwrap(),
        out,
        "removing the sync point went unnoticed"
    );
}

#[test]
fn a_sync_point_that_is_never_signalled_times_out() {
    let plan = compile_str("cross.ron", CROSS_QUEUE, &kinds(), 1).unwrap();
    let inst = plan.instantiate(&quantities()).unwrap();
    let mut broken = plan.clone();
    broken.sync_points[0].value = 99;
    let backend = CpuBackend {
        sync_timeout: Duration::from_millis(500),
        ..CpuBackend::default()
    };
    match backend.execute_with(&TestDefs, &broken, &inst, &Inputs::default()) {
        Err(CpuError::SyncTimeout { pass, value, .. }) => {
            assert_eq!((pass.as_str(), value), ("mix", 99))
        }
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("a deadlock must be an error"),
    }
}

#[test]
fn kinds_without_kernels_are_refused_by_name() {
    let src = r#"Graph(name: "g",
        resources: [Buffer(name: "out", size: Bytes(16), lifetime: Imported)],
        passes: [Pass(name: "r", kind: "kulikov.raster", writes: ["out"])],
        outputs: ["out"])"#;
    let plan = compile_str("g.ron", src, &strandgraph_passes::Registry, 1).unwrap();
    let inst = plan.instantiate(&quantities()).unwrap();
    let err = CpuBackend::default()
        .execute(&plan, &inst, &Inputs::default())
        .err()
        .expect("no kernel yet");
    assert!(err.to_string().contains("kulikov.raster"), "{err}");
}

#[test]
fn imported_inputs_are_uploaded_and_checked() {
    let plan = compile_str("cross.ron", CROSS_QUEUE, &kinds(), 1).unwrap();
    let inst = plan.instantiate(&quantities()).unwrap();
    let mut inputs = Inputs::default();
    inputs.set("b", vec![5; 4096]);
    let frame = CpuBackend::default()
        .execute_with(&TestDefs, &plan, &inst, &inputs)
        .unwrap();
    assert_eq!(
        frame.read(&plan, "out").unwrap()[0],
        hash(9).wrapping_mul(3).wrapping_add(5)
    );
    inputs.set("b", vec![5; 5000]);
    let err = CpuBackend::default()
        .execute_with(&TestDefs, &plan, &inst, &inputs)
        .err()
        .expect("too many words");
    assert!(matches!(err, CpuError::Input { .. }), "{err}");
}

#[test]
fn a_plan_larger_than_the_memory_limit_is_refused_by_name() {
    let plan = compile_str("cross.ron", CROSS_QUEUE, &kinds(), 1).unwrap();
    let inst = plan.instantiate(&quantities()).unwrap();
    let backend = CpuBackend {
        memory_limit: Some(1024),
        ..CpuBackend::default()
    };
    let err = backend
        .execute_with(&TestDefs, &plan, &inst, &Inputs::default())
        .err()
        .expect("over the limit");
    assert!(matches!(err, CpuError::OutOfMemory { .. }), "{err}");
    let text = err.to_string();
    assert!(text.contains("the largest") && text.contains('`'), "{text}");
    // At the plan's own size it runs.
    let roomy = CpuBackend {
        memory_limit: Some(1 << 30),
        ..CpuBackend::default()
    };
    assert!(
        roomy
            .execute_with(&TestDefs, &plan, &inst, &Inputs::default())
            .is_ok()
    );
}
