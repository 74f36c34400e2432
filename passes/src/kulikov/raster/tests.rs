//! The rasterizer against a brute-force reference, and order independence.

use super::*;
use crate::kernel::harness::Harness;
use crate::layout::{FrameData, ModelData, words_of};
use bytemuck::Zeroable;
use strandgraph_graph::Quantities;

const SIZE: u32 = 64;
const NEAR: f32 = 0.5;
const FAR: f32 = 10.0;

/// A segment in screen pixels with a width (pixels) and view depth at each end.
#[derive(Clone, Copy)]
struct Seg {
    a: [f32; 2],
    b: [f32; 2],
    width: f32,
    wa: f32,
    wb: f32,
}

fn harness(segs: &[Seg], order: &[u32]) -> Harness {
    let mut clip = Vec::new();
    let mut thickness = Vec::new();
    for s in segs {
        for (p, w) in [(s.a, s.wa), (s.b, s.wb)] {
            clip.push(clip_at(p, w));
            thickness.push(s.width * w);
        }
    }
    harness_clip(&clip, &thickness, order)
}

/// Screen (x right, y down) back to clip space at depth `w`.
fn clip_at(p: [f32; 2], w: f32) -> [f32; 4] {
    let ndc = [
        p[0] / SIZE as f32 * 2.0 - 1.0,
        1.0 - p[1] / SIZE as f32 * 2.0,
    ];
    [ndc[0] * w, ndc[1] * w, 0.5 * w, w]
}

/// Segments given by their ends' clip positions and world thicknesses
/// (`pixels_per_unit` is 1).
fn harness_clip(clip: &[[f32; 4]], thickness: &[f32], order: &[u32]) -> Harness {
    let n = (clip.len() / 2) as u32;
    let mut frame = FrameData::zeroed();
    frame.screen = [
        SIZE as f32,
        SIZE as f32,
        1.0 / SIZE as f32,
        1.0 / SIZE as f32,
    ];
    frame.near = 0.01;
    frame.far = 100.0;
    frame.model_count = 1;
    // Thickness is in world units × pixels_per_unit / w; store width × w so it comes out in pixels.
    frame.pixels_per_unit = 1.0;
    let mut model = ModelData::zeroed();
    model.strand_count = n;
    model.points_per_strand = 2;
    let clip: Vec<u32> = clip.iter().flatten().map(|v| v.to_bits()).collect();
    let verts: Vec<u32> = thickness
        .iter()
        .flat_map(|&t| [0.0, 0.0, 0.0, t].map(f32::to_bits))
        .collect();
    let lod = ModelLod {
        strands: n,
        vertex_step: 1,
        thickness_scale: 1.0,
        segments_per_strand: 1,
        strand_prefix: 0,
        depth_near: NEAR,
        depth_far: FAR,
        segment_prefix: 0,
    };
    let mut lods = vec![0u32; ModelLod::WORDS];
    lods[0] = lod.strands;
    lods[1] = 1;
    lods[2] = 1.0f32.to_bits();
    lods[3] = 1;
    lods[5] = NEAR.to_bits();
    lods[6] = FAR.to_bits();
    let q = Quantities {
        strands: u64::from(n),
        segments: u64::from(n),
        models: 1,
        width: SIZE,
        height: SIZE,
        ..Quantities::default()
    };
    let mut h = Harness::new(q);
    h.buffer("frame", words_of(&[frame]))
        .buffer("models", words_of(&[model]))
        .buffer("lod_models", lods)
        .buffer("sorted_segments", order.to_vec())
        .buffer("clip_positions", clip)
        .buffer("groom.vertices", verts)
        .buffer("atlas_tiles", vec![0, 1, 1, 0, 0, 1, 1, 0])
        .buffer(
            "scene.depth",
            vec![1.0f32.to_bits(); (SIZE * SIZE) as usize],
        )
        .buffer("vis_atlas", vec![EMPTY; 3 * TILE_TEXELS as usize])
        .buffer("coverage_atlas", vec![0; TILE_TEXELS as usize])
        .buffer("raster_args", vec![1, 1, 1, n]);
    h
}

fn run(segs: &[Seg], order: &[u32], params: RasterParams) -> (Vec<u32>, Vec<u32>, CounterValues) {
    let h = harness(segs, order);
    let stats = h.run(&RasterKernel(params), 1, GROUP);
    assert_eq!(h.out_of_bounds(), 0);
    (h.read("vis_atlas"), h.read("coverage_atlas"), stats)
}

