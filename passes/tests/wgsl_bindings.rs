//! Every pass kind's shader against its interface. For every kind in
//! `PASSES`:
//! - the shader file exists, composes and validates with the capabilities
//!   its tier allows (`capabilities_of`), no more;
//! - the entry point exists: a compute entry with `@workgroup_size` equal to
//!   `workgroup_size()`, or for a raster pass (`Shader.fragment` is `Some`)
//!   a vertex entry and a fragment entry;
//! - the resources the entry points use are `@group(0)`, numbered 0..=N
//!   without gaps: binding 0 is the uniform block of the pass parameters (a
//!   struct), bindings 1..=N are `bindings()` in order (for a raster pass,
//!   the leading ones: its trailing colour and depth attachments are not
//!   bound), named as the binding
//!   with `.` written `_` (or `<entry>_<name>` where one file holds several
//!   entry points that bind the same resource at different numbers), and
//!   accessed as declared (Read: `read` storage,
//!   a sampled texture or a read-only storage texture; Write: `read_write`
//!   storage or a writable storage texture; Atomic: `read_write` storage
//!   holding atomics).
//!
//! The shared records are checked against the Rust structs: every struct of
//! a module that carries a shared record's name (imported from layout.wgsl,
//! or a copy in a shader that does not compose) has the Rust record's size.

mod wgsl;

use naga::valid::{Capabilities, ModuleInfo};
use naga::{EntryPoint, Module, ShaderStage};
use naga_oil::compose::Composer;
use std::collections::BTreeMap;
use strandgraph_graph::AccessMode;
use strandgraph_passes::raster_state::Geometry;
use strandgraph_passes::wgsl::Shaders;
use strandgraph_passes::{PASSES, PassDef, Shader};
use wgsl::reflect::{Kind, Reflected, access_matches, reflect};
use wgsl::{BASE, compose, composer, record_sizes, shaders_dir};

/// The capability tier of a shader file, beyond [`BASE`]. Capabilities are
/// checked per module (docs/architecture.md), so each file is validated with exactly its
/// tier and a module that starts using more fails here.
fn capabilities_of(file: &str) -> Capabilities {
    match file {
        // The segment budget's proportional reduction is done in f64, as the
        // CPU kernel does (`budget as f64 / total as f64`).
        "kulikov/lod.wgsl" => BASE | Capabilities::FLOAT64,
        // atomic<u64> with atomicMin whose result is unused (docs/architecture.md, "Shaders").
        // Lipp §3.1.2: 64-bit atomicMin into the G-buffer, result unused;
        // the opaque meshes' visibility buffer likewise.
        "bench/atomic_min64.wgsl" | "lipp/raster.wgsl" | "opaque_mesh/visibility.wgsl" => {
            BASE | Capabilities::SHADER_INT64 | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX
        }
        // The same atomicMin from a fragment shader run per sample with
        // early depth tests (docs/hw_strands.md).
        "hw_strands/raster.wgsl" => {
            BASE | Capabilities::SHADER_INT64
                | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX
                | Capabilities::EARLY_DEPTH_TEST
                | Capabilities::MULTISAMPLED_SHADING
        }
        // The same fragment behind task and mesh shaders (VK_EXT_mesh_shader).
        "hw_strands/mesh.wgsl" => {
            BASE | Capabilities::SHADER_INT64
                | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX
                | Capabilities::EARLY_DEPTH_TEST
                | Capabilities::MULTISAMPLED_SHADING
                | Capabilities::MESH_SHADER
        }
        _ => BASE,
    }
}

/// Structs of a module that carry a shared record's name (imported from
/// layout.wgsl, or a copy) but not its size.
fn record_size_errors(module: &Module) -> Vec<String> {
    let mut layouter = naga::proc::Layouter::default();
    if let Err(e) = layouter.update(module.to_ctx()) {
        return vec![format!("layout: {e:?}")];
    }
    let mut errors = Vec::new();
    for (handle, ty) in module.types.iter() {
        let Some(name) = ty.name.as_deref() else {
            continue;
        };
        for (record, size) in record_sizes() {
            let decorated = Composer::decorated_name(Some("strandgraph::layout"), record);
            if (name == record || name == decorated) && layouter[handle].size as usize != size {
                errors.push(format!(
                    "struct {record} is {} bytes, the Rust record {size}",
                    layouter[handle].size
                ));
            }
        }
    }
    errors
}

