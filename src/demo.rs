//! The built-in demo scene (`render --demo`, `view --demo`):
//! `scenes/showcase.ron` and every shipped graph beside it (the viewer
//! switches between them), built into the binary, so an installed
//! `strandgraph` renders with no checkout. Scenes name their files relative
//! to the scene file, so they are written to a private temporary directory
//! for the loader, which is removed when the [`Demo`] is dropped.

use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::{Path, PathBuf};

/// The showcase scene as shipped.
pub const SCENE: &str = include_str!("../scenes/showcase.ron");
/// Where the scene looks for its graph, relative to the scene file.
#[cfg(test)]
const GRAPH_PATH: &str = "graphs/kulikov.ron";

/// Every shipped graph, written beside the scene.
pub use strandgraph_passes::shipped::GRAPHS;

/// The demo scene written out; the directory goes with it.
pub struct Demo {
    dir: PathBuf,
    /// The scene file, for [`crate::frame::prepare_with`].
    pub scene: PathBuf,
}

impl Demo {
    /// Writes the scene and its graph under the system's temporary
    /// directory, in a directory of this process's own.
    pub fn write() -> Result<Demo> {
        let dir = std::env::temp_dir().join(format!("strandgraph-demo-{}", std::process::id()));
        let write = |path: &Path, text: &str| -> Result<()> {
            if let Some(parent) = path.parent() {
                std::fs::create_dir_all(parent).into_diagnostic()?;
            }
            std::fs::write(path, text)
                .into_diagnostic()
                .wrap_err_with(|| format!("writing the demo scene to {}", path.display()))
        };
        let demo = Demo {
            scene: dir.join("showcase.ron"),
            dir,
        };
        write(&demo.scene, SCENE)?;
        for (name, text) in GRAPHS {
            write(&demo.dir.join("graphs").join(name), text)?;
        }
        Ok(demo)
    }
}

impl Drop for Demo {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scene_names_the_graph_built_in_beside_it() {
        assert!(SCENE.contains(&format!("graph: \"{GRAPH_PATH}\"")));
        let demo = Demo::write().unwrap();
        let desc = strandgraph_assets::Scene::parse(&demo.scene, SCENE).unwrap();
        assert!(demo.scene.parent().unwrap().join(&desc.graph).is_file());
        for (name, _) in GRAPHS {
            assert!(
                demo.scene
                    .parent()
                    .unwrap()
                    .join("graphs")
                    .join(name)
                    .is_file()
            );
        }
        let dir = demo.dir.clone();
        drop(demo);
        assert!(!dir.exists(), "the directory goes with the demo");
    }
}
