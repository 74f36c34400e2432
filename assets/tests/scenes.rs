//! The shipped scenes parse, name existing graphs, and load with the expected content.

use std::path::{Path, PathBuf};

use strandgraph_assets::Scene;
use strandgraph_assets::scene::{GroomSource, MeshSource};

fn scenes_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes"))
}

fn shipped() -> Vec<PathBuf> {
    let d = scenes_dir();
    let mut v: Vec<PathBuf> = [
        "showcase",
        "crowd",
        "sintel",
        "tressfx_ponytail",
        "bear",
        "fur",
    ]
    .iter()
    .map(|n| d.join(format!("{n}.ron")))
    .chain(
        ["close", "mid", "far"]
            .iter()
            .map(|n| d.join(format!("distances/{n}.ron"))),
    )
    .collect();
    v.sort();
    v
}

fn parse(p: &Path) -> strandgraph_assets::scene::SceneDesc {
    let text = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    Scene::parse(p, &text).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_shipped_scene_parses_and_names_its_files() {
    for p in shipped() {
        let s = parse(&p);
        let dir = p.parent().unwrap();
        assert!(
            s.graph.ends_with("kulikov.ron") || s.graph.ends_with("lipp.ron"),
            "{}",
            p.display()
        );
        for g in &s.grooms {
            if let GroomSource::File { path, .. } = &g.source {
                assert!(
                    path.contains("shared/grooms"),
                    "{path}: never copy grooms in"
                );
                assert!(dir.join(path).is_file(), "{}: {path} missing", p.display());
            }
        }
        for m in &s.meshes {
            if let MeshSource::File { path, .. } = &m.source {
                assert!(dir.join(path).is_file(), "{}: {path} missing", p.display());
            }
        }
    }
}

#[test]
fn showcase_has_hair_brows_beard_and_three_lights() {
    let s = Scene::load(&scenes_dir().join("showcase.ron")).unwrap();
    assert_eq!(s.desc.lights.len(), 3);
    let names: Vec<&str> = s.grooms.iter().map(|g| g.name.as_str()).collect();
    assert_eq!(names, ["hair", "eyebrows", "eyelashes", "beard"]);
    assert!(!s.grooms[0].facial_hair && s.grooms[1..].iter().all(|g| g.facial_hair));
    let c = s.counts();
    assert_eq!(c.strands, 60_000 + 1_500 + 360 + 24_000);
}

#[test]
fn crowd_has_twelve_characters_at_varied_distances() {
    let s = parse(&scenes_dir().join("crowd.ron"));
    assert_eq!(s.meshes.len(), 12);
    let mut z: Vec<f32> = s
        .meshes
        .iter()
        .map(|m| -m.transform.translation[2])
        .collect();
    z.sort_by(f32::total_cmp);
    assert!(z[0] < 1.0 && z[11] > 20.0, "{z:?}");
    // All twelve in frame at 16:9: each head's crown, chin and sides project
    // inside the view.
    let (eye, target, fov) = s.camera.eye_target_fov();
    let view = glam::Mat4::look_at_rh(eye.into(), target.into(), glam::Vec3::Y);
    let proj = glam::Mat4::perspective_rh(fov.to_radians(), 16.0 / 9.0, 0.05, 100.0);
    for m in &s.meshes {
        let c = glam::Vec3::from(m.transform.translation);
        for d in [
            [0.0, 0.12, 0.0],
            [0.0, -0.11, 0.0],
            [0.09, 0.0, 0.0],
            [-0.09, 0.0, 0.0],
        ] {
            let p = proj * view * (c + glam::Vec3::from(d)).extend(1.0);
            let ndc = p.truncate() / p.w;
            assert!(
                p.w > 0.0 && ndc.x.abs() < 0.98 && ndc.y.abs() < 0.98,
                "{}: {ndc}",
                m.name
            );
        }
    }
}

#[test]
fn distance_scenes_share_one_dense_groom() {
    let descs: Vec<_> = ["close", "mid", "far"]
        .iter()
        .map(|n| parse(&scenes_dir().join(format!("distances/{n}.ron"))))
        .collect();
    assert_eq!(descs[0].grooms, descs[1].grooms);
    assert_eq!(descs[1].grooms, descs[2].grooms);
    let s = Scene::load(&scenes_dir().join("distances/far.ron")).unwrap();
    let c = s.counts();
    assert_eq!(c.strands, 130_000);
    assert_eq!(c.vertices, 130_000 * 32);
    assert_eq!(c.bundles, 1_024);
}

#[test]
fn real_file_scenes_load() {
    let s = Scene::load(&scenes_dir().join("sintel.ron")).unwrap();
    assert_eq!(s.counts().strands, 11_400);
    assert_eq!(s.grooms[0].skinning.as_ref().map(Vec::len), Some(11_400));
    let s = Scene::load(&scenes_dir().join("tressfx_ponytail.ron")).unwrap();
    assert_eq!(s.counts().strands, 3_066 + 969 + 517 + 474);
    let s = Scene::load(&scenes_dir().join("bear.ron")).unwrap();
    assert_eq!(s.counts().vertices, 48_113 * 4);
}
