//! Tests of `lipp.lod` + `lipp.raster` on hand-made bundles, through the
//! simulator harness.

use super::*;
use crate::contract::PassDef;
use crate::kernel::harness::Harness;
use crate::layout::words_of;
use crate::lipp::BundleRecord;
use crate::lipp::lod::{LOD, LOD_GROUP, scan::LOD_SCAN, scan::SCAN_GROUP};
use crate::lipp::payload::{EMPTY, unpack};
use bytemuck::Zeroable;
use strandgraph_graph::Quantities;

const W: u32 = 96;
const H: u32 = 64;

pub(crate) fn frame() -> FrameData {
    let view = glam::Mat4::look_at_rh(
        glam::Vec3::new(0.0, -0.15, 0.6),
        glam::Vec3::new(0.0, -0.15, 0.0),
        glam::Vec3::Y,
    );
    let proj = glam::Mat4::perspective_rh(0.8, W as f32 / H as f32, 0.02, 500.0);
    let vp = proj * view;
    let mut f = FrameData::zeroed();
    f.view_proj = vp.to_cols_array();
    f.inv_view_proj = vp.inverse().to_cols_array();
    f.camera_pos = [0.0, -0.15, 0.6, 1.0];
    f.screen = [W as f32, H as f32, 1.0 / W as f32, 1.0 / H as f32];
    f.near = 0.02;
    f.far = 500.0;
    f
}

