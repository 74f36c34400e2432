//! The CPU kernel of `hw_strands.raster` on segments made by hand: sample
//! coverage at each MSAA count, the head's depth, the nearest strand
//! winning whatever the draw order, earlier grooms' `hair_depth`.

use super::raster::RASTER;
use super::{Segment, VERTICES_PER_SEGMENT};
use crate::kernel::harness::Harness;
use crate::layout::{FrameData, words_of};
use crate::lipp::payload::unpack;
use crate::opaque_mesh::testing::{frame, run_with};
use glam::{Vec2, Vec3, Vec4};
use strandgraph_graph::Quantities;

const W: u32 = 48;
const H: u32 = 32;
const EMPTY: u32 = u32::MAX;

/// A segment across the screen rising by `rise` (world units) at depth `z`,
/// its payload's w 0 at end a and 1 at end b.
fn segment(f: &FrameData, rise: f32, z: f32) -> Segment {
    let vp = glam::Mat4::from_cols_array(&f.view_proj);
    let clip = |x: f32| vp * Vec4::new(x, x * rise, z, 1.0);
    Segment {
        a: clip(-0.5),
        b: clip(0.5),
        bits_a: 7 << 12,
        bits_b: 63 << 8,
    }
}

/// `segments` drawn at `samples` MSAA over a head at depth `head`.
fn draw(segments: &[Segment], samples: usize, head: f32, model_index: u32) -> Harness {
    let f = frame(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 40.0, W, H);
    let pixels = (W * H) as usize;
    let mut hs = Harness::new(Quantities {
        width: W,
        height: H,
        mesh_strands: 1,
        ..Default::default()
    });
    let records: Vec<u32> = segments.iter().flat_map(|s| s.words()).collect();
    let count = segments.len() as u32 * VERTICES_PER_SEGMENT;
    hs.buffer("frame", words_of(&[f]))
        .buffer("hw_segments", records)
        .buffer("hw_draw_args", vec![count, 1, 0, 0])
        .buffer("scene.depth", vec![head.to_bits(); pixels])
        .buffer("hair_depth", vec![0.5f32.to_bits(); pixels])
        .buffer("gbuffer", vec![EMPTY; 2 * 8 * pixels])
        .buffer("strand_depth", vec![head.to_bits(); samples * pixels]);
    let params = ron::from_str(&format!("{{\"model_index\": {model_index}}}")).unwrap();
    run_with(&hs, &RASTER, &params);
    assert_eq!(hs.out_of_bounds(), 0);
    hs
}

/// Covered samples per G-buffer layer, and the payloads written.
fn covered(hs: &Harness) -> (Vec<usize>, Vec<u64>) {
    let g = hs.read("gbuffer");
    let pixels = (W * H) as usize;
    let mut per_layer = vec![0; 8];
    let mut payloads = Vec::new();
    for (i, w) in g.chunks(2).enumerate() {
        let p = u64::from(w[0]) | (u64::from(w[1]) << 32);
        if p != u64::MAX {
            per_layer[i / pixels] += 1;
            payloads.push(p);
        }
    }
    (per_layer, payloads)
}

#[test]
fn a_segment_covers_about_its_area_in_every_sample_layer() {
    let f = frame(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 40.0, W, H);
    // Slanted, so that at one sample it crosses rows of pixel centres.
    let s = segment(&f, 0.3, 0.0);
    let length = {
        let px = |c: Vec4| Vec2::new(c.x / c.w * W as f32, c.y / c.w * H as f32) * 0.5;
        (px(s.b) - px(s.a)).length() + 0.5
    };
    for samples in [1usize, 4, 8] {
        let hs = draw(&[s], samples, 1.0, 0);
        let (per_layer, payloads) = covered(&hs);
        let total: usize = per_layer.iter().sum();
        // A 0.5-pixel-wide quad: half a sample per pixel along its length.
        let expected = 0.5 * length * samples as f32;
        assert!(
            (total as f32 - expected).abs() < 0.25 * expected,
            "{samples}: {total} samples, about {expected} expected"
        );
        assert!(per_layer[samples..].iter().all(|&n| n == 0));
        // w runs from 0 at end a to 1 at end b; u and v are the segment's.
        let w: Vec<f32> = payloads.iter().map(|&p| unpack(p).uvw[2]).collect();
        assert!(w.iter().any(|&x| x < 0.2) && w.iter().any(|&x| x > 0.8));
        assert!(
            payloads
                .iter()
                .all(|&p| (unpack(p).uvw[1] - 7.0 / 63.0).abs() < 1e-6)
        );
    }
}

#[test]
fn the_head_hides_strands_behind_it() {
    let f = frame(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 40.0, W, H);
    let s = segment(&f, 0.0, 0.0);
    let z = {
        let c = s.a;
        c.z / c.w
    };
    let (in_front, _) = covered(&draw(&[s], 4, z + 0.01, 0));
    let (behind, _) = covered(&draw(&[s], 4, z - 0.01, 0));
    assert!(in_front.iter().sum::<usize>() > 0);
    assert_eq!(behind.iter().sum::<usize>(), 0);
}

#[test]
fn the_nearest_strand_wins_in_either_draw_order() {
    let f = frame(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 40.0, W, H);
    let near = segment(&f, 0.0, 0.2);
    let far = segment(&f, 0.0, -0.2);
    let a = draw(&[near, far], 4, 1.0, 0).read("gbuffer");
    let b = draw(&[far, near], 4, 1.0, 0).read("gbuffer");
    assert_eq!(a, b);
    let (_, payloads) = covered(&draw(&[far, near], 4, 1.0, 0));
    let nearest = unpack(*payloads.iter().min().unwrap()).depth;
    assert!(
        payloads
            .iter()
            .all(|&p| (unpack(p).depth - nearest).abs() < 1e-3)
    );
}

#[test]
fn later_grooms_test_earlier_grooms_depth() {
    let f = frame(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 40.0, W, H);
    // hair_depth is 0.5 (NDC) everywhere; a strand at z = 0 lies behind it.
    let s = segment(&f, 0.0, 0.0);
    assert!(s.a.z / s.a.w > 0.5);
    let (first, _) = covered(&draw(&[s], 4, 1.0, 0));
    let (second, _) = covered(&draw(&[s], 4, 1.0, 1));
    assert!(first.iter().sum::<usize>() > 0);
    assert_eq!(second.iter().sum::<usize>(), 0);
}
