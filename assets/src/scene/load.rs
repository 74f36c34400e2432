//! Loading a scene: parse the RON, then build or load every mesh and groom.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::check;
use super::{GroomDesc, GroomSource, LodSettings, Material, MeshSource, SceneDesc};
use crate::error::AssetError;
use crate::groom::Groom;
use crate::hairmesh::{HairMesh, HairMeshParams};
use crate::hairpatch::PatchParams;
use crate::loaders::envmap::{self, EnvMap};
use crate::loaders::{self, LoadOptions};
use crate::mesh::TriMesh;
use crate::procedural::surface::{Shape, Surface};
use crate::skinning::{self, RootSkinningInfo};

/// A loaded mesh, in its local space with its world transform.
pub struct SceneMesh {
    pub name: String,
    pub mesh: TriMesh,
    pub shape: Option<Shape>,
}

/// A loaded groom with everything the pipelines need.
pub struct SceneGroom {
    pub name: String,
    /// Strands in the groom's local space; `groom.transform` is the world transform
    /// (parent's transform composed with the groom's).
    pub groom: Groom,
    pub world: glam::Mat4,
    /// `world` in the rest pose ([`Scene::pose_at`] moves `world`).
    pub rest_world: glam::Mat4,
    pub parent: Option<usize>,
    /// Kulikov: one hairRootSkinningInfo_t per strand root, against the parent mesh.
    pub skinning: Option<Vec<RootSkinningInfo>>,
    pub hair_mesh: Option<HairMesh>,
    /// How this groom's hair patches are generated (Scheuermann 2004), resolved to the
    /// defaults when the scene gives none. The patches themselves are built lazily, only
    /// when a graph draws them.
    pub patches: PatchParams,
    pub material: Material,
    pub lod: LodSettings,
    pub facial_hair: bool,
    pub fedora: Option<super::Fedora>,
    /// Simulated by the PBD passes (`GroomDesc::simulate`).
    pub simulate: bool,
}

impl SceneGroom {
    pub fn memory_bytes(&self) -> usize {
        self.groom.memory_bytes()
            + self.skinning.as_ref().map_or(0, |s| s.len() * 16)
            + self.hair_mesh.as_ref().map_or(0, HairMesh::memory_bytes)
    }
    pub fn world_bounds(&self) -> crate::Aabb {
        self.groom.bounds().transformed(&self.world)
    }
}

/// A scene, fully loaded.
pub struct Scene {
    pub path: PathBuf,
    pub desc: SceneDesc,
    pub meshes: Vec<SceneMesh>,
    pub grooms: Vec<SceneGroom>,
    /// The render graph file, resolved against the scene's folder.
    pub graph: PathBuf,
    /// The environment's map (`environment.map`), as loaded: radiance not yet
    /// scaled by the environment's `color × intensity`.
    pub environment_map: Option<EnvMap>,
}

/// Totals the render-graph CLI maps into graph quantities.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SceneCounts {
    pub strands: u64,
    pub vertices: u64,
    pub segments: u64,
    pub bundles: u64,
    /// Strands the hair meshes generate (Σ N over bundles).
    pub mesh_strands: u64,
    /// Hair models (grooms).
    pub models: u64,
    pub meshes: u64,
    pub triangles: u64,
    pub lights: u64,
    pub width: u32,
    pub height: u32,
}

impl Scene {
    /// Parses a scene file without loading what it names.
    pub fn parse(path: &Path, text: &str) -> Result<SceneDesc, AssetError> {
        let opts = ron::Options::default().with_default_extension(
            ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES
                | ron::extensions::Extensions::IMPLICIT_SOME,
        );
        opts.from_str(text).map_err(|e| AssetError::Scene {
            path: path.to_path_buf(),
            line: e.span.start.line,
            col: e.span.start.col,
            message: e.code.to_string(),
        })
    }

    /// Parses a scene file and checks everything that needs neither the
    /// files it names nor a generator (ranges, finite numbers, mesh names,
    /// the counts that size what loading allocates; `check.rs`). Every
    /// error has the line and column of its culprit. [`Scene::load`] runs
    /// this before it loads anything.
    pub fn check(path: &Path, text: &str) -> Result<SceneDesc, AssetError> {
        let desc = Self::parse(path, text)?;
        check::check(&desc).map_err(|p| {
            let (line, col) = check::locate(text, &p.needle, p.nth);
            AssetError::Scene {
                path: path.to_path_buf(),
                line,
                col,
                message: p.message,
            }
        })?;
        Ok(desc)
    }

