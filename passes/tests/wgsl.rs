//! Reflects every pass's WGSL with naga and checks it against the pass
//! contract (DESIGN.md, "A test reflects every WGSL module with naga").
//!
//! Shaders share `shaders/common/layout.wgsl` (and the Kulikov helpers in
//! `shaders/kulikov/common.wgsl`) through naga_oil's `#import`: every file
//! with a `#define_import_path` is added to one `Composer` as a composable
//! module, and each pass's file is composed into a naga module from there.
//!
//! For every kind in `PASSES`:
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
//! The shared records are checked against the Rust structs: naga's layout
//! of each WGSL struct in layout.wgsl has the size (and the fields the CPU
//! kernels decode, the offsets) of the `#[repr(C)]` struct of the same name,
//! and so does every struct of that name in a pass's module (imported, or a
//! copy in a shader that does not compose).

use naga::valid::{Capabilities, ModuleInfo};
use naga::{AddressSpace, ImageClass, Module, ShaderStage, StorageAccess, TypeInner};
use naga_oil::compose::Composer;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use strandgraph_graph::AccessMode;
use strandgraph_passes::layout::{FrameData, LightData, ModelData, TriangleData};
use strandgraph_passes::wgsl::{Shaders, validate};
use strandgraph_passes::{GpuLayout, PASSES, PassDef};

/// What every shader may use: subgroup operations and subgroup barriers
/// (the Kulikov raster's request stacks, the cull's wave-aggregated atomics).
const BASE: Capabilities = Capabilities::SUBGROUP.union(Capabilities::SUBGROUP_BARRIER);

/// The capability tier of a shader file, beyond [`BASE`]. Capabilities are
/// checked per module (DESIGN.md), so each file is validated with exactly its
/// tier and a module that starts using more fails here.
fn capabilities_of(file: &str) -> Capabilities {
    match file {
        // The segment budget's proportional reduction is done in f64, as the
        // CPU kernel does (`budget as f64 / total as f64`).
        "kulikov/lod.wgsl" => BASE | Capabilities::FLOAT64,
        // atomic<u64> with atomicMin whose result is unused (DESIGN.md, "Shaders").
        // Lipp §3.1.2: 64-bit atomicMin into the G-buffer, result unused.
        "bench/atomic_min64.wgsl" | "lipp/raster.wgsl" => {
            BASE | Capabilities::SHADER_INT64 | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX
        }
        _ => BASE,
    }
}

/// Everything any module may use.
fn all_capabilities() -> Capabilities {
    strandgraph_passes::wgsl::all_capabilities()
}

fn shaders_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders")
}

/// Every composable module under `shaders/`, loaded by the composition the
/// backends use ([`strandgraph_passes::wgsl::Shaders`]).
fn composer() -> Shaders {
    Shaders::load(&shaders_dir()).unwrap_or_else(|e| panic!("{e}"))
}

/// Composes and validates one top-level shader with the given capabilities.
fn compose(
    composer: &mut Shaders,
    file: &str,
    source: &str,
    caps: Capabilities,
) -> Result<(Module, ModuleInfo), String> {
    let module = composer.module_from_source(file, source)?;
    let info = validate(&module, caps).map_err(|e| format!("{file}: {e}"))?;
    Ok((module, info))
}

/// A resource an entry point uses, as reflected from the module.
#[derive(Debug)]
struct Reflected {
    name: String,
    kind: Kind,
}

#[derive(Debug, PartialEq)]
enum Kind {
    Uniform { is_struct: bool },
    Storage { access: StorageAccess, atomic: bool },
    StorageTexture { access: StorageAccess },
    Texture,
    Sampler,
    Other(String),
}

fn contains_atomic(module: &Module, ty: naga::Handle<naga::Type>) -> bool {
    match &module.types[ty].inner {
        TypeInner::Atomic(_) => true,
        TypeInner::Array { base, .. } | TypeInner::BindingArray { base, .. } => {
            contains_atomic(module, *base)
        }
        TypeInner::Struct { members, .. } => members.iter().any(|m| contains_atomic(module, m.ty)),
        _ => false,
    }
}

/// `name` without naga_oil's module decoration: a binding declared in an
/// imported module (`shaders/kulikov/segments.wgsl`) keeps its WGSL name
/// before the suffix naga_oil appends (`Composer::decorated_name`: the
/// marker below, then the module path in base32).
fn undecorated(name: &str) -> &str {
    name.split_once("X_naga_oil_mod_X")
        .map_or(name, |(plain, _)| plain)
}

