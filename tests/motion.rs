//! Motion vectors against a known camera move (Kulikov, "Motion vectors"),
//! over two frames of one CPU session: the History buffer carries frame
//! one's compressed NDC into frame two.
//!
//! - Frame one looks at the showcase head from 10 m, beyond the LOD's
//!   `skip_vertices_beyond_m` (8 m), so every other vertex is skipped, and
//!   the strand LOD drops strands; frame two looks from 0.9 m, where every
//!   vertex of every strand is transformed.
//! - Vertices transformed in both frames move as the two known cameras say:
//!   this frame's clip position mapped back to the world by frame two's
//!   inverse view-projection and forward by frame one's.
//! - Vertices frame one skipped get no motion ("assume no movement if vertex
//!   wasn't transformed last frame").

use glam::{Mat4, Vec4};
use std::path::Path;
use strandgraph::frame::override_param;
use strandgraph_assets::Scene;
use strandgraph_assets::scene::Camera;
use strandgraph_cpu::CpuBackend;
use strandgraph_graph::{Instance, Plan, compile_file};
use strandgraph_passes::Registry;
use strandgraph_passes::upload::{Upload, upload};
use strandgraph_wgpu::WgpuBackend;

const W: u32 = 160;
const H: u32 = 90;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn look_from(scene: &mut Scene, position: [f32; 3]) {
    scene.desc.camera = Camera::LookAt {
        position,
        target: [0.0, 1.6, 0.0],
        fov_deg: 35.0,
    };
}

fn floats(words: &[u32]) -> Vec<f32> {
    words.iter().map(|&w| f32::from_bits(w)).collect()
}

/// The Kulikov graph and the showcase seen from 10 m, then from 0.9 m.
fn two_frames() -> (Plan, Instance, Upload, Upload) {
    let mut scene = Scene::load(&root().join("scenes/showcase.ron")).unwrap();
    let mut plan = compile_file(
        &root().join("scenes/graphs/kulikov.ron"),
        &Registry,
        scene.grooms.len() as u32,
    )
    .unwrap();
    // Shading does not matter here; skip the self-shadowing bake.
    override_param(&mut plan, "shade.self_shadow=\"None\"").unwrap();
    look_from(&mut scene, [0.0, 1.6, 10.0]);
    let far = upload(&scene, W, H);
    look_from(&mut scene, [0.0, 1.65, 0.9]);
    let near = upload(&scene, W, H);
    assert_eq!(far.quantities, near.quantities);
    let instance = plan.instantiate(&far.quantities).unwrap();
    (plan, instance, far, near)
}

#[test]
fn motion_vectors_follow_a_known_camera_move() {
    let (plan, instance, far, near) = two_frames();

    // Unaliased, so the transient post-transform cache can be read back.
    let backend = CpuBackend {
        alias: false,
        ..CpuBackend::default()
    };
    let mut session = backend.open(&Registry, &plan, &instance).unwrap();
    session.run(&far).unwrap();
    let clip_far = floats(&session.read(&plan, "clip_positions").unwrap());
    // The first frame has no history: nothing moved.
    for name in ["vertex_motion", "pixel_motion"] {
        let first = floats(&session.read(&plan, name).unwrap());
        assert!(first.iter().all(|&m| m == 0.0), "{name} on the first frame");
    }
    session.run(&near).unwrap();
    let clip_near = floats(&session.read(&plan, "clip_positions").unwrap());
    let motion = floats(&session.read(&plan, "vertex_motion").unwrap());

    let (f1, f2) = (far.frame.unwrap(), near.frame.unwrap());
    let view_proj_far = Mat4::from_cols_array(&f1.view_proj);
    let inv_near = Mat4::from_cols_array(&f2.inv_view_proj);
    let (mut checked, mut skipped, mut largest) = (0, 0, 0.0f32);
    let vertices = clip_near.len() / 4;
    for v in 0..vertices {
        let c2 = Vec4::from_slice(&clip_near[4 * v..4 * v + 4]);
        let m = [motion[2 * v], motion[2 * v + 1]];
        if c2.w <= f2.near {
            continue; // not drawn this frame
        }
        if clip_far[4 * v + 3] == 0.0 {
            // Skipped last frame by the LOD: no motion at all.
            assert_eq!(m, [0.0, 0.0], "vertex {v} was not transformed last frame");
            skipped += 1;
            continue;
        }
        // Where the known cameras put this world point in each frame.
        let world = inv_near * c2;
        let c1 = view_proj_far * (world / world.w);
        let ndc = |c: Vec4| (c.x / c.w, c.y / c.w);
        let ((x1, y1), (x2, y2)) = (ndc(c1), ndc(c2));
        if x1.abs() > 1.0 || y1.abs() > 1.0 {
            continue; // clamped by the UNORM16 history
        }
        let expected = [(x2 - x1) * 0.5 * W as f32, (y1 - y2) * 0.5 * H as f32];
        // UNORM16 steps of 2/65534 NDC, plus float noise of the round trip.
        let tolerance = 0.01;
        assert!(
            (m[0] - expected[0]).abs() < tolerance && (m[1] - expected[1]).abs() < tolerance,
            "vertex {v}: motion {m:?}, the camera move gives {expected:?}"
        );
        largest = largest.max(expected[0].hypot(expected[1]));
        checked += 1;
    }
    eprintln!(
        "{checked} vertices moved as the cameras say (up to {largest:.1} px); {skipped} skipped last frame have none"
    );
    assert!(checked > 10_000, "only {checked} vertices checked");
    assert!(skipped > 10_000, "only {skipped} LOD-skipped vertices");
    assert!(
        largest > 5.0,
        "the camera move should move vertices by pixels"
    );
}

