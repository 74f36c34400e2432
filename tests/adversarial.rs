//! Adversarial scenes: each ends in a clear error naming the file, or in a
//! documented fallback this test checks, never a panic, a hang or a wrong
//! image passed off as right. The rest of the list lives beside the code it
//! tests: a camera inside the hair (`tests/near_plane.rs`), a model past the
//! payload's 2^22 segments (`passes/src/kulikov/lod.rs`, the LOD keeps
//! 2^22 / (points - 1) strands), degenerate and inverted triangles
//! (`passes/src/opaque_mesh`, `passes/src/hardware_raster.rs`).

use std::path::{Path, PathBuf};
use strandgraph::frame::{Prepared, prepare, prepare_with};
use strandgraph_assets::groom::Groom;
use strandgraph_assets::loaders::cyhair;

mod common;
use common::{ash, check_flip_of, cpu, out_dir, read_ash, root};

const TEST: &str = "adversarial";

/// A scene file with a head, `grooms` (RON entries) and `extra` meshes,
/// at `size`, running `graph` (relative to the repository).
fn scene(name: &str, grooms: &str, meshes: &str, graph: &str, size: (u32, u32)) -> PathBuf {
    let text = format!(
        r#"Scene(
    resolution: ({}, {}),
    camera: LookAt(position: (0.42, 1.62, 0.78), target: (0.0, 1.52, 0.0), fov_deg: 35.0),
    lights: [Directional(direction: (0.45, -0.6, -0.65), color: (1.0, 0.95, 0.88), intensity: 3.0)],
    meshes: [(name: "head", source: Head(resolution: 48), transform: (translation: (0.0, 1.6, 0.0))),{meshes}],
    grooms: [{grooms}],
    graph: {:?},
)
"#,
        size.0,
        size.1,
        root().join(graph)
    );
    let path = out_dir(TEST).join(format!("{name}.ron"));
    std::fs::write(&path, text).unwrap();
    path
}

fn error_of(path: &Path) -> String {
    match prepare(path, None, None) {
        Ok(_) => panic!("{} prepared without an error", path.display()),
        // The chain, not the graphical report: that wraps lines at the
        // terminal width, which would split the names the tests look for.
        Err(e) => e
            .chain()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join(": "),
    }
}

/// Every channel of Rgba16Float image `name` is finite.
fn assert_finite(name: &str, words: &[u32]) {
    let bad = words
        .iter()
        .flat_map(|w| [w & 0xFFFF, w >> 16])
        .filter(|&h| !half::f16::from_bits(h as u16).is_finite())
        .count();
    assert_eq!(bad, 0, "{name}: {bad} channels are not finite");
}

/// The Kulikov frame on the CPU simulator and ash: finite, and the same
/// picture within a mean FLIP of 0.01.
fn renders_alike(p: &Prepared) {
    let session = ash(p, false);
    let cpu = cpu(p, session.subgroup_size);
    let name = "output.composed";
    let (c, a) = (cpu.read(&p.plan, name).unwrap(), read_ash(&session, name));
    assert_finite(name, &c);
    assert_finite(name, &a);
    check_flip_of(p, name, TEST, "ash", &c, &a, 0.01);
}

#[test]
fn a_groom_with_zero_strands_is_an_error_at_its_line() {
    let grooms = r#"(name: "hair", source: Procedural(style: Long, strands: 0, points: 16), parent: "head")"#;
    let path = scene(
        "zero_strands",
        grooms,
        "",
        "scenes/graphs/kulikov.ron",
        (64, 36),
    );
    let e = error_of(&path);
    assert!(
        e.contains("zero_strands.ron:6:") && e.contains("\"hair\"") && e.contains("strands"),
        "{e}"
    );
}

/// A groom file whose strand repeats its points (zero-length segments)
/// next to a normal one.
fn write_groom(name: &str, repeat: bool, poison: Option<f32>) -> PathBuf {
    let strands: Vec<Vec<glam::Vec3>> = (0..200)
        .map(|i| {
            let x = -0.12 + 0.0012 * i as f32;
            (0..12)
                .map(|k| {
                    let k = if repeat && k % 2 == 1 { k - 1 } else { k };
                    glam::Vec3::new(x, 1.75 - 0.02 * k as f32, 0.1)
                })
                .collect()
        })
        .collect();
    let mut groom = Groom::from_strands(strands, 80e-6);
    let marker = 0.123_456_79_f32;
    groom.positions[37].y = marker;
    let mut bytes = cyhair::write(&groom).unwrap();
    if let Some(bad) = poison {
        // Validation refuses to write a non-finite point: patch it in.
        let at = bytes
            .windows(4)
            .position(|w| w == marker.to_le_bytes())
            .unwrap();
        bytes[at..at + 4].copy_from_slice(&bad.to_le_bytes());
    }
    let path = out_dir(TEST).join(format!("{name}.hair"));
    std::fs::write(&path, bytes).unwrap();
    path
}