/// The group-0 resources the named entry points use, by binding number.
fn reflect(
    module: &Module,
    info: &ModuleInfo,
    entries: &[&str],
) -> Result<BTreeMap<u32, Reflected>, String> {
    let mut out = BTreeMap::new();
    for (index, ep) in module.entry_points.iter().enumerate() {
        if !entries.contains(&ep.name.as_str()) {
            continue;
        }
        let uses = info.get_entry_point(index);
        for (handle, var) in module.global_variables.iter() {
            if uses[handle].is_empty() {
                continue;
            }
            let Some(rb) = &var.binding else { continue };
            let name = undecorated(var.name.as_deref().unwrap_or_default()).to_string();
            if rb.group != 0 {
                return Err(format!("`{name}` is in group {}, expected 0", rb.group));
            }
            let inner = &module.types[var.ty].inner;
            let kind = match (var.space, inner) {
                (AddressSpace::Uniform, inner) => Kind::Uniform {
                    is_struct: matches!(inner, TypeInner::Struct { .. }),
                },
                (AddressSpace::Storage { access }, _) => Kind::Storage {
                    access,
                    atomic: contains_atomic(module, var.ty),
                },
                (AddressSpace::Handle, TypeInner::Image { class, .. }) => match class {
                    ImageClass::Storage { access, .. } => Kind::StorageTexture { access: *access },
                    _ => Kind::Texture,
                },
                (AddressSpace::Handle, TypeInner::Sampler { .. }) => Kind::Sampler,
                (space, inner) => Kind::Other(format!("{space:?} {inner:?}")),
            };
            if let Some(prev) = out.get(&rb.binding) {
                let prev: &Reflected = prev;
                if prev.name != name {
                    return Err(format!(
                        "binding {} is both `{}` and `{name}`",
                        rb.binding, prev.name
                    ));
                }
                continue;
            }
            out.insert(rb.binding, Reflected { name, kind });
        }
    }
    Ok(out)
}

fn access_matches(mode: AccessMode, kind: &Kind) -> bool {
    let rw = StorageAccess::LOAD | StorageAccess::STORE;
    match (mode, kind) {
        (AccessMode::Read, Kind::Storage { access, .. }) => *access == StorageAccess::LOAD,
        (AccessMode::Read, Kind::StorageTexture { access }) => *access == StorageAccess::LOAD,
        (AccessMode::Read, Kind::Texture | Kind::Uniform { .. }) => true,
        (AccessMode::Write, Kind::Storage { access, .. }) => *access == rw,
        (AccessMode::Write, Kind::StorageTexture { access }) => {
            access.contains(StorageAccess::STORE)
        }
        (AccessMode::Atomic, Kind::Storage { access, atomic }) => *access == rw && *atomic,
        (AccessMode::Atomic, Kind::StorageTexture { access }) => *access == rw,
        _ => false,
    }
}

