//! `PassDef::gpu_params` against the WGSL parameter block each pass's entry
//! point uses at binding 0: the pass's `#[repr(C)]` GPU block has the WGSL
//! struct's member names, in order, at naga's offsets, and its size.

mod wgsl;

use naga::{AddressSpace, Module, TypeInner};
use strandgraph_passes::wgsl::all_capabilities;
use strandgraph_passes::{GpuLayout, PASSES};
use wgsl::{compose, composer, shaders_dir};

/// The members of the WGSL struct `ty` as (name, byte offset).
fn members(module: &Module, ty: naga::Handle<naga::Type>) -> Vec<(String, usize)> {
    match &module.types[ty].inner {
        TypeInner::Struct { members, .. } => members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize))
            .collect(),
        _ => Vec::new(),
    }
}

/// What differs between a pass's Rust GPU block and the WGSL struct: names,
/// order, offsets and size. Rust fields named `_pad…` may be padding the
/// WGSL struct leaves implicit (its size rounds up to its alignment).
fn layout_mismatch(rust: &GpuLayout, wgsl: &[(String, usize)], wgsl_size: usize) -> Option<String> {
    let rust_fields: Vec<(String, usize)> = rust
        .fields
        .iter()
        .filter(|(name, _)| !name.starts_with("_pad") || wgsl.iter().any(|(w, _)| w == name))
        .map(|(name, offset)| (name.to_string(), *offset))
        .collect();
    if rust_fields != wgsl {
        return Some(format!(
            "Rust fields {rust_fields:?}, WGSL members {wgsl:?}"
        ));
    }
    (rust.size != wgsl_size).then(|| format!("Rust block is {} bytes, WGSL {wgsl_size}", rust.size))
}

/// `PassDef::gpu_params` fills the WGSL parameter block at binding 0: the
/// pass's `#[repr(C)]` GPU block has the uniform struct's member names, in
/// order, at naga's offsets, and its size; the words are that many bytes.
#[test]
fn gpu_params_fill_the_wgsl_parameter_block() {
    let mut composer = composer();
    let q = strandgraph_graph::Quantities::example();
    let mut failures = Vec::new();
    let mut checked = 0;
    for &def in PASSES {
        let kind = def.kind();
        let shader = def.shader();
        let source = std::fs::read_to_string(shaders_dir().join(shader.file)).unwrap();
        let (module, info) = compose(&mut composer, shader.file, &source, all_capabilities())
            .unwrap_or_else(|e| panic!("{e}"));
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        // The block this pass's entry point uses: one module may hold several
        // entry points with their own blocks at binding 0 (lipp/raster.wgsl).
        let entries: Vec<usize> = (module.entry_points.iter().enumerate())
            .filter(|(_, ep)| ep.name == shader.entry || Some(ep.name.as_str()) == shader.fragment)
            .map(|(i, _)| i)
            .collect();
        let used = |h: naga::Handle<naga::GlobalVariable>| {
            entries
                .iter()
                .any(|&e| !info.get_entry_point(e)[h].is_empty())
        };
        let block = module.global_variables.iter().find(|(h, v)| {
            v.space == AddressSpace::Uniform
                && used(*h)
                && v.binding
                    .as_ref()
                    .is_some_and(|b| b.group == 0 && b.binding == 0)
        });
        let Some((_, var)) = block else {
            failures.push(format!("{kind}: no uniform at binding 0"));
            continue;
        };
        let wgsl_bytes = layouter[var.ty].size as usize;
        let Some(layout) = def.gpu_layout() else {
            failures.push(format!("{kind}: no GPU block layout"));
            continue;
        };
        if let Some(e) = layout_mismatch(&layout, &members(&module, var.ty), wgsl_bytes) {
            failures.push(format!("{kind}: {e}"));
            continue;
        }
        match def.gpu_params(&ron::Value::Unit, &q) {
            Ok(words) if words.len() * 4 == wgsl_bytes => checked += 1,
            Ok(words) => failures.push(format!(
                "{kind}: gpu_params gives {} words, the WGSL block is {wgsl_bytes} bytes",
                words.len()
            )),
            Err(e) => failures.push(format!("{kind}: {e}")),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert_eq!(checked, PASSES.len(), "every pass's block is checked");
}

/// The check catches a swapped field, a renamed one and a size mismatch.
#[test]
fn layout_mismatches_are_reported() {
    let wgsl = vec![("a".to_string(), 0), ("b".to_string(), 4)];
    let ok = GpuLayout {
        fields: &[("a", 0), ("b", 4), ("_pad0", 8), ("_pad1", 12)],
        size: 16,
    };
    assert_eq!(layout_mismatch(&ok, &wgsl, 16), None);
    let swapped = GpuLayout {
        fields: &[("b", 0), ("a", 4)],
        size: 8,
    };
    assert!(layout_mismatch(&swapped, &wgsl, 8).is_some());
    let renamed = GpuLayout {
        fields: &[("a", 0), ("c", 4)],
        size: 8,
    };
    assert!(layout_mismatch(&renamed, &wgsl, 8).is_some());
    assert!(layout_mismatch(&ok, &wgsl, 32).is_some());
}
