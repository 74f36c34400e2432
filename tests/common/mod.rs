//! Helpers the three-way differential tests share (each test file uses
//! part of them).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use strandgraph::compare::flip;
use strandgraph::frame::Prepared;
use strandgraph::images::{Display, to_picture};
use strandgraph_ash::{AshBackend, Session, Validation};

pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Where a failing comparison writes its images: `$STRANDGRAPH_DIFF_OUT`,
/// else `target/<test>`.
pub fn out_dir(test: &str) -> PathBuf {
    let dir = std::env::var_os("STRANDGRAPH_DIFF_OUT")
        .map_or_else(|| root().join("target").join(test), PathBuf::from);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// One frame on ash under the Khronos layer with synchronization
/// validation (any message fails it); no device or no layer is a failure.
pub fn ash(p: &Prepared, alias: bool) -> Session {
    ash_with(
        p,
        AshBackend {
            alias,
            ..AshBackend::default()
        },
    )
}

/// [`ash`] with `backend`'s other settings (validation is always on).
pub fn ash_with(p: &Prepared, backend: AshBackend) -> Session {
    let backend = AshBackend {
        validation: Validation::Sync,
        ..backend
    };
    let (session, frame) = backend
        .execute(&p.plan, &p.instance, &p.upload)
        .unwrap_or_else(|e| {
            panic!(
                "ash backend failed: {e}\n(no device or layer? apt-get install mesa-vulkan-drivers \
                 libvulkan1 vulkan-validationlayers, or run scripts/test.sh)"
            )
        });
    for n in &session.notes {
        eprintln!("ash: {n}");
    }
    assert_eq!(frame.timings.len(), p.plan.order.len());
    session
}

/// One frame on the CPU simulator (the reference) at `subgroup_width`,
/// without aliasing so every transient can be read.
pub fn cpu(p: &Prepared, subgroup_width: u32) -> strandgraph_cpu::Frame<'static> {
    strandgraph_cpu::CpuBackend {
        subgroup_width,
        alias: false,
        ..strandgraph_cpu::CpuBackend::default()
    }
    .execute(&p.plan, &p.instance, &p.upload)
    .unwrap_or_else(|e| panic!("cpu backend failed: {e}"))
}

/// One frame on wgpu; no adapter is a failure.
pub fn wgpu(p: &Prepared) -> strandgraph_wgpu::Frame {
    wgpu_with(p, strandgraph_wgpu::WgpuBackend::default())
}

/// [`wgpu`] with `backend`'s settings.
pub fn wgpu_with(p: &Prepared, backend: strandgraph_wgpu::WgpuBackend) -> strandgraph_wgpu::Frame {
    backend
        .execute(&p.plan, &p.instance, &p.upload)
        .unwrap_or_else(|e| {
            panic!(
                "wgpu backend failed: {e}\n(no adapter? apt-get install mesa-vulkan-drivers \
                 libvulkan1, or run scripts/test.sh)"
            )
        })
}

/// A resource's words after the frame (it must have memory on ash).
pub fn read_ash(s: &Session, name: &str) -> Vec<u32> {
    s.read(name)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .unwrap_or_else(|| panic!("{name}: no memory on ash"))
}

/// `output.final` of a frame (`test`'s words) within a mean FLIP of
/// `max_mean` of the reference's; on failure both images and the FLIP map go
/// to `out_dir(test_name)`.
pub fn check_flip(
    p: &Prepared,
    test_name: &str,
    label: &str,
    reference: &[u32],
    test: &[u32],
    max_mean: f32,
) {
    check_flip_of(
        p,
        "output.final",
        test_name,
        label,
        reference,
        test,
        max_mean,
    );
}

/// [`check_flip`] of image resource `name`.
pub fn check_flip_of(
    p: &Prepared,
    name: &str,
    test_name: &str,
    label: &str,
    reference: &[u32],
    test: &[u32],
    max_mean: f32,
) {
    let label = &format!("{}.{label}", p.plan.graph.name);
    let (w, h) = (p.upload.quantities.width, p.upload.quantities.height);
    let r = p.plan.graph.resource_id(name).unwrap();
    let a = to_picture(&p.plan, r, reference, w, h, Display::CLIP).unwrap();
    let b = to_picture(&p.plan, r, test, w, h, Display::CLIP).unwrap();
    let d = flip(&a, &b).unwrap();
    eprintln!(
        "{name} {label}: mean FLIP {:.5}, max {:.4} at {:?}",
        d.mean, d.max, d.max_at
    );
    if d.mean > max_mean {
        let dir = out_dir(test_name);
        a.save(dir.join("output.cpu.png")).unwrap();
        b.save(dir.join(format!("output.{label}.png"))).unwrap();
        d.error_map
            .save(dir.join(format!("output.{label}.flip.png")))
            .unwrap();
        panic!(
            "{label}: mean FLIP {} > {max_mean}; images in {}",
            d.mean,
            dir.display()
        );
    }
}

/// A small scene the differential tests share: a 6,000-strand groom and a
/// 2,000-strand beard on a head, the showcase's three-quarter view, two
/// lights, `width`×`height`, running `graph` (relative to the repository);
/// written to `out_dir(test)`.
pub fn two_grooms(test: &str, graph: &str, width: u32, height: u32) -> PathBuf {
    let text = format!(
        r#"Scene(
    resolution: ({width}, {height}),
    camera: LookAt(position: (0.42, 1.62, 0.78), target: (0.0, 1.52, 0.0), fov_deg: 35.0),
    lights: [
        Directional(direction: (0.45, -0.6, -0.65), color: (1.0, 0.95, 0.88), intensity: 3.0),
        Point(position: (-0.9, 1.7, 0.6), color: (0.7, 0.8, 1.0), intensity: 6.0),
    ],
    meshes: [(name: "head", source: Head(resolution: 48), transform: (translation: (0.0, 1.6, 0.0)))],
    grooms: [(
        name: "hair",
        source: Procedural(style: Long, strands: 6000, points: 16, seed: 7),
        parent: "head",
        material: (melanin: 0.9, roughness: 0.3),
    ), (
        name: "beard",
        source: Procedural(style: Beard, strands: 2000, points: 8, seed: 13),
        parent: "head",
        material: (melanin: 3.0, roughness: 0.35),
        facial_hair: true,
    )],
    graph: {:?},
)
"#,
        root().join(graph)
    );
    let path = out_dir(test).join("small.ron");
    std::fs::write(&path, text).unwrap();
    path
}
