//! Files dropped on the viewer: a scene (`.ron` with `Scene(`) replaces the
//! scene, a render graph (any other `.ron`) replaces graph A, and a groom
//! (`.hair`, `.tfx`) is shown alone under a studio light rig, framed by the
//! camera. Groom files carry no units: one whose bounds span more than
//! [`CENTIMETRE_GUESS`] metres is read as centimetres (cyHair and TressFX
//! files are), and the panel says so.

use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::{Path, PathBuf};
use strandgraph_assets::Scene;
use strandgraph_assets::loaders::LoadOptions;
use strandgraph_assets::scene::Camera;

/// A groom read in metres that spans more than this many metres is taken
/// to be in centimetres: no head of hair is 4 m across.
const CENTIMETRE_GUESS: f32 = 4.0;

pub enum Dropped {
    Scene,
    Graph,
    Groom,
}

pub fn classify(path: &Path) -> Result<Dropped> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "hair" | "tfx" => Ok(Dropped::Groom),
        "ron" => {
            let text = std::fs::read_to_string(path)
                .into_diagnostic()
                .wrap_err_with(|| format!("reading {}", path.display()))?;
            // Comments aside, a scene file opens with `Scene(`.
            let body = text
                .lines()
                .map(str::trim)
                .find(|l| !l.is_empty() && !l.starts_with("//"));
            Ok(if body.is_some_and(|l| l.starts_with("Scene(")) {
                Dropped::Scene
            } else {
                Dropped::Graph
            })
        }
        _ => Err(miette::miette!(
            "{}: the viewer loads scenes and graphs (.ron) and grooms (.hair, .tfx)",
            path.display()
        )),
    }
}

/// Loads a dropped scene, or a scene around a dropped groom that `graph`
/// (graph A's file) renders; the note says what was guessed.
pub fn load(
    path: &Path,
    graph: Option<&Path>,
    scratch: &Scratch,
) -> Result<(Scene, Option<String>)> {
    if matches!(classify(path)?, Dropped::Scene) {
        let scene = Scene::load(path).map_err(|e| miette::miette!("{e}"))?;
        return Ok((scene, None));
    }
    let groom = strandgraph_assets::load_groom(path, &LoadOptions::default())
        .map_err(|e| miette::miette!("{e}"))?;
    let span = groom.bounds().size().length();
    let (units, note) = if span > CENTIMETRE_GUESS {
        (
            "Centimetres",
            Some(format!(
                "{}: read as centimetres (it spans {span:.0} units)",
                path.display()
            )),
        )
    } else {
        ("Metres", None)
    };
    let graph = graph.ok_or_else(|| miette::miette!("no graph to render the groom with"))?;
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let text = format!(
        r#"Scene(
    resolution: (1280, 720),
    camera: LookAt(position: (0.0, 0.0, 1.0), target: (0.0, 0.0, 0.0), fov_deg: 30.0),
    lights: [
        Directional(direction: (0.3, -0.6, -0.75), color: (1.0, 0.97, 0.92), intensity: 3.0),
        Point(position: (-1.5, 1.5, 1.0), color: (0.8, 0.85, 1.0), intensity: 8.0),
    ],
    environment: (color: (0.5, 0.5, 0.55), intensity: 0.3),
    grooms: [(name: "dropped", source: File(path: {:?}, units: {units}), material: (melanin: 0.8, roughness: 0.3))],
    graph: {:?},
)
"#,
        abs(path).display().to_string(),
        abs(graph).display().to_string(),
    );
    let file = scratch.write("dropped.ron", &text)?;
    let mut scene = Scene::load(&file).map_err(|e| miette::miette!("{e}"))?;
    frame_bounds(&mut scene);
    Ok((scene, note))
}

/// Points the camera at the scene's hair from the front, far enough back
/// that the bounding sphere fills 90% of the height.
fn frame_bounds(scene: &mut Scene) {
    let Some(bounds) = scene
        .grooms
        .iter()
        .map(|g| g.world_bounds())
        .reduce(|a, b| a.union(b))
    else {
        return;
    };
    let fov: f32 = 30.0;
    let radius = bounds.size().length() * 0.5;
    let distance = radius / (fov.to_radians() * 0.5).sin() / 0.9;
    let c = bounds.center();
    scene.desc.camera = Camera::LookAt {
        position: [c.x, c.y + 0.15 * radius, c.z + distance],
        target: c.to_array(),
        fov_deg: fov,
    };
}

/// A directory of this process's own for the scenes the viewer writes,
/// removed when the viewer closes.
pub struct Scratch(PathBuf);

impl Scratch {
    pub fn new() -> Scratch {
        // One a viewer; the count keeps tests running side by side apart.
        static COUNT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let name = format!("strandgraph-view-{}-{n}", std::process::id());
        Scratch(std::env::temp_dir().join(name))
    }

    fn write(&self, name: &str, text: &str) -> Result<PathBuf> {
        std::fs::create_dir_all(&self.0).into_diagnostic()?;
        let path = self.0.join(name);
        std::fs::write(&path, text)
            .into_diagnostic()
            .wrap_err_with(|| format!("writing {}", path.display()))?;
        Ok(path)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_and_graphs_are_told_apart_by_their_first_line() {
        let dir = Scratch::new();
        let scene = dir.write("s.ron", "// a scene\n\nScene(\n)").unwrap();
        let graph = dir
            .write("g.ron", "// a graph\n(name: \"g\", passes: [])")
            .unwrap();
        assert!(matches!(classify(&scene).unwrap(), Dropped::Scene));
        assert!(matches!(classify(&graph).unwrap(), Dropped::Graph));
        assert!(matches!(
            classify(Path::new("x.TFX")).unwrap(),
            Dropped::Groom
        ));
        let e = classify(Path::new("head.obj")).err().unwrap().to_string();
        assert!(e.contains("head.obj") && e.contains(".tfx"), "{e}");
    }

    /// A groom in centimetres (30 units across) dropped on the viewer:
    /// read as centimetres, with a note, and framed by the camera.
    #[test]
    fn a_dropped_groom_in_centimetres_is_scaled_and_framed() {
        use strandgraph_assets::Groom;
        let dir = Scratch::new();
        let strands: Vec<Vec<glam::Vec3>> = (0..50)
            .map(|i| {
                let x = -15.0 + 0.6 * i as f32;
                (0..8)
                    .map(|k| glam::Vec3::new(x, 170.0 - 4.0 * k as f32, 10.0))
                    .collect()
            })
            .collect();
        let groom = Groom::from_strands(strands, 0.008);
        let bytes = strandgraph_assets::loaders::cyhair::write(&groom).unwrap();
        let file = dir.write("cm.hair", "").unwrap();
        std::fs::write(&file, bytes).unwrap();
        let graph = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scenes/graphs/kulikov.ron"
        ));

        let (scene, note) = load(&file, Some(graph), &dir).unwrap();
        assert!(note.unwrap().contains("centimetres"));
        let bounds = scene.grooms[0].world_bounds();
        assert!((bounds.size().x - 0.294).abs() < 1e-3, "{bounds:?}");
        let Camera::LookAt {
            position, target, ..
        } = scene.desc.camera
        else {
            panic!("the camera is placed with LookAt");
        };
        let c = bounds.center();
        assert!((glam::Vec3::from(target) - c).length() < 1e-4);
        // In front of the hair (+Z), far enough to see all of it.
        assert!(position[2] > c.z + bounds.size().length());
        assert_eq!(scene.graph, std::fs::canonicalize(graph).unwrap());
    }
}
