//! `strandgraph info FILE`: strands, points, segments, bounds and memory of a scene
//! (.ron), groom (.hair, .tfx) or mesh (.obj). Errors name the file and the place:
//! `file:line:col` for RON and text formats, a byte offset for binary ones.

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use strandgraph_assets::{Aabb, AssetError, Groom, LoadOptions, Scene, TriMesh, Units};

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph info scenes/crowd.ron
  strandgraph info my_groom.tfx           # a groom (.hair, .tfx) or mesh (.obj)")]
pub struct Args {
    /// A scene (.ron), groom (.hair, .tfx) or mesh (.obj) file.
    pub file: std::path::PathBuf,
    /// Length unit of a groom or mesh file's coordinates (scenes say so per file).
    #[arg(long, value_enum, default_value_t = UnitArg::Metres)]
    pub units: UnitArg,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum UnitArg {
    Metres,
    Centimetres,
    Millimetres,
}

impl From<UnitArg> for Units {
    fn from(u: UnitArg) -> Units {
        match u {
            UnitArg::Metres => Units::Metres,
            UnitArg::Centimetres => Units::Centimetres,
            UnitArg::Millimetres => Units::Millimetres,
        }
    }
}

pub fn run(args: Args) -> miette::Result<()> {
    let started = Instant::now();
    let mut out = String::new();
    let path = args.file.as_path();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let report = |e: AssetError| miette::miette!("{e}");
    match ext.as_str() {
        "ron" => scene_info(path, &mut out).map_err(report)?,
        "obj" => {
            let m = strandgraph_assets::load_mesh(path, args.units.into()).map_err(report)?;
            line(
                &mut out,
                mesh_line(&path.display().to_string(), &m, m.bounds()),
            );
        }
        "hair" | "tfx" => {
            let opts = LoadOptions {
                units: args.units.into(),
                ..Default::default()
            };
            let g = strandgraph_assets::load_groom(path, &opts).map_err(report)?;
            line(
                &mut out,
                groom_line(
                    &path.display().to_string(),
                    &g,
                    g.bounds(),
                    g.memory_bytes(),
                ),
            );
        }
        _ => {
            return Err(miette::miette!(
                "{}: unknown file type (expected .ron, .hair, .tfx or .obj)",
                path.display()
            ));
        }
    }
    line(
        &mut out,
        format!("loaded in {:.2} s", started.elapsed().as_secs_f64()),
    );
    // A closed pipe (`| head`) is not an error worth a panic.
    let _ = std::io::stdout().lock().write_all(out.as_bytes());
    Ok(())
}

fn line(out: &mut String, s: String) {
    out.push_str(&s);
    out.push('\n');
}

fn scene_info(path: &Path, out: &mut String) -> Result<(), AssetError> {
    let scene = Scene::load(path)?;
    let c = scene.counts();
    let graph = if scene.graph.is_file() {
        "found"
    } else {
        "not found"
    };
    *out += &format!(
        "scene {}: {}x{}, {} lights, {} meshes, {} grooms, graph {} ({graph})",
        path.display(),
        c.width,
        c.height,
        c.lights,
        c.meshes,
        c.models,
        scene.desc.graph,
    );
    out.push('\n');
    for m in &scene.meshes {
        let world = m.mesh.bounds().transformed(&m.mesh.transform.matrix());
        line(
            out,
            format!(
                "  {}",
                mesh_line(&format!("mesh  {}", m.name), &m.mesh, world)
            ),
        );
    }
    let mut memory = 0;
    for g in &scene.grooms {
        let mut line = groom_line(
            &format!("groom {}", g.name),
            &g.groom,
            g.world_bounds(),
            g.memory_bytes(),
        );
        if let Some(h) = &g.hair_mesh {
            line += &format!(
                ", hair mesh {} bundles x {} layers",
                thousands(h.bundle_count() as u64),
                h.layers.len() / h.bundle_count().max(1)
            );
        }
        if g.skinning.is_some() {
            line += ", root skinning";
        }
        if g.facial_hair {
            line += ", facial hair";
        }
        memory += g.memory_bytes();
        *out += &format!("  {line}\n");
    }
    *out += &format!(
        "total: {} strands, {} points, {} segments, {} bundles, {} triangles, {}",
        thousands(c.strands),
        thousands(c.vertices),
        thousands(c.segments),
        thousands(c.bundles),
        thousands(c.triangles),
        bytes(memory),
    );
    out.push('\n');
    Ok(())
}

fn groom_line(label: &str, g: &Groom, b: Aabb, memory: usize) -> String {
    format!(
        "{label}: {} strands, {} points, {} segments, bounds {} m, {}",
        thousands(g.strand_count() as u64),
        thousands(g.point_count() as u64),
        thousands(g.segment_count() as u64),
        bounds(b),
        bytes(memory)
    )
}

fn mesh_line(label: &str, m: &TriMesh, b: Aabb) -> String {
    format!(
        "{label}: {} vertices, {} triangles, bounds {} m, {}",
        thousands(m.vertex_count() as u64),
        thousands(m.triangle_count() as u64),
        bounds(b),
        bytes(m.memory_bytes())
    )
}

fn bounds(b: Aabb) -> String {
    if b.is_empty() {
        return "(empty)".into();
    }
    format!(
        "({:.3}, {:.3}, {:.3})..({:.3}, {:.3}, {:.3})",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
    )
}

fn thousands(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::with_capacity(s.len() + s.len() / 3);
    for (i, ch) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(ch);
    }
    out
}

fn bytes(n: usize) -> String {
    let n = n as f64;
    if n >= 1024.0 * 1024.0 {
        format!("{:.1} MiB", n / (1024.0 * 1024.0))
    } else {
        format!("{:.1} KiB", n / 1024.0)
    }
}
