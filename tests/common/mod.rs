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
    let backend = AshBackend {
        validation: Validation::Sync,
        alias,
        ..AshBackend::default()
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
    let label = &format!("{}.{label}", p.plan.graph.name);
    let name = "output.final";
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