/// The shared records and their sizes on the Rust side.
fn record_sizes() -> [(&'static str, usize); 6] {
    use strandgraph_passes::kulikov::{ModelLod, tile_alloc::ModelTiles};
    [
        ("FrameData", std::mem::size_of::<FrameData>()),
        ("ModelData", std::mem::size_of::<ModelData>()),
        ("LightData", std::mem::size_of::<LightData>()),
        ("TriangleData", std::mem::size_of::<TriangleData>()),
        ("ModelLod", ModelLod::WORDS * 4),
        ("ModelTiles", ModelTiles::WORDS * 4),
    ]
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

/// Checks one definition's shader; returns what is wrong with it.
fn check_definition(composer: &mut Shaders, def: &dyn PassDef) -> Result<(), String> {
    let shader = def.shader();
    let path = shaders_dir().join(shader.file);
    let source = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let (module, info) = compose(composer, shader.file, &source, capabilities_of(shader.file))?;

    let find = |name: &str| module.entry_points.iter().find(|ep| ep.name == name);
    let entry = find(shader.entry).ok_or_else(|| format!("no entry point `{}`", shader.entry))?;
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
            if entry.stage != ShaderStage::Vertex {
                return Err(format!(
                    "`{}` is {:?}, expected a vertex entry",
                    shader.entry, entry.stage
                ));
            }
            let frag = find(fragment).ok_or_else(|| format!("no fragment entry `{fragment}`"))?;
            if frag.stage != ShaderStage::Fragment {
                return Err(format!(
                    "`{fragment}` is {:?}, expected a fragment entry",
                    frag.stage
                ));
            }
            entries.push(fragment);
        }
    }
    // The draw state names the fragment entries it draws with, the first
    // one being `Shader::fragment`; compute passes have none.
    let defaults = ron::Value::Map(Default::default());
    let raster = def
        .raster(&defaults, &strandgraph_graph::Quantities::example())
        .map_err(|e| e.to_string())?;
    match (&raster, shader.fragment) {
        (None, None) => {}
        (Some(r), Some(fragment)) => {
            if r.draws.first().map(|d| d.fragment) != Some(fragment) {
                return Err(format!("raster() draws do not start with `{fragment}`"));
            }
            for d in &r.draws[1..] {
                let ep = find(d.fragment)
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

    let used = reflect(&module, &info, &entries)?;
    let mut errors = record_size_errors(&module);
    let numbers: Vec<u32> = used.keys().copied().collect();
    let expected_numbers: Vec<u32> = (0..numbers.len() as u32).collect();
    if numbers != expected_numbers {
        errors.push(format!(
            "bindings in use are {numbers:?}, expected 0..{}",
            numbers.len()
        ));
    }
    // Binding 0 is the parameter block; without one, the resources are
    // compared from binding 0 on, so every mismatch is reported at once.
    let first = match used.values().next() {
        Some(Reflected {
            kind: Kind::Uniform { is_struct: true },
            ..
        }) => 1,
        other => {
            let found = other.map_or("nothing".to_string(), |r| {
                format!("`{}` ({:?})", r.name, r.kind)
            });
            errors.push(format!(
                "binding 0 must be the uniform struct of the pass parameters, found {found}"
            ));
            0
        }
    };
    let resources: Vec<(u32, &Reflected)> = used.iter().skip(first).map(|(n, r)| (*n, r)).collect();
    match def.bindings() {
        Some(declared) => {
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
            for (b, (number, r)) in declared.iter().zip(&resources) {
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
        }
        // The pass binds whatever the graph gives it, one written resource at a time.
        None => {
            if resources.is_empty()
                || !resources
                    .iter()
                    .all(|(_, r)| access_matches(AccessMode::Write, &r.kind))
            {
                errors.push(format!(
                    "expected writable resources after the parameters, found {resources:?}"
                ));
            }
        }
    }
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

/// Composes a probe that binds every shared record, so their layouts can be read.
fn layout_probe(composer: &mut Shaders) -> Module {
    let source = "
#import strandgraph::layout::{FrameData, ModelData, LightData, TriangleData, ModelLod, ModelTiles}
@group(0) @binding(0) var<storage> frame: FrameData;
@group(0) @binding(1) var<storage> models: array<ModelData>;
@group(0) @binding(2) var<storage> lights: array<LightData>;
@group(0) @binding(3) var<storage> triangles: array<TriangleData>;
@group(0) @binding(4) var<storage> lods: array<ModelLod>;
@group(0) @binding(5) var<storage> tiles: array<ModelTiles>;
@compute @workgroup_size(1)
fn probe() {
    _ = frame.near;
    _ = models[0].flags;
    _ = lights[0].radiance;
    _ = triangles[0].mesh;
    _ = lods[0].strands;
    _ = tiles[0].valid;
}
";
    compose(composer, "layout_probe.wgsl", source, BASE)
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

#[test]
fn shared_layout_matches_the_rust_records() {
    let mut composer = composer();
    let module = layout_probe(&mut composer);
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let size_of_wgsl = |name: &str| {
        let decorated = Composer::decorated_name(Some("strandgraph::layout"), name);
        let (handle, _) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(&decorated) || t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("layout.wgsl has no struct {name}"));
        layouter[handle].size as usize
    };
    let expected = record_sizes();
    for (name, size) in expected {
        assert_eq!(size_of_wgsl(name), size, "WGSL {name} vs the Rust record");
    }
}

/// Field offsets the CPU kernels decode by word index must match the WGSL structs.
#[test]
fn shared_layout_field_offsets_match() {
    let mut composer = composer();
    let module = layout_probe(&mut composer);
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let offsets = |name: &str| -> BTreeMap<String, u32> {
        let decorated = Composer::decorated_name(Some("strandgraph::layout"), name);
        let ty = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(&decorated))
            .unwrap_or_else(|| panic!("layout.wgsl has no struct {name}"))
            .1;
        let TypeInner::Struct { members, .. } = &ty.inner else {
            panic!("{name} is not a struct")
        };
        members
            .iter()
            .map(|m| (m.name.clone().unwrap(), m.offset))
            .collect()
    };
    let frame = offsets("FrameData");
    assert_eq!(
        (
            frame["camera_pos"],
            frame["screen"],
            frame["near"],
            frame["pixels_per_unit"],
            frame["_pad"]
        ),
        (
            std::mem::offset_of!(FrameData, camera_pos) as u32,
            std::mem::offset_of!(FrameData, screen) as u32,
            std::mem::offset_of!(FrameData, near) as u32,
            std::mem::offset_of!(FrameData, pixels_per_unit) as u32,
            std::mem::offset_of!(FrameData, _pad) as u32,
        )
    );
    let model = offsets("ModelData");
    for (field, rust) in [
        ("bounds_min", std::mem::offset_of!(ModelData, bounds_min)),
        (
            "strand_first",
            std::mem::offset_of!(ModelData, strand_first),
        ),
        ("flags", std::mem::offset_of!(ModelData, flags)),
        (
            "mesh_rotation",
            std::mem::offset_of!(ModelData, mesh_rotation),
        ),
        ("color", std::mem::offset_of!(ModelData, color)),
        (
            "fedora_sphere",
            std::mem::offset_of!(ModelData, fedora_sphere),
        ),
        (
            "min_fraction",
            std::mem::offset_of!(ModelData, min_fraction),
        ),
    ] {
        assert_eq!(model[field] as usize, rust, "ModelData.{field}");
    }
    let tri = offsets("TriangleData");
    assert_eq!(
        tri["mesh"] as usize,
        std::mem::offset_of!(TriangleData, mesh)
    );
    let light = offsets("LightData");
    assert_eq!(
        light["radiance"] as usize,
        std::mem::offset_of!(LightData, radiance)
    );
    // The 8-word records, word by word (ModelLod::load, ModelTiles::load).
    let lod = offsets("ModelLod");
    let words: Vec<u32> = [
        "strands",
        "vertex_step",
        "thickness_scale",
        "segments_per_strand",
        "strand_prefix",
        "depth_near",
        "depth_far",
    ]
    .iter()
    .map(|f| lod[*f] / 4)
    .collect();
    assert_eq!(words, vec![0, 1, 2, 3, 4, 5, 6]);
    let tiles = offsets("ModelTiles");
    let words: Vec<u32> = [
        "first_tile",
        "grid_w",
        "grid_h",
        "origin_x",
        "origin_y",
        "downscale",
        "valid",
    ]
    .iter()
    .map(|f| tiles[*f] / 4)
    .collect();
    assert_eq!(words, vec![0, 1, 2, 3, 4, 5, 6]);
}

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

/// The f32 bits of constant `name` in `module`, following aliases.
fn constant_bits(module: &Module, name: &str) -> Option<u32> {
    let c = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))?;
    let mut init = c.1.init;
    loop {
        match module.global_expressions[init] {
            naga::Expression::Literal(naga::Literal::F32(v)) => return Some(v.to_bits()),
            naga::Expression::Constant(h) => init = module.constants[h].init,
            _ => return None,
        }
    }
}

/// Constants whose exact bits both sides must share: a kernel multiplies by
/// them where a division would round differently on a GPU (payload.rs).
#[test]
fn wgsl_constants_have_the_rust_bits() {
    let source = "
#import strandgraph::lipp::{DEPTH_MAX, INV_DEPTH_MAX}
const PROBE_DEPTH_MAX: f32 = DEPTH_MAX;
const PROBE_INV_DEPTH_MAX: f32 = INV_DEPTH_MAX;
@compute @workgroup_size(1)
fn probe() {
    _ = PROBE_DEPTH_MAX * PROBE_INV_DEPTH_MAX;
}
";
    let mut composer = composer();
    let module = compose(&mut composer, "constants_probe.wgsl", source, BASE)
        .unwrap_or_else(|e| panic!("{e}"))
        .0;
    use strandgraph_passes::lipp::payload::{DEPTH_MAX, INV_DEPTH_MAX};
    for (name, rust) in [
        ("PROBE_DEPTH_MAX", DEPTH_MAX),
        ("PROBE_INV_DEPTH_MAX", INV_DEPTH_MAX),
    ] {
        assert_eq!(constant_bits(&module, name), Some(rust.to_bits()), "{name}");
    }
}
