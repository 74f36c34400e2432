//! Every shipped scene renders with every shipped pipeline graph on the CPU
//! simulator (at a small size): an A/B that only works on the scenes built
//! for one pipeline is not an A/B. Grooms that declare no hair mesh get one
//! fitted (Lipp draws hair meshes); scenes without a head mesh keep a
//! placeholder triangle buffer and draw no opaque geometry.
//!
//! Kulikov's self-shadowing runs as the voxel march here: the offline bake
//! is the same for every graph and is tested on its own (bake/tests). The
//! references resolve one sample a pixel rather than 64: at this size every
//! pixel of a groom holds thousands of ribbons, and the 64 samples took
//! 92 s of this test's 606 s; the sampling itself is tested at full count
//! in tests/agree.rs and measured by the bench. Lipp's LOD passes run with
//! the LOD on in every graph, the reference's included: its every strand at
//! 127 points took 296 s of the remaining 506 s (the crowd alone 141 s);
//! the full-detail reference is tested in tests/agree.rs and measured by
//! the bench.

use std::path::{Path, PathBuf};
use strandgraph::frame::{complete_upload, override_param};
use strandgraph_assets::Scene;
use strandgraph_cpu::CpuBackend;
use strandgraph_graph::compile_file;
use strandgraph_passes::Registry;
use strandgraph_passes::upload::upload;

const W: u32 = 96;
const H: u32 = 54;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn shipped(dir: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    files.sort();
    files
}

#[test]
fn every_scene_renders_with_every_pipeline() {
    let scenes: Vec<PathBuf> = [shipped("scenes"), shipped("scenes/distances")].concat();
    // The pipelines; roofline.ron is the bench's, not a pipeline.
    let graphs: Vec<PathBuf> = shipped("scenes/graphs")
        .into_iter()
        .filter(|g| !g.ends_with("roofline.ron"))
        .collect();
    assert!(
        scenes.len() >= 10 && graphs.len() >= 4,
        "{scenes:?} {graphs:?}"
    );
    let mut failures = Vec::new();
    for scene_path in &scenes {
        let scene = Scene::load(scene_path).unwrap_or_else(|e| panic!("{e}"));
        for graph in &graphs {
            let label = format!(
                "{} with {}",
                scene_path.strip_prefix(root()).unwrap().display(),
                graph.file_name().unwrap().to_string_lossy()
            );
            match render(&scene, graph) {
                Ok(drawn) => eprintln!("{label}: {drawn} pixels drawn"),
                Err(e) => failures.push(format!("{label}: {e}")),
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Runs `graph` on `scene`; the number of output pixels that are not the
/// background (the top-left pixel's value, which no shipped scene covers).
fn render(scene: &Scene, graph: &Path) -> Result<usize, String> {
    let mut plan =
        compile_file(graph, &Registry, scene.grooms.len() as u32).map_err(|e| format!("{e:?}"))?;
    if plan.graph.passes.iter().any(|p| p.kind == "kulikov.shade") {
        override_param(&mut plan, "shade.self_shadow=\"VoxelMarch\"")
            .map_err(|e| format!("{e:?}"))?;
    }
    let passes = |kind: &'static str| plan.graph.passes.iter().filter(move |p| p.kind == kind);
    let mut specs: Vec<String> = passes("reference.resolve")
        .map(|p| format!("{}.samples_per_axis=1", p.name))
        .collect();
    // Lipp's LOD on, in the reference too (which draws every strand at
    // C_max points): at this size it cuts the strands to a few per bundle.
    for p in passes("lipp.lod") {
        specs.push(format!("{}.enabled=true", p.name));
        specs.push(format!("{}.groom_resolution=true", p.name));
    }
    for spec in &specs {
        override_param(&mut plan, spec).map_err(|e| format!("{e:?}"))?;
    }
    let mut up = upload(scene, W, H);
    complete_upload(&plan, scene, &mut up).map_err(|e| format!("{e:?}"))?;
    let instance = plan
        .instantiate(&up.quantities)
        .map_err(|e| format!("{e:?}"))?;
    let frame = CpuBackend::default()
        .execute(&plan, &instance, &up)
        .map_err(|e| e.to_string())?;
    let (r, _) = plan.graph.outputs[0];
    let name = &plan.graph.resources[r].name;
    let words = frame.read(&plan, name).ok_or("no output")?;
    // Rgba16Float: two words per pixel.
    let background = [words[0], words[1]];
    let drawn = words
        .chunks_exact(2)
        .filter(|px| **px != background)
        .count();
    if drawn == 0 {
        return Err("nothing drawn".into());
    }
    Ok(drawn)
}
