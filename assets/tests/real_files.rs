//! Every file in ../shared/grooms loads with the counts its README gives. These files
//! exist in CI too; a missing file FAILS the test.

use std::path::PathBuf;

use strandgraph_assets::{LoadOptions, Units, load_groom, load_mesh};

fn grooms_dir() -> PathBuf {
    let d = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/grooms"));
    assert!(
        d.is_dir(),
        "{} is missing: the real groom files are required",
        d.display()
    );
    d
}

fn check(rel: &str, units: Units, strands: usize, points_per_strand: usize) {
    let path = grooms_dir().join(rel);
    let t = std::time::Instant::now();
    let g = load_groom(
        &path,
        &LoadOptions {
            units,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("{rel}: loaded in {:?}", t.elapsed());
    g.validate().unwrap();
    assert_eq!(g.strand_count(), strands, "{rel} strands");
    assert_eq!(g.point_count(), strands * points_per_strand, "{rel} points");
    assert_eq!(g.uniform_points_per_strand(), Some(points_per_strand));
    // Sanity of units: a groom spans between 1 cm and 3 m once in metres.
    let size = g.bounds().size().max_element();
    assert!((0.01..3.0).contains(&size), "{rel}: {size} m across");
}

#[test]
fn sintel_hair_tfx4() {
    check("sintel/sintel_hair_16pts.tfx", Units::Metres, 11_400, 16);
}

#[test]
fn ratboy_mohawk_tfx4_has_strand_uvs() {
    check("tressfx/ratboy_mohawk.v4.tfx", Units::Metres, 2_228, 32);
    let g = load_groom(
        &grooms_dir().join("tressfx/ratboy_mohawk.v4.tfx"),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(g.strand_uvs.map(|u| u.len()), Some(2_228));
}

#[test]
fn bear_tfx3() {
    check("tressfx/bear.v3.tfx", Units::Centimetres, 48_113, 4);
}

#[test]
fn testhair1_tfx3() {
    check("tressfx/testhair1.v3.tfx", Units::Centimetres, 10_027, 4);
}

#[test]
fn ponytail_pieces_tfx3() {
    for (f, n) in [
        ("side", 3_066),
        ("front_top", 969),
        ("back", 517),
        ("tail", 474),
    ] {
        check(
            &format!("tressfx/ponytail_{f}.v3.tfx"),
            Units::Centimetres,
            n,
            16,
        );
    }
}

#[test]
fn ruby_and_free_hair_tfx2() {
    for (f, n) in [
        ("ruby_long_hair", 3_000),
        ("ruby_short_hair", 1_867),
        ("hair_free", 3_942),
    ] {
        check(&format!("tressfx/{f}.v2.tfx"), Units::Centimetres, n, 16);
    }
}

#[test]
fn sintel_meshes_obj() {
    let head = load_mesh(&grooms_dir().join("sintel/sintel_head.obj"), Units::Metres).unwrap();
    assert_eq!(head.vertex_count(), 3_046);
    // 5,952 faces: all triangles in this file.
    assert_eq!(head.triangle_count(), 5_952);
    head.validate().unwrap();
    let lashes = load_mesh(
        &grooms_dir().join("sintel/sintel_eyelashes.obj"),
        Units::Metres,
    )
    .unwrap();
    assert!(lashes.triangle_count() >= 192);
}

#[test]
fn sintel_hair_roots_sit_on_sintel_head() {
    let dir = grooms_dir();
    let head = load_mesh(&dir.join("sintel/sintel_head.obj"), Units::Metres).unwrap();
    let hair = load_groom(
        &dir.join("sintel/sintel_hair_16pts.tfx"),
        &LoadOptions::default(),
    )
    .unwrap();
    let roots = hair.roots();
    let skin = strandgraph_assets::skinning::bake(&head, &roots);
    // Roots of the real groom are within 2 cm of the matching head mesh.
    let near = roots
        .iter()
        .zip(&skin)
        .filter(|(r, s)| s.root_position(&head).unwrap().distance(**r) < 0.02)
        .count();
    assert!(
        near * 10 >= roots.len() * 9,
        "{near} of {} roots near the head",
        roots.len()
    );
}
