//! Fuzz the graph compiler on arbitrary text: parse, validate, cull, order,
//! lifetimes, aliasing and synchronisation must return a plan or positioned
//! errors, never panic. A plan is then instantiated for a scene whose
//! quantities come from the input too, so symbolic sizes meet huge and zero
//! counts (overflow must be an error, not a wrap or an allocation).
#![no_main]

use libfuzzer_sys::fuzz_target;
use strandgraph_graph::{AnyKind, Quantities, compile_str};

fuzz_target!(|data: &[u8]| {
    // The first 8 bytes choose the model count and the scene's quantities.
    let (head, text) = data.split_at(data.len().min(8));
    let Ok(text) = std::str::from_utf8(text) else {
        return;
    };
    let byte = |i: usize| u64::from(head.get(i).copied().unwrap_or(1));
    let models = (byte(0) % 6) as u32;
    let Ok(plan) = compile_str("fuzz.ron", text, &AnyKind, models) else {
        return;
    };
    let scale = |i: usize| {
        let b = byte(i);
        if b == 255 {
            u64::MAX / 3
        } else {
            b << (b % 40)
        }
    };
    let q = Quantities {
        strands: scale(1),
        vertices: scale(2),
        segments: scale(3),
        bundles: scale(4),
        mesh_strands: scale(5),
        models: u64::from(models),
        patches: scale(4),
        triangles: scale(5),
        lights: byte(6) % 8,
        width: (byte(7) * 17 + 1) as u32,
        height: (byte(7) * 9 + 1) as u32,
    };
    let _ = plan.instantiate(&q);
});