fn file_groom(path: &Path) -> String {
    format!(r#"(name: "strands", source: File(path: {path:?}), material: (melanin: 1.0))"#)
}

#[test]
fn non_finite_positions_are_errors_naming_the_file() {
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let groom = write_groom("poisoned", false, Some(bad));
        let path = scene(
            "poisoned",
            &file_groom(&groom),
            "",
            "scenes/graphs/kulikov.ron",
            (64, 36),
        );
        let e = error_of(&path);
        assert!(
            e.contains("poisoned.hair") && e.contains("point 37 is not finite"),
            "{bad}: {e}"
        );
    }
    for (field, bad) in [
        (
            "position: (0.42, 1.62, 0.78)",
            "position: (NaN, 1.62, 0.78)",
        ),
        (
            "position: (0.42, 1.62, 0.78)",
            "position: (0.42, inf, 0.78)",
        ),
        (
            "translation: (0.0, 1.6, 0.0)",
            "translation: (0.0, -inf, 0.0)",
        ),
    ] {
        let path = scene("non_finite", "", "", "scenes/graphs/kulikov.ron", (64, 36));
        let text = std::fs::read_to_string(&path).unwrap().replace(field, bad);
        std::fs::write(&path, text).unwrap();
        let e = error_of(&path);
        assert!(
            e.contains("non_finite.ron:") && e.contains("finite") || e.contains("bad transform"),
            "{bad}: {e}"
        );
    }
}

/// Zero-length segments are not drawn (the raster's trapezoid, Lipp's walk
/// and the reference's end-on disk test them); the frame stays finite.
#[test]
fn zero_length_segments_render_finite_frames() {
    let groom = write_groom("repeated_points", true, None);
    let path = scene(
        "zero_length",
        &file_groom(&groom),
        "",
        "scenes/graphs/kulikov.ron",
        (96, 54),
    );
    renders_alike(&prepare(&path, None, None).unwrap());
    let p = prepare(
        &path,
        Some(&root().join("scenes/graphs/kulikov_reference.ron")),
        None,
    )
    .unwrap();
    let frame = cpu(&p, 32);
    assert_finite(
        "output.reference",
        &frame.read(&p.plan, "output.reference").unwrap(),
    );
}

/// 200 grooms on one head: 200 models through every per-model pass.
fn many_models(n: usize) -> PathBuf {
    let grooms: Vec<String> = (0..n)
        .map(|i| {
            format!(
                r#"(name: "g{i}", source: Procedural(style: Long, strands: 12, points: 6, seed: {i}), parent: "head")"#
            )
        })
        .collect();
    scene(
        "many_models",
        &grooms.join(",\n"),
        "",
        "scenes/graphs/kulikov.ron",
        (96, 54),
    )
}

#[test]
fn two_hundred_models_render_on_cpu_and_ash() {
    let p = prepare(&many_models(200), None, None).unwrap();
    assert_eq!(p.upload.quantities.models, 200);
    renders_alike(&p);
}

/// Fewer atlas tiles than models: every model gets at most the coarsest
/// downscale, and those past the atlas's end are not drawn (`valid` 0 in
/// `atlas_tiles`, `tile_alloc::allocate`), the same on every backend.
#[test]
fn more_models_than_atlas_tiles_drops_the_models_past_the_atlas() {
    let overrides = ["tile_alloc.atlas_tiles=8".to_string()];
    let p = prepare_with(&many_models(40), None, None, &overrides).unwrap();
    let session = ash(&p, false);
    let cpu = cpu(&p, session.subgroup_size);
    let tiles = cpu.read(&p.plan, "atlas_tiles").unwrap();
    assert_eq!(tiles, read_ash(&session, "atlas_tiles"));
    // ModelTiles: 8 words: first_tile, grid_w, grid_h, origin x and y, downscale, valid.
    let valid = tiles.chunks(8).filter(|t| t[6] == 1).count();
    let used: u32 = tiles
        .chunks(8)
        .filter(|t| t[6] == 1)
        .map(|t| t[1] * t[2])
        .sum();
    eprintln!("{valid} of 40 models drawn on {used} of 8 tiles");
    assert!(
        valid > 0 && valid < 40 && used <= 8,
        "{valid} models drawn on {used} tiles"
    );
    let name = "output.composed";
    check_flip_of(
        &p,
        name,
        TEST,
        "ash",
        &cpu.read(&p.plan, name).unwrap(),
        &read_ash(&session, name),
        0.01,
    );
}

/// A 16384×16384 frame: each backend renders it or names what does not
/// fit (lavapipe in CI: a workgroup count, wgpu's binding limit; the CPU
/// simulator under a memory budget: the largest resource).
#[test]
fn a_16384_square_frame_renders_or_names_the_limit() {
    let grooms = r#"(name: "hair", source: Procedural(style: Long, strands: 500, points: 8), parent: "head")"#;
    let path = scene(
        "huge",
        grooms,
        "",
        "scenes/graphs/kulikov.ron",
        (16384, 16384),
    );
    let p = prepare(&path, None, None).unwrap();
    let named = |e: String| {
        eprintln!("{e}");
        assert!(
            e.contains("pass `") || e.contains("MiB") || e.contains("GiB"),
            "the error names neither a pass nor a size: {e}"
        );
    };
    match strandgraph_ash::AshBackend::default().execute(&p.plan, &p.instance, &p.upload) {
        Ok((session, _)) => assert_eq!(
            read_ash(&session, "output.composed").len(),
            16384 * 16384 * 2
        ),
        Err(e) => named(e.to_string()),
    }
    match strandgraph_wgpu::WgpuBackend::default().execute(&p.plan, &p.instance, &p.upload) {
        Ok(frame) => assert!(frame.read(&p.plan, "output.composed").unwrap().is_some()),
        Err(e) => named(e.to_string()),
    }
    let limited = strandgraph_cpu::CpuBackend {
        memory_limit: Some(1 << 30),
        ..strandgraph_cpu::CpuBackend::default()
    };
    match limited.execute(&p.plan, &p.instance, &p.upload) {
        Ok(_) => panic!("a 16384x16384 frame fitted in 1 GiB"),
        Err(e) => named(e.to_string()),
    }
}
