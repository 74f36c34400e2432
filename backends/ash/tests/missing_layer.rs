//! Asking for validation without the layer installed is an error naming the
//! layer, not a silent run without it. Its own test binary: the loader's
//! layer search path is process-wide.

use strandgraph_ash::{AshBackend, AshError, Validation};
use strandgraph_graph::compile_str;
use strandgraph_passes::Registry;

#[test]
fn a_missing_validation_layer_is_an_error() {
    // SAFETY: this binary's only test; nothing else reads the environment concurrently.
    unsafe {
        std::env::set_var("VK_LAYER_PATH", "/nonexistent-strandgraph-layers");
        std::env::remove_var("VK_ADD_LAYER_PATH");
    }
    let plan = compile_str(
        "clear.ron",
        r#"Graph(
            name: "clear",
            resources: [Buffer(name: "out", size: Bytes(64), lifetime: Imported)],
            passes: [Pass(name: "clear", kind: "common.clear", params: {"value": 7}, writes: ["out"])],
            outputs: ["out"],
        )"#,
        &Registry,
        1,
    )
    .unwrap();
    let instance = plan.instantiate(&Default::default()).unwrap();
    let backend = AshBackend {
        validation: Validation::Sync,
        ..AshBackend::default()
    };
    match backend.open(&plan, &instance) {
        Err(AshError::LayerMissing(layer)) => assert_eq!(layer, "VK_LAYER_KHRONOS_validation"),
        Err(e) => panic!("expected LayerMissing, got {e}"),
        Ok(_) => panic!("validation was requested without the layer and the session opened"),
    }
}
