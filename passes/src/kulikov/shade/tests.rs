//! Shading on hand-made strands: only visible segments' vertices are shaded,
//! the voxel march darkens what lies behind dense hair, the baked SH darkens
//! towards the directions it counts scattering events in.

use super::*;
use crate::kernel::harness::Harness;
use crate::kulikov::ModelLod;
use crate::kulikov::density::AREA_UNIT;
use crate::layout::{ModelData, words_of};
use crate::opaque_mesh::testing::{frame, sun};
use bytemuck::Zeroable;
use strandgraph_graph::Quantities;

const POINTS: u32 = 5;

/// Plain words as a binding (leaked: test-only, a few KiB).
fn words(w: &[u32]) -> Words<'static> {
    use std::sync::atomic::{AtomicU32, AtomicU64};
    let atoms: Vec<AtomicU32> = w.iter().map(|&x| AtomicU32::new(x)).collect();
    Words::new(
        Box::leak(atoms.into_boxed_slice()),
        Box::leak(Box::new(AtomicU64::new(0))),
    )
}

/// `strands` vertical strands along x, 1 cm apart, lit from +z; every
/// segment visible except `hidden`.
fn harness(strands: u32, hidden: &[u32]) -> (Harness, Vec<u32>) {
    let mut f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 40.0, 64, 64);
    f.model_count = 1;
    f.light_count = 1;
    let vp = glam::Mat4::from_cols_array(&f.view_proj);
    let mut m = ModelData::zeroed();
    m.strand_count = strands;
    m.points_per_strand = POINTS;
    m.bounds_min = [-0.1, -0.1, -0.1, 0.0];
    m.bounds_max = [0.1, 0.1, 0.1, 0.0];
    m.color = [0.3, 0.2, 0.1, 0.3];
    let lod = ModelLod {
        strands,
        vertex_step: 1,
        thickness_scale: 1.0,
        segments_per_strand: POINTS - 1,
        ..Default::default()
    };
    let lod_words = {
        let w = words(&[0; 8]);
        lod.store(&w, 0);
        (0..8).map(|i| w.load(i)).collect::<Vec<u32>>()
    };
    let (mut clip, mut verts) = (Vec::new(), Vec::new());
    for s in 0..strands {
        for k in 0..POINTS {
            let p = Vec3::new(-0.05 + 0.01 * s as f32, 0.05 - 0.025 * k as f32, 0.0);
            clip.extend((vp * p.extend(1.0)).to_array().map(f32::to_bits));
            verts.extend([p.x, p.y, p.z, 1e-3].map(f32::to_bits));
        }
    }
    let segments = strands * (POINTS - 1);
    let mut bits = vec![0u32; segments.div_ceil(32) as usize];
    let visible: Vec<u32> = (0..segments).filter(|s| !hidden.contains(s)).collect();
    for &s in &visible {
        bits[(s / 32) as usize] |= 1 << (s % 32);
    }
    let n = visible.len() as u32;
    let mut hs = Harness::new(Quantities {
        segments: u64::from(segments),
        vertices: u64::from(strands * POINTS),
        models: 1,
        lights: 1,
        width: 64,
        height: 64,
        ..Default::default()
    });
    hs.buffer("frame", words_of(&[f]))
        .buffer("models", words_of(&[m]))
        .buffer("lod_models", lod_words)
        .buffer("lights", words_of(&[sun(Vec3::new(0.0, 0.0, -1.0), 3.0)]))
        .buffer("shade_args", vec![n.div_ceil(SHADE_GROUP), 1, 1, n])
        .buffer("shading_segments", visible.clone())
        .buffer("segment_visibility", bits)
        .buffer("clip_positions", clip)
        .buffer("groom.vertices", verts)
        .buffer("density_grid", vec![0; GRID_WORDS as usize])
        .buffer("groom.shadow_sh", vec![0; (4 * strands * POINTS) as usize])
        .buffer(
            "vertex_lighting",
            vec![u32::MAX; (2 * strands * POINTS) as usize],
        );
    (hs, visible)
}

fn shade(hs: &Harness, params: &str) -> Vec<[f32; 4]> {
    let k = crate::PassDef::cpu_kernel(&SHADE, &ron::from_str(params).unwrap()).unwrap();
    let groups = hs.read("shade_args")[0];
    hs.run(k.as_ref(), groups, SHADE_GROUP);
    assert_eq!(hs.out_of_bounds(), 0);
    let w = hs.read("vertex_lighting");
    let words = words(&w);
    (0..w.len() / 2)
        .map(|i| crate::kulikov::debug_resolve::load_rgba16f(&words, i))
        .collect()
}