/// The shader file of `shader`, composed and validated with its tier.
fn load(composer: &mut Shaders, shader: &Shader) -> Result<(Module, ModuleInfo), String> {
    let path = shaders_dir().join(shader.file);
    let source = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    compose(composer, shader.file, &source, capabilities_of(shader.file))
}

fn find<'m>(module: &'m Module, name: &str) -> Option<&'m EntryPoint> {
    module.entry_points.iter().find(|ep| ep.name == name)
}

/// The entry points `def` runs, checked for stage and workgroup size: its
/// compute entry, or its vertex (or task and mesh) and fragment entries.
fn entry_points(module: &Module, def: &dyn PassDef) -> Result<Vec<&'static str>, String> {
    let shader = def.shader();
    let entry =
        find(module, shader.entry).ok_or_else(|| format!("no entry point `{}`", shader.entry))?;
    let mut entries = vec![shader.entry];
    match shader.fragment {
        None => {
            if entry.stage != ShaderStage::Compute {
                return Err(format!(
                    "`{}` is {:?}, expected a compute entry",
                    shader.entry, entry.stage
                ));
            }
            let expected = [def.workgroup_size(), 1, 1];
            if entry.workgroup_size != expected {
                return Err(format!(
                    "`{}` has @workgroup_size{:?}, the definition says {expected:?}",
                    shader.entry, entry.workgroup_size
                ));
            }
        }
        Some(fragment) => {
            let defaults = ron::Value::Map(Default::default());
            let raster = def
                .raster(&defaults, &strandgraph_graph::Quantities::example())
                .map_err(|e| e.to_string())?;
            // A mesh pass's entry is its mesh entry, launched by its task entry.
            let task = match raster.map(|r| r.geometry) {
                Some(Geometry::MeshTasks { task, .. }) => Some(task),
                _ => None,
            };
            let expected = if task.is_some() {
                ShaderStage::Mesh
            } else {
                ShaderStage::Vertex
            };
            if entry.stage != expected {
                return Err(format!(
                    "`{}` is {:?}, expected a {expected:?} entry",
                    shader.entry, entry.stage
                ));
            }
            if let Some(task) = task {
                let ep = find(module, task).ok_or_else(|| format!("no task entry `{task}`"))?;
                if ep.stage != ShaderStage::Task {
                    return Err(format!("`{task}` is {:?}, expected a task entry", ep.stage));
                }
                entries.push(task);
            }
            let frag =
                find(module, fragment).ok_or_else(|| format!("no fragment entry `{fragment}`"))?;
            if frag.stage != ShaderStage::Fragment {
                return Err(format!(
                    "`{fragment}` is {:?}, expected a fragment entry",
                    frag.stage
                ));
            }
            entries.push(fragment);
        }
    }
    // Entry points a switch selects (PassDef::entries): the same stage and
    // workgroup size as the default one.
    for variant in def.entries().into_iter().skip(1) {
        let ep = find(module, variant)
            .ok_or_else(|| format!("no entry point `{variant}` (PassDef::entries)"))?;
        if ep.stage != entry.stage || ep.workgroup_size != entry.workgroup_size {
            return Err(format!(
                "`{variant}` is {:?} {:?}, `{}` is {:?} {:?}",
                ep.stage, ep.workgroup_size, shader.entry, entry.stage, entry.workgroup_size
            ));
        }
        entries.push(variant);
    }
    Ok(entries)
}

/// The draw state names the fragment entries it draws with, the first
/// one being `Shader::fragment`; compute passes have none.
fn check_draws(module: &Module, def: &dyn PassDef) -> Result<(), String> {
    let defaults = ron::Value::Map(Default::default());
    let raster = def
        .raster(&defaults, &strandgraph_graph::Quantities::example())
        .map_err(|e| e.to_string())?;
    match (&raster, def.shader().fragment) {
        (None, None) => {}
        (Some(r), Some(fragment)) => {
            if r.draws.first().map(|d| d.fragment) != Some(fragment) {
                return Err(format!("raster() draws do not start with `{fragment}`"));
            }
            for d in &r.draws[1..] {
                let ep = find(module, d.fragment)
                    .ok_or_else(|| format!("draw entry `{}` is missing", d.fragment))?;
                if ep.stage != ShaderStage::Fragment {
                    return Err(format!(
                        "draw entry `{}` is not a fragment entry",
                        d.fragment
                    ));
                }
            }
        }
        (Some(_), None) => return Err("raster() is Some for a compute pass".into()),
        (None, Some(_)) => return Err("a raster pass without raster() draw state".into()),
    }
    Ok(())
}

