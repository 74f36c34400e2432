//! The shared WGSL against the Rust side: the records of
//! `shaders/common/layout.wgsl` have the size (and the fields the CPU
//! kernels decode, the offsets) of the `#[repr(C)]` struct of the same name,
//! and the constants the Lipp kernels share have the same bits.

mod wgsl;

use naga::proc::Layouter;
use naga::{Module, TypeInner};
use naga_oil::compose::Composer;
use std::collections::BTreeMap;
use strandgraph_passes::layout::{FrameData, LightData, ModelData, TriangleData};
use wgsl::{BASE, compose, composer, record_sizes};

/// Composes a probe that binds every shared record, so their layouts can be
/// read, and lays its types out as naga does.
fn layout_probe() -> (Module, Layouter) {
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
    let module = compose(&mut composer(), "layout_probe.wgsl", source, BASE)
        .unwrap_or_else(|e| panic!("{e}"))
        .0;
    let mut layouter = Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    (module, layouter)
}

#[test]
fn shared_layout_matches_the_rust_records() {
    let (module, layouter) = layout_probe();
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
    let (module, _) = layout_probe();
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
    let words = |record: &str, fields: [&str; 7]| -> Vec<u32> {
        let offsets = offsets(record);
        fields.iter().map(|f| offsets[*f] / 4).collect()
    };
    let lod = [
        "strands",
        "vertex_step",
        "thickness_scale",
        "segments_per_strand",
        "strand_prefix",
        "depth_near",
        "depth_far",
    ];
    assert_eq!(words("ModelLod", lod), vec![0, 1, 2, 3, 4, 5, 6]);
    let tiles = [
        "first_tile",
        "grid_w",
        "grid_h",
        "origin_x",
        "origin_y",
        "downscale",
        "valid",
    ];
    assert_eq!(words("ModelTiles", tiles), vec![0, 1, 2, 3, 4, 5, 6]);
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

/// Asserts that each WGSL constant expression (after `import`, e.g.
/// `DEPTH_MAX` or `R_ALBEDO_FIT[3]`) has the f32 bits of its Rust value.
fn assert_wgsl_bits(import: &str, constants: &[(String, f32)]) {
    let aliases: String = constants
        .iter()
        .enumerate()
        .map(|(i, (expr, _))| format!("const PROBE_{i}: f32 = {expr};\n"))
        .collect();
    let source = format!(
        "#import {import}\n{aliases}@compute @workgroup_size(1)\nfn probe() {{\n    _ = PROBE_0;\n}}\n"
    );
    let mut composer = composer();
    let module = compose(&mut composer, "constants_probe.wgsl", &source, BASE)
        .unwrap_or_else(|e| panic!("{e}"))
        .0;
    for (i, (expr, rust)) in constants.iter().enumerate() {
        let bits = constant_bits(&module, &format!("PROBE_{i}"));
        assert_eq!(bits, Some(rust.to_bits()), "{expr}");
    }
}

/// Constants whose exact bits both sides must share: a kernel multiplies by
/// them where a division would round differently on a GPU (payload.rs).
#[test]
fn wgsl_constants_have_the_rust_bits() {
    use strandgraph_passes::lipp::payload::{DEPTH_MAX, INV_DEPTH_MAX};
    assert_wgsl_bits(
        "strandgraph::lipp::{DEPTH_MAX, INV_DEPTH_MAX}",
        &[
            ("DEPTH_MAX".into(), DEPTH_MAX),
            ("INV_DEPTH_MAX".into(), INV_DEPTH_MAX),
        ],
    );
}

/// Chiang's R albedo fit (chiang.wgsl `R_ALBEDO_FIT`) has the Rust
/// coefficients' bits, element by element.
#[test]
fn r_albedo_fit_has_the_rust_bits() {
    use strandgraph_passes::lipp::chiang::R_ALBEDO_FIT;
    let constants: Vec<(String, f32)> = R_ALBEDO_FIT
        .iter()
        .enumerate()
        .map(|(i, &c)| (format!("R_ALBEDO_FIT[{i}]"), c))
        .collect();
    assert_wgsl_bits("strandgraph::chiang::R_ALBEDO_FIT", &constants);
}