/// The same two frames on wgpu (lavapipe in CI): the History buffer
/// persists across `Session::run`, and the motion agrees with the CPU.
#[test]
fn motion_vectors_agree_on_wgpu() {
    let (plan, instance, far, near) = two_frames();
    let mut cpu = CpuBackend::default()
        .open(&Registry, &plan, &instance)
        .unwrap();
    let mut gpu = WgpuBackend::default()
        .open(&Registry, &plan, &instance)
        .unwrap_or_else(|e| panic!("wgpu: {e} (scripts/test.sh installs lavapipe)"));
    for frame in [&far, &near] {
        cpu.run(frame).unwrap();
        gpu.run(frame).unwrap();
    }
    let c = floats(&cpu.read(&plan, "vertex_motion").unwrap());
    let g = floats(&gpu.read(&plan, "vertex_motion").unwrap().unwrap());
    assert_eq!(c.len(), g.len());
    let moving = c.iter().filter(|m| **m != 0.0).count();
    let worst = c
        .iter()
        .zip(&g)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    let same_zeros = c
        .iter()
        .zip(&g)
        .filter(|(a, b)| (**a == 0.0) == (**b == 0.0))
        .count();
    eprintln!(
        "{moving} moving components; worst difference {worst} px; zero pattern agrees on {same_zeros}/{}",
        c.len()
    );
    assert!(moving > 10_000, "only {moving} moving components");
    // One UNORM16 step is 2/65534 NDC (0.0024 px at 160 px); float division differs by ulps.
    assert!(worst < 0.01, "motion differs by {worst} px");
    assert!(same_zeros as f64 >= 0.999 * c.len() as f64);
}

/// Frame `C`: the near view moved 5 cm sideways, looking the same way (a
/// pure translation, so every pixel moves, not only those off the target's
/// depth).
fn third_frame() -> Upload {
    let mut scene = Scene::load(&root().join("scenes/showcase.ron")).unwrap();
    scene.desc.camera = Camera::LookAt {
        position: [0.05, 1.65, 0.9],
        target: [0.05, 1.6, 0.0],
        fov_deg: 35.0,
    };
    upload(&scene, W, H)
}

