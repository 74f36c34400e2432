//! A camera inside the hair, 5 cm from the cheek: strands pass beside and
//! behind it, so many segments cross the near plane. Every strand pipeline
//! draws the part of such a segment in front of the plane (`common::clip`
//! in strandgraph-passes, its unit tests beside each pass); here the whole
//! Kulikov frame keeps them on every backend, and every pipeline's frame
//! agrees between the CPU simulator and ash (under the validation layer) and
//! wgpu (lavapipe in CI).

use strandgraph::frame::{Prepared, prepare};
use strandgraph_passes::layout::ModelData;

mod common;
use common::{ash, check_flip_of, cpu, out_dir, read_ash, root, wgpu};

const W: u32 = 160;
const H: u32 = 90;

/// The scene: the showcase's head and long hair (LOD off, so every segment
/// is drawn), the camera at the right cheek looking across the face.
fn inside_hair(graph: &str) -> Prepared {
    let text = format!(
        r#"Scene(
    resolution: ({W}, {H}),
    camera: LookAt(position: (0.11, 1.6, 0.06), target: (0.0, 1.62, 0.0), fov_deg: 70.0),
    lights: [Directional(direction: (0.45, -0.6, -0.65), color: (1.0, 0.95, 0.88), intensity: 3.0)],
    meshes: [(name: "head", source: Head(resolution: 48), transform: (translation: (0.0, 1.6, 0.0)))],
    grooms: [(
        name: "hair",
        source: Procedural(style: Long, strands: 6000, points: 16, seed: 7),
        parent: "head",
        material: (melanin: 0.9, roughness: 0.3),
        lod: (enabled: false),
    )],
    graph: {:?},
)
"#,
        root().join(graph)
    );
    let path = out_dir("near_plane").join(format!(
        "{}.ron",
        graph.rsplit('/').next().unwrap().trim_end_matches(".ron")
    ));
    std::fs::write(&path, text).unwrap();
    prepare(&path, None, None).unwrap_or_else(|e| panic!("{e:?}"))
}

/// Segments the cull kept (`segment_visibility`) with one end in front of
/// the near plane and one at or behind it, from the frame's clip positions.
fn kept_crossing(p: &Prepared, visibility: &[u32], clip: &[u32]) -> usize {
    let models: &[ModelData] = bytemuck::cast_slice(&p.upload.resources["models"]);
    let near = strandgraph_passes::upload::NEAR;
    let w = |v: u32| f32::from_bits(clip[4 * v as usize + 3]);
    let mut n = 0;
    for m in models {
        let per = m.points_per_strand - 1;
        for local in 0..m.strand_count * per {
            let id = (m.segment_first + local) as usize;
            if visibility[id / 32] & (1 << (id % 32)) == 0 {
                continue;
            }
            let v0 = m.vertex_first + local / per * m.points_per_strand + local % per;
            if (w(v0) > near) != (w(v0 + 1) > near) {
                n += 1;
            }
        }
    }
    n
}

#[test]
fn kulikov_keeps_segments_crossing_the_near_plane_on_every_backend() {
    let p = inside_hair("scenes/graphs/kulikov.ron");
    let session = ash(&p, false);
    let cpu = cpu(&p, session.subgroup_size);
    let wgpu = wgpu(&p);
    let read_cpu = |name: &str| cpu.read(&p.plan, name).unwrap();
    let on_cpu = kept_crossing(
        &p,
        &read_cpu("segment_visibility"),
        &read_cpu("clip_positions"),
    );
    let on_ash = kept_crossing(
        &p,
        &read_ash(&session, "segment_visibility"),
        &read_ash(&session, "clip_positions"),
    );
    let read_wgpu = |name: &str| wgpu.read(&p.plan, name).unwrap().unwrap();
    let on_wgpu = kept_crossing(
        &p,
        &read_wgpu("segment_visibility"),
        &read_wgpu("clip_positions"),
    );
    eprintln!("segments crossing the near plane kept: cpu {on_cpu}, ash {on_ash}, wgpu {on_wgpu}");
    // Before clipping, the cull dropped every one of them.
    assert!(on_cpu >= 10, "only {on_cpu} crossing segments kept");
    assert!(on_ash.abs_diff(on_cpu) * 100 <= on_cpu && on_wgpu.abs_diff(on_cpu) * 100 <= on_cpu);
    let image = "output.composed";
    let out = read_cpu(image);
    let on_ash = read_ash(&session, image);
    check_flip_of(&p, image, "near_plane", "ash", &out, &on_ash, 0.01);
    check_flip_of(
        &p,
        image,
        "near_plane",
        "wgpu",
        &out,
        &read_wgpu(image),
        0.01,
    );
}

/// Lipp's software raster, the hardware strands and Lipp's reference on the
/// same view: the CPU simulator and ash agree.
#[test]
fn every_strand_pipeline_agrees_across_the_near_plane() {
    for (graph, image) in [
        ("scenes/graphs/lipp.ron", "output.final"),
        ("scenes/graphs/hw_strands.ron", "output.final"),
        ("scenes/graphs/kulikov_reference.ron", "output.reference"),
    ] {
        let p = inside_hair(graph);
        let session = ash(&p, false);
        let cpu = cpu(&p, session.subgroup_size);
        let out = cpu.read(&p.plan, image).unwrap();
        let on_ash = read_ash(&session, image);
        check_flip_of(&p, image, "near_plane", "ash", &out, &on_ash, 0.01);
    }
}