#[test]
fn shades_exactly_the_vertices_of_visible_segments() {
    // Strand 1 has no visible segment; strand 2 lost its last two.
    let per = POINTS - 1;
    let hidden = [per, per + 1, per + 2, per + 3, 2 * per + 2, 2 * per + 3];
    let (hs, _) = harness(3, &hidden);
    let lit = shade(&hs, r#"{"self_shadow": "None"}"#);
    let shaded: Vec<bool> = lit.iter().map(|c| c[3] == 1.0).collect();
    let p = POINTS as usize;
    assert!(shaded[..p].iter().all(|&s| s), "strand 0 {shaded:?}");
    assert!(shaded[p..2 * p].iter().all(|&s| !s), "strand 1 {shaded:?}");
    assert_eq!(&shaded[2 * p..], &[true, true, true, false, false]);
    for c in lit.iter().filter(|c| c[3] == 1.0) {
        assert!(c[..3].iter().all(|x| x.is_finite() && *x > 0.0), "{c:?}");
    }
}

#[test]
fn voxel_march_darkens_hair_behind_dense_hair() {
    let (mut hs, _) = harness(2, &[]);
    // A dense slab between the strands (z = 0) and the light (+z), 5 cm thick.
    let m: ModelData = crate::layout::read(&words(&hs.read("models")), 0);
    let g = Grid::of(&m, 48);
    let mut grid = vec![0u32; GRID_WORDS as usize];
    // Ten strands crossed per centimetre of slab.
    let units = (1000.0 * g.voxel_volume() / AREA_UNIT) as u32;
    for z in 0..48u32 {
        for y in 0..48u32 {
            for x in 0..48u32 {
                let zc = g.min[2] + (z as f32 + 0.5) * g.size[2] / 48.0;
                if zc > 0.02 && zc < 0.07 {
                    grid[((z * 48 + y) * 48 + x) as usize] = units;
                }
            }
        }
    }
    let free = shade(&hs, r#"{"self_shadow": "VoxelMarch"}"#);
    hs.buffer("density_grid", grid);
    let shadowed = shade(&hs, r#"{"self_shadow": "VoxelMarch", "ambient": 0.0}"#);
    let none = shade(&hs, r#"{"self_shadow": "None", "ambient": 0.0}"#);
    assert!(
        free[2][0] > 10.0 * shadowed[2][0],
        "{:?} vs {:?}",
        free[2],
        shadowed[2]
    );
    assert!(none[2][0] > 10.0 * shadowed[2][0]);
}

/// Kulikov's fetch: visibility = exp(−absorption · max(0, SH · light)).
/// The light is at +z: an SH that counts events towards +z darkens by
/// exactly that factor, one that counts them away from it (or the biased
/// "all missed" SH) leaves the shading as unshadowed.
#[test]
fn baked_sh_shadows_towards_the_light_only() {
    let (mut hs, _) = harness(2, &[]);
    let n = (2 * POINTS) as usize;
    let params = r#"{"self_shadow": "Baked", "ambient": 0.0, "absorption": 0.5}"#;
    let none = shade(&hs, r#"{"self_shadow": "None", "ambient": 0.0}"#);
    let sh_of = |z: f32, c0: f32| -> Vec<u32> {
        (0..n)
            .flat_map(|_| [c0, 0.0, z, 0.0].map(f32::to_bits))
            .collect()
    };
    // Two events towards +z (and -2 towards -z): Y1 * c = 2.
    let c = 2.0 / strandgraph_bake::sh::Y1;
    hs.buffer("groom.shadow_sh", sh_of(c, 0.0));
    let towards = shade(&hs, params);
    hs.buffer("groom.shadow_sh", sh_of(-c, 0.0));
    let away = shade(&hs, params);
    // Every ray missed: the zero-event bias, -5 everywhere.
    hs.buffer(
        "groom.shadow_sh",
        sh_of(0.0, -5.0 / strandgraph_bake::sh::Y0),
    );
    let open = shade(&hs, params);
    let k = (-0.5f32 * 2.0).exp();
    for v in 0..n {
        assert_eq!(away[v], none[v], "vertex {v}");
        assert_eq!(open[v], none[v], "vertex {v}");
        // Karis's scatter fake also tints by pow(colour / luma, 1 − k), so
        // the red channel is scaled by k within that tint.
        assert!(
            towards[v][0] < none[v][0] * k * 1.3 && towards[v][0] > none[v][0] * k * 0.7,
            "vertex {v}: {:?} vs {:?} (k = {k})",
            towards[v],
            none[v]
        );
    }
}

#[test]
fn bake_settings_are_checked() {
    let p = |s: &str| SHADE.params(&ron::from_str(s).unwrap());
    let ok = p(r#"{"self_shadow": "Baked", "bake_rays": 8}"#).unwrap();
    assert_eq!(ok.self_shadow, SelfShadow::Baked);
    assert_eq!(ok.bake().rays, 8);
    for bad in [
        r#"{"bake_rays": 0}"#,
        r#"{"bake_vertex_stride": 0}"#,
        r#"{"max_scatter_events": -1.0}"#,
        r#"{"self_shadow": "Soft"}"#,
    ] {
        assert!(p(bad).is_err(), "{bad}");
    }
}
