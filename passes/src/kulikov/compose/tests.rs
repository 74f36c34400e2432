//! The coverage fit against randomly placed opaque lines (the talk's own
//! derivation), the reconstruction, and the model order.

use super::reconstruct::{Layer, reconstruct};
use super::*;
use crate::kulikov::payload::total_coverage;

/// xorshift32 in [0, 1).
fn rand(s: &mut u32) -> f32 {
    *s ^= *s << 13;
    *s ^= *s >> 17;
    *s ^= *s << 5;
    (*s >> 8) as f32 / (1 << 24) as f32
}

/// Kulikov, "Coverage layer": "numerically simulate total coverage as a
/// function of additive coverage by drawing a bunch of opaque lines and
/// calculating precise total coverage after each line is drawn". Lines of one
/// width (0.2 px, "a typical strand covers about 20-25% of pixel area")
/// through random points of a pixel at random angles, measured on a 48×48
/// sample grid; the shipped quadratic stays within 0.16 of the simulated
/// mean over x in [0, 4], and errs on the opaque side.
#[test]
fn quadratic_fit_tracks_randomly_placed_opaque_lines() {
    const N: usize = 48;
    const BINS: usize = 16; // x in [0, 4), 0.25 wide
    let mut sum = [0.0f64; BINS];
    let mut cnt = [0u32; BINS];
    let mut s = 0x1234_5678u32;
    for _pixel in 0..400 {
        let mut covered = vec![false; N * N];
        let mut additive = 0.0f32;
        for _line in 0..40 {
            let (px, py) = (rand(&mut s), rand(&mut s));
            let a = rand(&mut s) * std::f32::consts::PI;
            let (nx, ny) = (-a.sin(), a.cos());
            let mut hits = 0;
            for j in 0..N {
                for i in 0..N {
                    let (x, y) = ((i as f32 + 0.5) / N as f32, (j as f32 + 0.5) / N as f32);
                    if ((x - px) * nx + (y - py) * ny).abs() < 0.1 {
                        hits += 1;
                        covered[j * N + i] = true;
                    }
                }
            }
            additive += hits as f32 / (N * N) as f32;
            let b = (additive / 0.25) as usize;
            if b >= BINS {
                break;
            }
            let total = covered.iter().filter(|c| **c).count() as f64 / (N * N) as f64;
            let fit = total_coverage((additive * COVERAGE_SCALE).round() as u32);
            sum[b] += f64::from(fit) - total;
            cnt[b] += 1;
        }
    }
    let mut worst = 0.0f32;
    for b in 0..BINS {
        if cnt[b] < 20 {
            continue;
        }
        let x = (b as f32 + 0.5) * 0.25;
        // Mean of fit(x) − simulated over the samples with x in this bin.
        let err = (sum[b] / f64::from(cnt[b])) as f32;
        worst = worst.max(err.abs());
        assert!(err > -0.05, "x ~{x}: fit below the simulation by {err}");
        assert!(err.abs() < 0.16, "x ~{x}: fit off the simulation by {err}");
    }
    assert!(worst > 0.0, "no bin was filled");
    eprintln!("quadratic fit vs simulated lines: worst mean error {worst:.3}");
}

#[test]
fn reconstruction_reaches_full_opacity_in_dense_regions() {
    let l = |c, v| Layer {
        coverage: c,
        lighting: [v; 3],
    };
    let layers = [l(0.25, 1.0), l(0.25, 2.0), l(0.25, 3.0)];
    // 16 strands of a quarter pixel each: x = 4, the fit saturates.
    let (hair, alpha) = reconstruct(&layers, total_coverage(4096), true);
    assert_eq!(alpha, 1.0);
    let c_front = 1.0 - 0.75f32.powi(3);
    let front = 0.25 * 1.0 + 0.75 * 0.25 * 2.0 + 0.75 * 0.75 * 0.25 * 3.0;
    let w = [0.25 / 16.0, 0.25 / 4.0, 0.25];
    let avg = (w[0] * 1.0 + w[1] * 2.0 + w[2] * 3.0) / (w[0] + w[1] + w[2]);
    assert!(
        (hair[0] - (front + (1.0 - c_front) * avg)).abs() < 1e-5,
        "{hair:?}"
    );
    // Without reconstruction the front layers alone stay translucent.
    let (_, front_only) = reconstruct(&layers, 1.0, false);
    assert!((front_only - c_front).abs() < 1e-6);
    // A single thin strand: the fit is below its coverage, nothing is missing.
    let (h, a) = reconstruct(&[l(0.5, 2.0)], total_coverage(512), true);
    assert_eq!((h[0], a), (1.0, 0.5));
}

#[test]
fn facial_hair_composes_before_the_main_hair() {
    use crate::layout::{FrameData, ModelData};
    use bytemuck::Zeroable;
    let mut frame = FrameData::zeroed();
    frame.camera_pos = [0.0, 0.0, 2.0, 1.0];
    let model = |z: f32, flags: u32| {
        let mut m = ModelData::zeroed();
        m.bounds_min = [-0.1, -0.1, z - 0.1, 0.0];
        m.bounds_max = [0.1, 0.1, z + 0.1, 0.0];
        m.flags = flags;
        m
    };
    // Main hair behind the head centre, beard in front of it.
    let scene = Scene {
        frame,
        models: vec![
            model(-0.1, 0),
            model(0.1, MODEL_FACIAL_HAIR),
            model(-1.0, 0),
        ],
    };
    assert_eq!(model_order(&scene, 0.0), vec![2, 0, 1]);
    assert_eq!(model_order(&scene, 0.5), vec![2, 1, 0]);
    assert!(
        (ndc_depth(3.0, 0.02, 500.0) - {
            let p = glam::Mat4::perspective_rh(1.0, 1.0, 0.02, 500.0);
            let c = p * glam::Vec4::new(0.0, 0.0, -3.0, 1.0);
            c.z / c.w
        })
        .abs()
            < 1e-5
    );
}

/// The workgroup cull drops a model only where no pixel of the workgroup
/// can sample its tiles, jitter included: every (tiles, workgroup) pair
/// where some pixel's sample lands in the tiles is kept.
#[test]
fn workgroup_cull_keeps_every_model_a_pixel_can_sample() {
    use super::{GROUP, group_span, reaches, sample_at};
    use crate::kulikov::tile_alloc::ModelTiles;
    let (width, height) = (333u32, 190u32);
    let mut kept_elsewhere = 0;
    for (ox, oy, gw, gh, d) in [
        (0, 0, 1, 1, 1),
        (1, 1, 1, 1, 2),
        (0, 1, 2, 1, 4),
        (2, 0, 1, 2, 3),
        (1, 0, 1, 1, 8),
    ] {
        let t = ModelTiles {
            first_tile: 0,
            grid_w: gw,
            grid_h: gh,
            origin_x: ox,
            origin_y: oy,
            downscale: d,
            valid: 1,
        };
        for group in 0..(width * height).div_ceil(GROUP) {
            let span = group_span(group, width, height);
            let sampled = (group * GROUP..((group + 1) * GROUP).min(width * height)).any(|i| {
                let (sx, sy) = sample_at(i % width, i / width, d, 8, width, height);
                t.texel(sx, sy).is_some()
            });
            if sampled {
                assert!(reaches(&t, span), "{t:?} group {group} {span:?}");
            } else if reaches(&t, span) {
                kept_elsewhere += 1;
            }
        }
    }
    // Conservative, but not everything: most workgroups are dropped.
    assert!(
        kept_elsewhere < 200,
        "{kept_elsewhere} workgroups kept needlessly"
    );
}