fn defaults() -> RasterParams {
    RasterParams::default()
}

/// Supersampled coverage of pixel (x, y) by the segment's trapezoid, computed
/// without the rasterizer's geometry code: point-in-quad over n×n samples.
fn reference_coverage(s: &Seg, x: u32, y: u32, n: u32) -> f32 {
    grown_coverage(s, x, y, n, 0.0)
}

/// Coverage of the trapezoid grown (or shrunk, negative) by `grow` pixels.
fn grown_coverage(s: &Seg, x: u32, y: u32, n: u32, grow: f32) -> f32 {
    let d = [s.b[0] - s.a[0], s.b[1] - s.a[1]];
    let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
    let (dir, nrm) = ([d[0] / len, d[1] / len], [-d[1] / len, d[0] / len]);
    let mut inside = 0;
    for j in 0..n {
        for i in 0..n {
            let p = [
                x as f32 + (i as f32 + 0.5) / n as f32 - s.a[0],
                y as f32 + (j as f32 + 0.5) / n as f32 - s.a[1],
            ];
            let along = (p[0] * dir[0] + p[1] * dir[1]) / len;
            let across = (p[0] * nrm[0] + p[1] * nrm[1]).abs();
            let half = 0.5 * s.width + grow; // equal widths in these tests
            let slack = grow / len;
            if (-slack..=1.0 + slack).contains(&along) && across <= half {
                inside += 1;
            }
        }
    }
    inside as f32 / (n * n) as f32
}

fn reference_depth(s: &Seg, x: u32, y: u32) -> u32 {
    // Endpoints on the 1/256-pixel grid every backend snaps to (docs/architecture.md).
    let snap = |v: f32| (v * 256.0).round() / 256.0;
    let (a, b) = ([snap(s.a[0]), snap(s.a[1])], [snap(s.b[0]), snap(s.b[1])]);
    let p = [x as f32 + 0.5 - a[0], y as f32 + 0.5 - a[1]];
    let d = [b[0] - a[0], b[1] - a[1]];
    let t = ((p[0] * d[0] + p[1] * d[1]) / (d[0] * d[0] + d[1] * d[1])).clamp(0.0, 1.0);
    super::super::payload::quantize_depth(s.wa + t * (s.wb - s.wa), NEAR, FAR)
}

fn segments() -> Vec<Seg> {
    let mut v = Vec::new();
    // A fan of thick and thin segments crossing each other at various slopes and depths.
    for k in 0..24u32 {
        let angle = k as f32 * 0.26;
        let (c, s) = (angle.cos(), angle.sin());
        v.push(Seg {
            a: [32.3 - 22.0 * c, 31.7 - 20.0 * s],
            b: [31.9 + 21.0 * c, 32.2 + 19.0 * s],
            width: [0.3, 1.0, 2.5, 4.0][k as usize % 4],
            wa: 1.0 + k as f32 * 0.3,
            wb: 2.0 + (23 - k) as f32 * 0.25,
        });
    }
    v
}

#[test]
fn coverage_of_a_thick_segment_matches_the_reference() {
    let seg = [Seg {
        a: [10.2, 12.7],
        b: [50.6, 40.1],
        width: 3.3,
        wa: 1.0,
        wb: 1.0,
    }];
    let (_, cov, _) = run(&seg, &[0], defaults());
    for y in 0..SIZE {
        for x in 0..SIZE {
            let got = cov[(y * TILE + x) as usize] as f32 / COVERAGE_SCALE;
            let want = reference_coverage(&seg[0], x, y, 64);
            assert!(
                (got - want).abs() < 0.03,
                "pixel ({x}, {y}): {got} vs {want}"
            );
        }
    }
}

#[test]
fn layers_hold_the_three_nearest_fragments() {
    let segs = segments();
    let order: Vec<u32> = (0..segs.len() as u32).collect();
    let (vis, _, _) = run(&segs, &order, defaults());
    let mut checked = 0;
    for y in 0..SIZE {
        for x in 0..SIZE {
            // A segment covers the pixel when even its slightly shrunk shape does;
            // skip pixels that only the grown shape touches (grazing edges the
            // supersampled reference cannot decide like the exact area does).
            let inner: Vec<f32> = segs
                .iter()
                .map(|s| grown_coverage(s, x, y, 32, -0.05))
                .collect();
            let outer: Vec<f32> = segs
                .iter()
                .map(|s| grown_coverage(s, x, y, 32, 0.05))
                .collect();
            if inner.iter().zip(&outer).any(|(&i, &o)| i == 0.0 && o > 0.0) {
                continue;
            }
            let covs = inner;
            let mut want: Vec<u32> = (0..segs.len())
                .filter(|&i| covs[i] > 0.0)
                .map(|i| pack(reference_depth(&segs[i], x, y), i as u32))
                .collect();
            want.sort_unstable();
            want.resize(LAYERS, EMPTY);
            let texel = (y * TILE + x) as usize;
            let got: Vec<u32> = (0..LAYERS)
                .map(|l| vis[texel + l * TILE_TEXELS as usize])
                .collect();
            assert_eq!(got, want[..LAYERS], "pixel ({x}, {y})");
            checked += 1;
        }
    }
    assert!(checked > 3000, "only {checked} pixels were unambiguous");
}