/// The binding numbers in use must be 0..N without gaps.
fn numbering_error(used: &BTreeMap<u32, Reflected>) -> Option<String> {
    let numbers: Vec<u32> = used.keys().copied().collect();
    let expected_numbers: Vec<u32> = (0..numbers.len() as u32).collect();
    (numbers != expected_numbers).then(|| {
        format!(
            "bindings in use are {numbers:?}, expected 0..{}",
            numbers.len()
        )
    })
}

/// Binding 0 must be the parameter block.
fn parameter_block_error(used: &BTreeMap<u32, Reflected>) -> Option<String> {
    match used.values().next() {
        Some(Reflected {
            kind: Kind::Uniform { is_struct: true },
            ..
        }) => None,
        other => {
            let found = other.map_or("nothing".to_string(), |r| {
                format!("`{}` ({:?})", r.name, r.kind)
            });
            Some(format!(
                "binding 0 must be the uniform struct of the pass parameters, found {found}"
            ))
        }
    }
}

/// The resources after the parameter block against `def.bindings()`: count,
/// names and access.
fn resource_errors(def: &dyn PassDef, resources: &[(u32, &Reflected)]) -> Vec<String> {
    let shader = def.shader();
    let mut errors = Vec::new();
    let Some(declared) = def.bindings() else {
        // The pass binds whatever the graph gives it, one written resource at a time.
        if resources.is_empty()
            || !resources
                .iter()
                .all(|(_, r)| access_matches(AccessMode::Write, &r.kind))
        {
            errors.push(format!(
                "expected writable resources after the parameters, found {resources:?}"
            ));
        }
        return errors;
    };
    // A raster pass binds its declared resources up to its attachments
    // (colour and depth targets are not bound), which come last.
    let bound = if shader.fragment.is_some() {
        resources.len().min(declared.len())
    } else {
        declared.len()
    };
    let declared = &declared[..bound];
    if resources.len() != declared.len() {
        let names: Vec<&str> = resources.iter().map(|(_, r)| r.name.as_str()).collect();
        errors.push(format!(
            "{} bound resources after the parameters ({names:?}), the definition declares {}",
            resources.len(),
            declared.len()
        ));
    }
    for (b, (number, r)) in declared.iter().zip(resources) {
        let want = b.name.replace('.', "_");
        let prefixed = format!("{}_{want}", shader.entry);
        if r.name != want && r.name != prefixed {
            errors.push(format!(
                "binding {number} is `{}`, expected `{want}`",
                r.name
            ));
        }
        if !access_matches(b.mode, &r.kind) {
            errors.push(format!(
                "binding {number} `{}` is {:?}, declared {:?}",
                r.name, r.kind, b.mode
            ));
        }
    }
    errors
}

/// Checks one definition's shader; returns what is wrong with it. The shader
/// must load and have the right entry points and draws before its bindings
/// are compared; the binding checks then report every mismatch at once.
fn check_definition(composer: &mut Shaders, def: &dyn PassDef) -> Result<(), String> {
    let (module, info) = load(composer, &def.shader())?;
    let entries = entry_points(&module, def)?;
    check_draws(&module, def)?;
    let used = reflect(&module, &info, &entries)?;
    let mut errors = record_size_errors(&module);
    errors.extend(numbering_error(&used));
    let block_error = parameter_block_error(&used);
    // Without a parameter block, the resources are compared from binding 0
    // on, so every mismatch is reported at once.
    let first = if block_error.is_none() { 1 } else { 0 };
    errors.extend(block_error);
    let resources: Vec<(u32, &Reflected)> = used.iter().skip(first).map(|(n, r)| (*n, r)).collect();
    errors.extend(resource_errors(def, &resources));
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors.join("; "))
    }
}

#[test]
fn every_definition_has_a_valid_shader_matching_its_interface() {
    let mut composer = composer();
    let mut checked = Vec::new();
    let mut failures = Vec::new();
    for &def in PASSES {
        let file = def.shader().file;
        match check_definition(&mut composer, def) {
            Ok(()) => checked.push(format!("{} ({file})", def.kind())),
            Err(e) => failures.push(format!("{} ({file}): {e}", def.kind())),
        }
    }
    eprintln!(
        "{} definitions match their shader:\n{}",
        checked.len(),
        checked.join("\n")
    );
    assert!(
        failures.is_empty(),
        "{} shader(s) do not match their definition:\n{}",
        failures.len(),
        failures.join("\n")
    );
    assert!(!checked.is_empty(), "no definition was checked");
}