/// Two curly bundles of 4 layers hanging down from y = 0.
pub(crate) fn harness(raster: &str, subgroup: u32) -> (Harness, u32) {
    let mut bundles = Vec::new();
    let mut layers = Vec::new();
    for b in 0..2u32 {
        let x0 = b as f32 * 0.06 - 0.05;
        let rec = BundleRecord {
            first_layer: b * 4,
            layer_count: 4,
            strands: 40,
            model: 0,
            curl_radius: 0.004,
            curl_turns: 4.0,
            twist: 0.25,
            noise: 0.002,
            seed: 7 + b,
            lod_lambda: 1.0,
            // Unknown: the LOD's C_max, so the strands keep every point.
            groom_points: 0,
        };
        bundles.extend(rec.words());
        for i in 0..4 {
            let y = -(i as f32) * 0.1;
            for c in [[0.0, 0.0], [0.03, 0.0], [0.03, 0.03], [0.0, 0.03]] {
                let w = i as f32 / 3.0;
                layers.extend(
                    [x0 + c[0], y, c[1], 1.0 - 0.5 * w, 0.0, -1.0, 0.0, w].map(f32::to_bits),
                );
            }
        }
    }
    let q = Quantities {
        bundles: 2,
        width: W,
        height: H,
        ..Default::default()
    };
    let mut h = Harness::new(q);
    h.subgroup_width = subgroup;
    h.buffer("frame", words_of(&[frame()]))
        .buffer("hairmesh.bundles", bundles)
        .buffer("hairmesh.layers", layers)
        .buffer("lod_choices", vec![0; 8])
        .buffer("bundle_lod", vec![0; 8])
        .buffer("raster_args", vec![0; 8])
        .buffer("scene.depth", vec![1.0f32.to_bits(); (W * H) as usize])
        .buffer("hiz", vec![1.0f32.to_bits(); hiz_blocks()])
        .buffer("gbuffer", vec![u32::MAX; (4 * W * H) as usize]);
    let lod = LOD
        .cpu_kernel(&ron::from_str(r#"{"enabled": false}"#).unwrap())
        .unwrap();
    h.run(lod.as_ref(), 1, LOD_GROUP);
    let scan = LOD_SCAN.cpu_kernel(&ron::Value::Unit).unwrap();
    h.run(scan.as_ref(), 1, SCAN_GROUP);
    let groups = h.read("raster_args")[0];
    let k = crate::PassDef::cpu_kernel(&RASTER, &ron::from_str(raster).unwrap()).unwrap();
    h.run(k.as_ref(), groups, RASTER_GROUP);
    (h, groups)
}

fn hiz_blocks() -> usize {
    (W.div_ceil(16) * H.div_ceil(16)) as usize
}

fn payloads(h: &Harness) -> Vec<u64> {
    h.read("gbuffer")
        .chunks(2)
        .map(|w| u64::from(w[0]) | (u64::from(w[1]) << 32))
        .collect()
}

#[test]
fn strands_land_in_both_layers_and_centre_is_a_subset() {
    let (h, groups) = harness("{}", 32);
    assert_eq!(groups, 80);
    assert_eq!(h.out_of_bounds(), 0);
    let p = payloads(&h);
    let (centre, cons) = p.split_at((W * H) as usize);
    let nc = centre.iter().filter(|&&x| x != EMPTY).count();
    let na = cons.iter().filter(|&&x| x != EMPTY).count();
    assert!(nc > 100 && na > nc, "centre {nc}, conservative {na}");
    for (g, a) in centre.iter().zip(cons) {
        if *g != EMPTY {
            assert_ne!(*a, EMPTY, "a centre hit is also a conservative hit");
            // The conservative layer keeps the nearest of more candidates.
            assert!(unpack(*a).depth <= unpack(*g).depth + 1e-6);
        }
    }
    // Hanging strands: tangents mostly vertical.
    let vertical = centre
        .iter()
        .filter(|&&x| x != EMPTY)
        .filter(|&&x| unpack(x).tangent[1].abs() > 0.5)
        .count();
    assert!(vertical * 2 > nc, "{vertical} of {nc}");
}

#[test]
fn shuffles_naive_assembly_and_subgroup_width_give_identical_g_buffers() {
    let (coop, _) = harness("{}", 32);
    let reference = payloads(&coop);
    for (params, width) in [
        ("{}", 8),
        ("{}", 4),
        (r#"{"cooperative_assembly": false}"#, 32),
        (r#"{"strip_rounds": false}"#, 32),
        (r#"{"strip_rounds": false}"#, 8),
    ] {
        let (h, _) = harness(params, width);
        assert!(
            payloads(&h) == reference,
            "{params} at subgroup width {width}"
        );
    }
}

#[test]
fn segment_payload_changes_only_the_tangent_bits() {
    let (on, _) = harness("{}", 32);
    let (off, _) = harness(r#"{"segment_payload": false}"#, 32);
    let (a, b) = (payloads(&on), payloads(&off));
    let (mut hits, mut changed, mut other_winner) = (0, 0, 0);
    for (&x, &y) in a.iter().zip(&b) {
        assert_eq!(x == EMPTY, y == EMPTY, "the same pixels are written");
        if x == EMPTY {
            continue;
        }
        hits += 1;
        let (sx, sy) = (unpack(x), unpack(y));
        // A depth tie between two strands can resolve to the other one.
        if sx.depth != sy.depth || sx.uvw != sy.uvw || sx.ao != sy.ao {
            other_winner += 1;
            continue;
        }
        changed += usize::from(x != y);
        // Quantised octahedral tangents a segment's turn apart.
        assert!(
            crate::lipp::dot(sx.tangent, sy.tangent) > 0.95,
            "{sx:?} vs {sy:?}"
        );
    }
    assert!(hits > 100 && changed > 0, "{hits} hits, {changed} changed");
    assert!(other_winner * 100 <= hits, "{other_winner} of {hits}");
}

#[test]
fn the_per_sample_payload_is_an_entry_point_of_its_own() {
    use crate::contract::PassDef;
    let entry = |p: &str| RASTER.entry(&ron::from_str(p).unwrap()).unwrap();
    assert_eq!(entry("{}"), "raster");
    assert_eq!(
        entry(r#"{"segment_payload": false}"#),
        "raster_sample_payload"
    );
    assert_eq!(entry(r#"{"strip_rounds": false}"#), "raster_code1_strips");
    assert_eq!(
        RASTER.entries(),
        [
            "raster",
            "raster_sample_payload",
            "raster_code1_strips",
            "raster_sample_payload_code1_strips"
        ]
    );
}

/// The harness's strands keep every point (C = 127, the LOD's C_max), which
/// one point a lane covers in four rounds, and Code 1's strips of four in
/// one: the G-buffer test above compares the two.
#[test]
fn strip_rounds_cover_every_point() {
    use crate::lipp::assemble::{strip_len, strip_rounds};
    let (h, _) = harness("{}", 32);
    let c = h.read("bundle_lod")[1];
    assert_eq!(c, 127);
    assert_eq!((strip_len(c, 1), strip_rounds(c, 1)), (1, 4));
    assert_eq!((strip_len(c, 2), strip_rounds(c, 2)), (2, 2));
    assert_eq!((strip_len(c, 4), strip_rounds(c, 4)), (4, 1));
    for c in 2..=crate::lipp::MAX_CONTROL_POINTS {
        for max in [1, 2, 4] {
            let (s, r) = (strip_len(c, max), strip_rounds(c, max));
            // Every segment a lane's strip, and no round without one.
            assert!(
                r * 32 * s >= c - 1 && (r - 1) * 32 * s < c - 1,
                "C {c}, {max}"
            );
        }
    }
}

#[test]
fn depth_test_against_the_scene_rejects_hidden_strands() {
    let (mut h, groups) = harness("{}", 32);
    h.buffer("scene.depth", vec![0.0f32.to_bits(); (W * H) as usize])
        .buffer("gbuffer", vec![u32::MAX; (4 * W * H) as usize]);
    let k = crate::PassDef::cpu_kernel(&RASTER, &ron::Value::Unit).unwrap();
    let c = h.run(k.as_ref(), groups, RASTER_GROUP);
    assert_eq!(c.pixels_written, 0);
    assert!(payloads(&h).iter().all(|&x| x == EMPTY));
}

#[test]
fn occlusion_culling_skips_hidden_segments_and_changes_nothing() {
    use crate::kulikov::depth_downsample::DEPTH_DOWNSAMPLE;
    let (mut h, _) = harness("{}", 32);
    // A wall over the left half at the strands' median depth.
    let mut depths: Vec<f32> = payloads(&h)
        .iter()
        .filter(|&&x| x != EMPTY)
        .map(|&x| unpack(x).depth)
        .collect();
    depths.sort_by(f32::total_cmp);
    let wall = depths[depths.len() / 2];
    let scene = (0..W * H).map(|i| if i % W < W / 2 { wall } else { 1.0 });
    h.buffer("scene.depth", scene.map(f32::to_bits).collect());
    let downsample = DEPTH_DOWNSAMPLE.cpu_kernel(&ron::Value::Unit).unwrap();
    h.run(downsample.as_ref(), hiz_blocks() as u32, 256);
    let groups = h.read("raster_args")[0];
    let mut draw = |params: &str| {
        h.buffer("gbuffer", vec![u32::MAX; (4 * W * H) as usize]);
        let k = crate::PassDef::cpu_kernel(&RASTER, &ron::from_str(params).unwrap()).unwrap();
        let c = h.run(k.as_ref(), groups, RASTER_GROUP);
        (payloads(&h), c.culled, c.atomics)
    };
    let (culled, n, atomics) = draw("{}");
    let (walked, none, all_atomics) = draw(r#"{"occlusion_cull": false}"#);
    assert_eq!(none, 0);
    assert!(n > 0, "no segment was culled");
    assert!(culled == walked, "culling changed the G-buffer");
    // Culled segments are the ones whose samples the depth test rejects.
    assert_eq!(atomics, all_atomics);
    assert!(culled.iter().any(|&x| x != EMPTY));
}

#[test]
fn bad_params_are_errors() {
    for bad in [
        r#"{"msaa": 3}"#,
        r#"{"centre_diameter": 0.0}"#,
        r#"{"styling": 1}"#,
    ] {
        assert!(
            crate::PassDef::cpu_kernel(&RASTER, &ron::from_str(bad).unwrap()).is_err(),
            "{bad}"
        );
    }
}

#[test]
fn msaa_reference_mode_fills_one_layer_per_sample() {
    let (mut h, groups) = harness("{}", 32);
    let layers = 4usize;
    h.buffer("gbuffer", vec![u32::MAX; 2 * layers * (W * H) as usize]);
    let k = RASTER
        .cpu_kernel(&ron::from_str(r#"{"msaa": 4}"#).unwrap())
        .unwrap();
    h.run(k.as_ref(), groups, RASTER_GROUP);
    assert_eq!(h.out_of_bounds(), 0);
    let p = payloads(&h);
    let hits: Vec<usize> = p
        .chunks((W * H) as usize)
        .map(|l| l.iter().filter(|&&x| x != EMPTY).count())
        .collect();
    assert_eq!(hits.len(), layers);
    // Four sample positions see about as many strand pixels each.
    let (lo, hi) = (*hits.iter().min().unwrap(), *hits.iter().max().unwrap());
    assert!(lo > 100 && hi < 2 * lo, "{hits:?}");
    assert_eq!(super::sample_positions(8).len(), 8);
}

#[test]
fn a_columns_rows_are_the_union_of_both_layers_rows() {
    use super::column_rows;
    let empty = (1, 0);
    assert_eq!(column_rows((3, 4), (2, 5)), (2, 5));
    assert_eq!(column_rows((3, 4), (4, 4)), (3, 4));
    assert_eq!(column_rows(empty, (2, 3)), (2, 3), "no centre sample");
    assert_eq!(column_rows((7, 8), empty), (7, 8), "no conservative layer");
    let (lo, hi) = column_rows(empty, empty);
    assert!(lo > hi, "nothing to visit");
}