#[test]
fn shuffled_segment_order_gives_identical_layers() {
    let segs = segments();
    let order: Vec<u32> = (0..segs.len() as u32).collect();
    let mut shuffled = order.clone();
    shuffled.reverse();
    shuffled.swap(3, 17);
    for params in [
        defaults(),
        RasterParams {
            last_layer_cull: false,
            morton_sort: false,
            ..defaults()
        },
    ] {
        let (v1, c1, _) = run(&segs, &order, params);
        let (v2, c2, _) = run(&segs, &shuffled, params);
        assert_eq!(v1, v2);
        assert_eq!(c1, c2);
    }
}

#[test]
fn ablations_change_cost_not_results() {
    let segs = segments();
    let order: Vec<u32> = (0..segs.len() as u32).collect();
    let (v, c, flat) = run(&segs, &order, defaults());
    let (v2, c2, nested) = run(
        &segs,
        &order,
        RasterParams {
            loop_flattening: false,
            ..defaults()
        },
    );
    let (v3, c3, no_cull) = run(
        &segs,
        &order,
        RasterParams {
            last_layer_cull: false,
            ..defaults()
        },
    );
    assert_eq!((&v, &c), (&v2, &c2));
    assert_eq!((&v, &c), (&v3, &c3));
    let util = |s: &CounterValues| s.lane_utilisation().unwrap();
    assert!(
        util(&flat) > util(&nested),
        "flattened {} vs nested {}",
        util(&flat),
        util(&nested)
    );
    assert!(no_cull.atomics >= flat.atomics);
}

#[test]
fn fragments_behind_the_scene_depth_are_rejected() {
    let seg = [Seg {
        a: [5.0, 5.0],
        b: [60.0, 60.0],
        width: 2.0,
        wa: 5.0,
        wb: 5.0,
    }];
    let mut h = harness(&seg, &[0]);
    // Scene depth at view distance 2: everything of the segment (at 5) is hidden.
    let z = (100.0 / (100.0 - 0.01)) * (1.0 - 0.01 / 2.0);
    h.buffer(
        "scene.depth",
        vec![(z as f32).to_bits(); (SIZE * SIZE) as usize],
    );
    h.run(&RasterKernel(defaults()), 1, GROUP);
    assert!(h.read("coverage_atlas").iter().all(|&c| c == 0));
    assert!(h.read("vis_atlas").iter().all(|&p| p == EMPTY));
}

/// `n` segments of lengths from 1.5 to 60 pixels at every slope and three
/// widths: the divergent loop bounds of Kulikov's "Divergence" slide.
fn varied_segments(n: u32) -> Vec<Seg> {
    (0..n)
        .map(|k| {
            let len = 1.5 + ((k * 37) % 59) as f32;
            let angle = k as f32 * 0.7;
            let centre = [
                32.0 + ((k * 13) % 9) as f32 - 4.0,
                32.0 + ((k * 7) % 11) as f32 - 5.0,
            ];
            let (dx, dy) = (0.5 * len * angle.cos(), 0.5 * len * angle.sin());
            let clamp = |v: f32| v.clamp(0.3, SIZE as f32 - 0.3);
            Seg {
                a: [clamp(centre[0] - dx), clamp(centre[1] - dy)],
                b: [clamp(centre[0] + dx), clamp(centre[1] + dy)],
                width: [0.5, 1.0, 2.0][k as usize % 3],
                wa: 1.0 + (k % 17) as f32 * 0.4,
                wb: 1.5 + (k % 13) as f32 * 0.5,
            }
        })
        .collect()
}