    /// Parses and checks the scene ([`Scene::check`]), then builds or loads
    /// all of its meshes and grooms.
    pub fn load(path: &Path) -> Result<Scene, AssetError> {
        let text = std::fs::read_to_string(path).map_err(|source| AssetError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let desc = Self::check(path, &text)?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let err = |needle: &str, message: String| {
            let (line, col) = check::locate(&text, needle, 0);
            AssetError::Scene {
                path: path.to_path_buf(),
                line,
                col,
                message,
            }
        };

        // Meshes (in parallel).
        let meshes: Vec<SceneMesh> = desc
            .meshes
            .par_iter()
            .map(|m| {
                let (mut mesh, shape) = match &m.source {
                    MeshSource::Head(p) => (p.build(), Some(Shape::Head(*p))),
                    MeshSource::Body(p) => (p.build(), Some(Shape::Body(*p))),
                    MeshSource::File { path: p, units } => {
                        let mesh = loaders::load_mesh(&dir.join(p), *units)
                            .map_err(|e| err(p, format!("mesh {:?}: {e}", m.name)))?;
                        (mesh, None)
                    }
                };
                mesh.transform = m.transform;
                Ok(SceneMesh {
                    name: m.name.clone(),
                    mesh,
                    shape,
                })
            })
            .collect::<Result<_, _>>()?;

        let environment_map = match desc.environment.as_ref().and_then(|e| e.map.as_ref()) {
            Some(p) => Some(
                envmap::load(&dir.join(p)).map_err(|e| err(p, format!("environment map: {e}")))?,
            ),
            None => None,
        };

        // Grooms, one after another (each is parallel inside).
        let mut grooms = Vec::with_capacity(desc.grooms.len());
        for g in &desc.grooms {
            let span = tracing::info_span!("groom", name = %g.name);
            let _e = span.enter();
            grooms.push(load_groom(g, &meshes, dir, &err)?);
        }
        Ok(Scene {
            path: path.to_path_buf(),
            graph: dir.join(&desc.graph),
            desc,
            meshes,
            grooms,
            environment_map,
        })
    }

    pub fn counts(&self) -> SceneCounts {
        let mut c = SceneCounts {
            models: self.grooms.len() as u64,
            meshes: self.meshes.len() as u64,
            lights: self.desc.lights.len() as u64,
            width: self.desc.resolution.0,
            height: self.desc.resolution.1,
            ..Default::default()
        };
        for g in &self.grooms {
            c.strands += g.groom.strand_count() as u64;
            c.vertices += g.groom.point_count() as u64;
            c.segments += g.groom.segment_count() as u64;
            c.bundles += g.hair_mesh.as_ref().map_or(0, |h| h.bundle_count() as u64);
            c.mesh_strands += g.hair_mesh.as_ref().map_or(0, |h| {
                h.bundles.iter().map(|b| u64::from(b.strands)).sum::<u64>()
            });
        }
        c.triangles = self
            .meshes
            .iter()
            .map(|m| m.mesh.triangle_count() as u64)
            .sum();
        c
    }
}

fn load_groom(
    g: &GroomDesc,
    meshes: &[SceneMesh],
    dir: &Path,
    err: &dyn Fn(&str, String) -> AssetError,
) -> Result<SceneGroom, AssetError> {
    let name = format!("\"{}\"", g.name);
    let parent = match &g.parent {
        Some(p) => Some(meshes.iter().position(|m| &m.name == p).ok_or_else(|| {
            err(
                &format!("parent: \"{p}\""),
                format!("groom {:?}: no mesh named {p:?}", g.name),
            )
        })?),
        None => None,
    };
    let surface = || -> Result<Surface, AssetError> {
        let p = parent.ok_or_else(|| {
            err(
                &name,
                format!("groom {:?}: a procedural groom needs a parent mesh", g.name),
            )
        })?;
        let m = &meshes[p];
        Ok(match m.shape {
            Some(s) => Surface::procedural(s),
            None => Surface::from_mesh(m.mesh.clone()),
        })
    };
    // Scene::check has checked the names, ranges and sizes.
    let patches = g.patches.unwrap_or_default();
    let mut skinning = None;
    let mut hair_mesh = None;
    let mut groom = match &g.source {
        GroomSource::Procedural(params) => {
            let generated = params.generate(&surface()?);
            skinning = Some(generated.skinning);
            generated.groom
        }
        GroomSource::HairMesh(params) => {
            let hm = g.hair_mesh.ok_or_else(|| {
                err(&name, format!("groom {:?}: a HairMesh source needs `hair_mesh: (bundles: .., layers: ..)`", g.name))
            })?;
            let mesh = HairMesh::procedural(&surface()?, params, &hm, params.strands);
            let thickness = params.root_thickness.unwrap_or(70e-6);
            let groom = mesh.to_groom(params.points as usize, thickness);
            hair_mesh = Some(mesh);
            groom
        }
        GroomSource::File {
            path,
            units,
            thickness,
        } => loaders::load_groom(
            &dir.join(path),
            &LoadOptions {
                units: *units,
                thickness: *thickness,
            },
        )
        .map_err(|e| err(path, format!("groom {:?}: {e}", g.name)))?,
    };
    if groom.strand_count() == 0 {
        return Err(err(
            &name,
            format!(
                "groom {:?} has no strands (is the parent region empty?)",
                g.name
            ),
        ));
    }
    if let (Some(p), None) = (parent, &skinning) {
        skinning = Some(skinning::bake(&meshes[p].mesh, &groom.roots()));
    }
    if hair_mesh.is_none() {
        // Lipp's pipelines draw hair meshes: fit one to every groom that
        // declares none, so every pipeline can render every scene.
        let params = g
            .hair_mesh
            .unwrap_or_else(|| HairMeshParams::fitted_default(groom.strand_count()));
        hair_mesh = Some(HairMesh::fit(&groom, &params));
    }
    // Kulikov: a stable randomized strand order, so LOD draws a prefix.
    if g.lod.enabled {
        let order = groom.shuffled_order(g.lod.shuffle_seed);
        groom = groom.reordered(&order);
        if let Some(s) = skinning.as_mut() {
            *s = order.iter().map(|&i| s[i as usize]).collect();
        }
    }
    let world = match parent {
        Some(p) => meshes[p].mesh.transform.compose(&g.transform),
        None => g.transform.matrix(),
    };
    groom.transform = g.transform;
    if let Some(h) = hair_mesh.as_mut() {
        h.transform = g.transform;
    }
    Ok(SceneGroom {
        name: g.name.clone(),
        groom,
        world,
        rest_world: world,
        parent,
        skinning,
        hair_mesh,
        patches,
        material: g.material,
        lod: g.lod,
        facial_hair: g.facial_hair,
        fedora: g.fedora,
        simulate: g.simulate,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn load_err(p: &Path) -> AssetError {
        match Scene::load(p) {
            Err(e) => e,
            Ok(_) => panic!("{} loaded", p.display()),
        }
    }

    fn tmp(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("strandgraph-scene-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    const MINI: &str = r#"Scene(
    resolution: (640, 360),
    camera: Orbit(target: (0.0, 0.0, 0.0), distance: 0.8, yaw_deg: 30.0, pitch_deg: 10.0, fov_deg: 35.0),
    lights: [
        Directional(direction: (0.0, -1.0, -1.0), color: (1.0, 1.0, 1.0), intensity: 3.0),
        Point(position: (0.5, 0.5, 0.5), color: (1.0, 0.9, 0.8), intensity: 10.0),
    ],
    environment: (color: (0.5, 0.6, 0.7), intensity: 0.3),
    meshes: [
        (name: "head", source: Head(resolution: 48)),
    ],
    grooms: [
        (name: "hair", source: Procedural(style: Wavy, strands: 500, points: 8), parent: "head",
         material: (melanin: 1.0, roughness: 0.25)),
        (name: "beard", source: Procedural(style: Beard, strands: 200, points: 4), parent: "head",
         facial_hair: true, hair_mesh: (bundles: 20, layers: 4)),
    ],
    graph: "graphs/kulikov.ron",
)"#;

    #[test]
    fn loads_a_scene_and_counts() {
        let d = tmp("mini");
        let p = write(&d, "mini.ron", MINI);
        let s = Scene::load(&p).unwrap();
        let c = s.counts();
        assert_eq!(c.strands, 700);
        assert_eq!(c.vertices, 500 * 8 + 200 * 4);
        assert_eq!(c.segments, 500 * 7 + 200 * 3);
        assert_eq!((c.models, c.lights, c.width, c.height), (2, 2, 640, 360));
        // The beard's declared hair mesh (at most 20 bundles) and the one
        // fitted to the hair, which declares none (16 for 500 strands).
        let bundles = |g: usize| {
            s.grooms[g]
                .hair_mesh
                .as_ref()
                .map_or(0, |m| m.bundle_count())
        };
        assert!((1..=16).contains(&bundles(0)) && (1..=20).contains(&bundles(1)));
        assert_eq!(c.bundles as usize, bundles(0) + bundles(1));
        assert_eq!(s.graph, d.join("graphs/kulikov.ron"));
        assert!(s.grooms[1].facial_hair);
        assert_eq!(s.grooms[0].skinning.as_ref().map(Vec::len), Some(500));
        // The shuffled skinning still matches the shuffled roots.
        let g = &s.grooms[0];
        let head = &s.meshes[0].mesh;
        for (r, sk) in g.groom.roots().iter().zip(g.skinning.as_ref().unwrap()) {
            assert!(sk.root_position(head).unwrap().distance(*r) < 1e-4);
        }
    }

    #[test]
    fn parse_errors_have_line_and_column() {
        let d = tmp("bad");
        let p = write(
            &d,
            "bad.ron",
            &MINI.replace("intensity: 3.0", "intensity: \"x\""),
        );
        let e = load_err(&p);
        let AssetError::Scene { line, .. } = e else {
            panic!("{e}")
        };
        assert_eq!(line, 5);
        assert!(
            e.to_string().starts_with(&format!("{}:5:", p.display())),
            "{e}"
        );
    }

    #[test]
    fn semantic_errors_point_at_the_culprit() {
        let d = tmp("sem");
        let p = write(
            &d,
            "sem.ron",
            &MINI.replace(
                "parent: \"head\",\n         facial",
                "parent: \"nose\",\n         facial",
            ),
        );
        let e = load_err(&p).to_string();
        assert!(
            e.contains(":15:") && e.contains("no mesh named \"nose\""),
            "{e}"
        );
        let p = write(
            &d,
            "missing.ron",
            &MINI.replace("Head(resolution: 48)", "File(path: \"nope.obj\")"),
        );
        let e = load_err(&p).to_string();
        assert!(e.contains("nope.obj") && e.contains(":10:"), "{e}");
    }

    #[test]
    fn patch_params_resolve_and_are_validated() {
        let d = tmp("patches");
        let s = Scene::load(&write(
            &d,
            "ok.ron",
            &MINI.replace("layers: 4)),", "layers: 4), patches: (layers: 2)),"),
        ))
        .unwrap();
        assert_eq!(s.grooms[0].patches, PatchParams::default());
        let want = PatchParams {
            layers: 2,
            ..Default::default()
        };
        assert_eq!(s.grooms[1].patches, want);
        let p = write(
            &d,
            "bad.ron",
            &MINI.replace("layers: 4)),", "layers: 4), patches: (layers: 9)),"),
        );
        let e = load_err(&p).to_string();
        assert!(
            e.contains("bad.ron:15:") && e.contains("\"beard\"") && e.contains("layers"),
            "{e}"
        );
    }

    #[test]
    fn environment_maps_load_relative_to_the_scene_and_errors_name_them() {
        let d = tmp("envmap");
        let with =
            |map: &str| MINI.replace("intensity: 0.3)", &format!("intensity: 0.3, map: {map:?})"));
        let p = write(&d, "missing.ron", &with("env/none.exr"));
        let e = load_err(&p).to_string();
        assert!(
            e.contains(":8:") && e.contains("environment map") && e.contains("env/none.exr"),
            "{e}"
        );
        std::fs::create_dir_all(d.join("env")).unwrap();
        std::fs::write(d.join("env/bad.hdr"), b"#?RADIANCE\n\n-Y 10 +X 10\n").unwrap();
        let p = write(&d, "bad.ron", &with("env/bad.hdr"));
        let e = load_err(&p).to_string();
        assert!(e.contains("bad.hdr") && e.contains("twice as wide"), "{e}");
        let studio = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/env/studio.exr");
        let p = write(&d, "good.ron", &with(&studio.display().to_string()));
        let s = Scene::load(&p).unwrap();
        let m = s.environment_map.expect("the map is loaded");
        assert_eq!((m.width, m.height), (128, 64));
        assert!(
            Scene::load(&write(&d, "none.ron", MINI))
                .unwrap()
                .environment_map
                .is_none()
        );
    }

    /// `Scene::check` on MINI with `from` replaced by `to`: the error's line
    /// and message.
    fn check_err(from: &str, to: &str) -> (usize, String) {
        assert!(MINI.contains(from), "{from}");
        let text = MINI.replacen(from, to, 1);
        match Scene::check(Path::new("s.ron"), &text) {
            Err(AssetError::Scene { line, message, .. }) => (line, message),
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("{to} passed the check"),
        }
    }

    #[test]
    fn check_needs_no_files_and_passes_every_shipped_scene() {
        let desc = Scene::check(Path::new("s.ron"), MINI).unwrap();
        assert_eq!(desc.grooms.len(), 2);
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let mut checked = 0;
        for dir in [scenes.clone(), scenes.join("distances")] {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let p = entry.unwrap().path();
                if p.extension().is_some_and(|e| e == "ron") {
                    let text = std::fs::read_to_string(&p).unwrap();
                    Scene::check(&p, &text).unwrap_or_else(|e| panic!("{e}"));
                    checked += 1;
                }
            }
        }
        assert!(checked >= 9, "{checked}");
    }

    /// What `Scene::load` would have allocated or computed from before it
    /// refused them (a body of 4e9 rings overflowed `resolution * 3` and
    /// asked for 1e19 vertices; 20M strands of 1,024 points, 245 GB; an
    /// unbounded hair mesh), and numbers that are not numbers: each is an
    /// error at its line.
    #[test]
    fn check_refuses_what_loading_could_not_build() {
        let cases = [
            (
                "Head(resolution: 48)",
                "Body(resolution: 4000000000)",
                10,
                "mesh \"head\": resolution = 4000000000 must be at most 1024",
            ),
            (
                "Head(resolution: 48)",
                "Body(half_extents: (0.2, 0.0, 0.5))",
                10,
                "half_extents",
            ),
            (
                "strands: 500, points: 8",
                "strands: 20000000, points: 1024",
                13,
                "groom \"hair\": strands × points = 20480000000 is more than",
            ),
            (
                "hair_mesh: (bundles: 20,",
                "hair_mesh: (bundles: 0,",
                15,
                "groom \"beard\": hair_mesh: bundles = 0 must be in 1..=65536",
            ),
            (
                "layers: 4)",
                "layers: 100000)",
                15,
                "hair_mesh: layers = 100000 must be in 2..=64",
            ),
            (
                "layers: 4)",
                "layers: 4, style: (noise: NaN))",
                15,
                "hair_mesh: style",
            ),
            (
                "points: 8)",
                "points: 8, parting: inf)",
                13,
                "parting is out of range",
            ),
            (
                "roughness: 0.25)),",
                "roughness: 0.25), lod: (min_fraction: 2.0)),",
                13,
                "lod: min_fraction = 2 must be in 0..=1",
            ),
            (
                "roughness: 0.25)),",
                "roughness: 0.25), fedora: (box_min: (0, 0, 0), box_max: (1, 1, 1), \
                 sphere_center: (0, NaN, 0), sphere_radius: 1)),",
                13,
                "fedora",
            ),
            (
                "fov_deg: 35.0",
                "fov_deg: 180.0",
                3,
                "camera: fov_deg = 180",
            ),
            ("distance: 0.8", "distance: 0.0", 3, "camera: distance = 0"),
            (
                "yaw_deg: 30.0",
                "yaw_deg: -inf",
                3,
                "camera: target, yaw_deg",
            ),
            ("intensity: 10.0", "intensity: NaN", 4, "light 1: color"),
            (
                "direction: (0.0, -1.0, -1.0)",
                "direction: (0.0, 0.0, 0.0)",
                4,
                "light 0: direction",
            ),
            ("intensity: 0.3", "intensity: -0.3", 8, "environment: color"),
            (
                "resolution: (640, 360)",
                "resolution: (640, 0)",
                2,
                "resolution 640x0 is out of range",
            ),
        ];
        for (from, to, line, message) in cases {
            let (l, m) = check_err(from, to);
            assert!(l == line && m.contains(message), "{to}: {l}: {m}");
        }
        // A file groom's units and thickness.
        let file = "Procedural(style: Wavy, strands: 500, points: 8)";
        for to in [
            "File(path: \"g.hair\", units: Scale(0.0))",
            "File(path: \"g.hair\", thickness: -1e-4)",
        ] {
            let (l, m) = check_err(file, to);
            assert!(
                l == 13 && m.starts_with("groom \"hair\": "),
                "{to}: {l}: {m}"
            );
        }
    }

    #[test]
    fn a_duplicate_mesh_name_points_at_the_second() {
        let (line, message) = check_err(
            "        (name: \"head\", source: Head(resolution: 48)),\n",
            "        (name: \"head\", source: Head(resolution: 48)),\n        \
             (name: \"head\", source: Body(resolution: 64)),\n",
        );
        assert_eq!(
            (line, message.as_str()),
            (11, "mesh name \"head\" is used twice")
        );
    }
}