/// Per-pixel motion after a pure camera move is the motion of the surface
/// point under each pixel. Hair pixels take the front segment's vertex
/// motion, opaque ones reproject their depth; both must agree with the two
/// cameras. After the 10 m → 0.9 m cut, hair whose vertices the far frame
/// skipped has none, which a reprojection would never give.
#[test]
fn pixel_motion_follows_the_camera_and_the_vertex_history() {
    let (plan, instance, far, near) = two_frames();
    let sideways = third_frame();
    let mut session = CpuBackend {
        alias: false,
        ..CpuBackend::default()
    }
    .open(&Registry, &plan, &instance)
    .unwrap();
    let reprojection = |now: &Upload, prev: &Upload, i: usize, z: f32| {
        let (f, p) = (now.frame.unwrap(), prev.frame.unwrap());
        let (x, y) = ((i as u32 % W) as f32 + 0.5, (i as u32 / W) as f32 + 0.5);
        let ndc = Vec4::new(x / W as f32 * 2.0 - 1.0, 1.0 - y / H as f32 * 2.0, z, 1.0);
        let world = Mat4::from_cols_array(&f.inv_view_proj) * ndc;
        let c = Mat4::from_cols_array(&p.view_proj) * (world / world.w);
        [
            (ndc.x - c.x / c.w) * 0.5 * W as f32,
            (c.y / c.w - ndc.y) * 0.5 * H as f32,
        ]
    };

    session.run(&far).unwrap();
    session.run(&near).unwrap();
    let depth = floats(&session.read(&plan, "hair_depth").unwrap());
    let motion = floats(&session.read(&plan, "pixel_motion").unwrap());
    let unmoved_hair = (0..depth.len())
        .filter(|&i| depth[i] < 1.0 && motion[2 * i] == 0.0 && motion[2 * i + 1] == 0.0)
        .filter(|&i| {
            let r = reprojection(&near, &far, i, depth[i]);
            r[0].hypot(r[1]) > 5.0
        })
        .count();
    assert!(
        unmoved_hair > 50,
        "{unmoved_hair} pixels of LOD-skipped hair"
    );

    session.run(&sideways).unwrap();
    let depth = floats(&session.read(&plan, "hair_depth").unwrap());
    let motion = floats(&session.read(&plan, "pixel_motion").unwrap());
    let (mut with_depth, mut agree, mut largest) = (0, 0, 0.0f32);
    for i in 0..depth.len() {
        if depth[i] >= 1.0 {
            assert_eq!([motion[2 * i], motion[2 * i + 1]], [0.0, 0.0], "background");
            continue;
        }
        with_depth += 1;
        let r = reprojection(&sideways, &near, i, depth[i]);
        let m = [motion[2 * i], motion[2 * i + 1]];
        largest = largest.max(r[0].hypot(r[1]));
        // UNORM16 history steps, and the segment's screen-linear interpolation.
        if (m[0] - r[0]).hypot(m[1] - r[1]) < 0.25 {
            agree += 1;
        }
    }
    eprintln!("{agree}/{with_depth} pixels move as the cameras say (up to {largest:.2} px)");
    assert!(with_depth > 1000, "{with_depth} pixels with depth");
    assert!(largest > 2.0, "the camera move should move pixels");
    assert!(
        agree as f64 >= 0.99 * with_depth as f64,
        "{agree}/{with_depth}"
    );
}

/// The per-pixel motion of the same three frames on wgpu agrees with the CPU.
#[test]
fn pixel_motion_agrees_on_wgpu() {
    let (plan, instance, far, near) = two_frames();
    let sideways = third_frame();
    let mut cpu = CpuBackend::default()
        .open(&Registry, &plan, &instance)
        .unwrap();
    let mut gpu = WgpuBackend::default()
        .open(&Registry, &plan, &instance)
        .unwrap_or_else(|e| panic!("wgpu: {e} (scripts/test.sh installs lavapipe)"));
    for frame in [&far, &near, &sideways] {
        cpu.run(frame).unwrap();
        gpu.run(frame).unwrap();
    }
    let c = floats(&cpu.read(&plan, "pixel_motion").unwrap());
    let g = floats(&gpu.read(&plan, "pixel_motion").unwrap().unwrap());
    assert_eq!(c.len(), g.len());
    let close = c
        .chunks(2)
        .zip(g.chunks(2))
        .filter(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]) < 0.05)
        .count();
    let moving = c.chunks(2).filter(|m| m[0] != 0.0 || m[1] != 0.0).count();
    eprintln!(
        "{close}/{} pixels within 0.05 px; {moving} moving",
        c.len() / 2
    );
    assert!(moving > 1000, "only {moving} moving pixels");
    assert!(close as f64 >= 0.995 * (c.len() / 2) as f64);
}