/// Runs every workgroup the segments need at subgroup width `width`.
fn run_wide(segs: &[Seg], width: u32, params: RasterParams) -> (Vec<u32>, Vec<u32>, CounterValues) {
    let order: Vec<u32> = (0..segs.len() as u32).collect();
    let mut h = harness(segs, &order);
    h.subgroup_width = width;
    let stats = h.run(
        &RasterKernel(params),
        (segs.len() as u32).div_ceil(GROUP),
        GROUP,
    );
    assert_eq!(h.out_of_bounds(), 0);
    (h.read("vis_atlas"), h.read("coverage_atlas"), stats)
}

fn switches(bits: u32) -> RasterParams {
    RasterParams {
        loop_flattening: bits & 1 != 0,
        pixel_request_stack: bits & 2 != 0,
        depth_test_stack: bits & 4 != 0,
        last_layer_cull: bits & 8 != 0,
        morton_sort: bits & 16 != 0,
        ..defaults()
    }
}

#[test]
fn every_switch_combination_writes_the_same_atlas() {
    // 300 segments: two workgroups, the second partly idle. Width 48 does
    // not divide 256, so the last subgroup of a group runs without stacks.
    let segs = varied_segments(300);
    let (vis, cov, _) = run_wide(&segs, 32, defaults());
    assert!(cov.iter().filter(|&&c| c > 0).count() > 1500);
    for width in [8, 32, 48] {
        for bits in 0..32 {
            let (v, c, stats) = run_wide(&segs, width, switches(bits));
            assert!(v == vis && c == cov, "width {width}, {:?}", switches(bits));
            assert!(stats.total_lanes > 0);
        }
    }
}

#[test]
fn flattening_raises_lane_utilisation_on_varied_lengths() {
    let segs = varied_segments(300);
    let util = |p: RasterParams| run_wide(&segs, 32, p).2.lane_utilisation().unwrap();
    for stacks in [true, false] {
        let with = |flat| RasterParams {
            loop_flattening: flat,
            pixel_request_stack: stacks,
            depth_test_stack: stacks,
            ..defaults()
        };
        let (flat, nested) = (util(with(true)), util(with(false)));
        assert!(
            flat > nested,
            "stacks {stacks}: flattened {flat} vs nested {nested}"
        );
    }
}

#[test]
fn request_stacks_raise_lane_utilisation() {
    let segs = varied_segments(300);
    for flat in [true, false] {
        let with = |stacks| RasterParams {
            loop_flattening: flat,
            pixel_request_stack: stacks,
            depth_test_stack: stacks,
            // The cull's savings depend on the order writes arrive in, which the stacks change.
            last_layer_cull: false,
            ..defaults()
        };
        let (s, n) = (
            run_wide(&segs, 32, with(true)).2,
            run_wide(&segs, 32, with(false)).2,
        );
        // The same pixels and atomics, in fuller steps.
        assert_eq!((s.pixels_written, s.atomics), (n.pixels_written, n.atomics));
        assert!(
            s.lane_utilisation() > n.lane_utilisation(),
            "flattened {flat}: {s:?} vs {n:?}"
        );
    }
}

/// A segment from in front of the camera to behind it draws its part in
/// front of the near plane (`common::clip`), exactly as that part given as
/// the segment; one wholly behind draws nothing.
#[test]
fn a_segment_crossing_the_near_plane_draws_its_part_in_front() {
    let near = 0.01; // the harness's frame.near
    let front = clip_at([12.0, 40.0], 2.0);
    let behind = [0.9, 0.3, -0.5, -1.0];
    let run_clip = |clip: &[[f32; 4]], thickness: &[f32]| {
        let h = harness_clip(clip, thickness, &[0]);
        h.run(&RasterKernel(defaults()), 1, GROUP);
        assert_eq!(h.out_of_bounds(), 0);
        (h.read("vis_atlas"), h.read("coverage_atlas"))
    };
    let (vis, cov) = run_clip(&[front, behind], &[2.0, 2.0]);
    let part = crate::common::clip::near_clip(front, behind, near).unwrap();
    assert_eq!(part.b[3], near);
    let (vis_part, cov_part) = run_clip(&[part.a, part.b], &part.ends(2.0, 2.0));
    assert_eq!((&vis, &cov), (&vis_part, &cov_part));
    let covered = (0..(SIZE * SIZE) as usize)
        .filter(|&i| vis[i] != EMPTY)
        .count();
    assert!(covered > 40, "{covered} pixels");
    let (vis, _) = run_clip(&[[0.1, 0.1, -0.1, 0.005], behind], &[2.0, 2.0]);
    assert!(vis.iter().all(|&p| p == EMPTY));
}
