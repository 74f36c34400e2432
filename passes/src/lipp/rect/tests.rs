use super::*;
use crate::lipp::assemble::{Assembly, assemble};
use crate::lipp::{BundleLod, LAYER_WORDS};
use std::sync::atomic::{AtomicU32, AtomicU64};

#[test]
fn tiles_round_outwards_and_unpack_to_pixels() {
    let (w, h) = (1920, 1080);
    assert_eq!(granularity(w, h), 8);
    assert_eq!(granularity(3840, 2160), 16);
    assert_eq!(granularity(8, 8), 8);
    let r = Rect {
        x0: 17,
        y0: 3,
        x1: 101,
        y1: 1080,
    };
    let back = Rect::unpack_tiles(r.pack_tiles(w, h), w, h);
    assert_eq!(
        back,
        Rect {
            x0: 16,
            y0: 0,
            x1: 104,
            y1: 1080
        }
    );
    // The screen's edge is a tile edge past it, clamped back.
    let full = Rect::full(1000, 700);
    assert_eq!(
        Rect::unpack_tiles(full.pack_tiles(1000, 700), 1000, 700),
        full
    );
    assert_eq!(Rect::EMPTY.pack_tiles(w, h), 0);
    assert!(Rect::unpack_tiles(0, w, h).is_empty());
    assert_eq!(Rect::from_args(r.args()[0], r.args()[1]), r);
}

#[test]
fn a_union_ignores_empty_rectangles() {
    let a = Rect {
        x0: 5,
        y0: 6,
        x1: 10,
        y1: 20,
    };
    let b = Rect {
        x0: 1,
        y0: 8,
        x1: 7,
        y1: 30,
    };
    assert_eq!(Rect::EMPTY.union(a), a);
    assert_eq!(a.union(Rect::EMPTY), a);
    assert_eq!(
        a.union(b),
        Rect {
            x0: 1,
            y0: 6,
            x1: 10,
            y1: 30
        }
    );
}

#[test]
fn runs_of_pixels_touch_the_rectangle_where_they_share_a_pixel() {
    let r = Rect {
        x0: 100,
        y0: 10,
        x1: 200,
        y1: 20,
    };
    let w = 640;
    // Row 10, pixels 36..100: the last one is x = 99, outside.
    assert!(!r.touches_run(10 * w + 36, 64, w));
    assert!(r.touches_run(10 * w + 37, 64, w));
    assert!(r.touches_run(19 * w + 199, 64, w));
    assert!(!r.touches_run(19 * w + 200, 64, w));
    assert!(!r.touches_run(20 * w + 150, 64, w));
    assert!(!r.touches_run(9 * w + 150, 64, w));
    // A run over two rows, one of them in the rectangle's: conservatively yes.
    assert!(r.touches_run(10 * w - 10, 64, w));
    assert!(
        r.touches_run(20 * w - 10, 64, w),
        "row 19's end, x = 630..640"
    );
    assert!(!r.touches_run(21 * w - 10, 64, w), "rows 20 and 21");
    // Every pixel inside is in a touching run.
    for y in r.y0..r.y1 {
        for x in [r.x0, r.x1 - 1] {
            let i = y * w + x;
            assert!(r.touches_run(i - i % 64, 64, w), "({x}, {y})");
        }
    }
}

/// However many workgroups a pass is dispatched with (a run each, the
/// scan's `clear_runs`, or the cap past 65,535), their blocks take every
/// run the rectangle touches exactly once.
#[test]
fn blocks_of_runs_take_every_touching_run_once() {
    let r = Rect {
        x0: 70,
        y0: 3,
        x1: 613,
        y1: 41,
    };
    let w = 640;
    let (first, runs) = r.runs(w);
    let one_each: Vec<u32> = (first..first + runs)
        .filter(|&run| r.touches_run(run * TILE, TILE, w))
        .collect();
    assert!(one_each.len() > 1 && one_each.len() < runs as usize);
    for per in [1, 2, 7, 8, runs - 1, runs, runs + 5] {
        let [groups, y, z] = r.run_dispatch(w, per);
        assert_eq!(
            (groups, y, z),
            (runs.div_ceil(per), 1, 1),
            "{per} runs a group"
        );
        let mut taken: Vec<u32> = (0..groups)
            .flat_map(|g| r.runs_of_group(w, g, groups))
            .collect();
        taken.sort_unstable();
        assert_eq!(taken, one_each, "{per} runs a group");
    }
    // Fewer workgroups than asked for (the dispatch's cap): still all.
    let mut taken: Vec<u32> = (0..3).flat_map(|g| r.runs_of_group(w, g, 3)).collect();
    taken.sort_unstable();
    assert_eq!(taken, one_each);
    assert_eq!(Rect::EMPTY.run_dispatch(w, 8), [0, 1, 1]);
}

/// A bundle of `n` layers, twisted, curled and noisy, its layers' quads
/// uneven and bent, in `words`.
fn styled_bundle(n: u32, seed: u32) -> (Vec<AtomicU32>, BundleRecord) {
    let mut words = Vec::new();
    let h = |i: u32| crate::lipp::unit(crate::lipp::pcg(seed ^ i.wrapping_mul(0x9E37_79B9)));
    for i in 0..n {
        let y = -(i as f32) * 0.05;
        let bend = 0.02 * (i as f32).powi(2) * h(i);
        for (k, c) in [[0.0, 0.0], [0.03, 0.0], [0.03, 0.02], [0.0, 0.02]]
            .iter()
            .enumerate()
        {
            let j = 0.01 * h(100 + 4 * i + k as u32);
            let w = i as f32 / (n - 1) as f32;
            words.extend(
                [c[0] + bend + j, y, c[1] - bend, 1.0, 0.0, -1.0, 0.0, w].map(f32::to_bits),
            );
        }
    }
    assert_eq!(words.len(), n as usize * LAYER_WORDS);
    let b = BundleRecord {
        layer_count: n,
        strands: 64,
        curl_radius: 0.004 * h(1),
        curl_turns: 6.0 * h(2),
        twist: 1.5 * h(3),
        noise: 0.003 * h(4),
        seed,
        ..Default::default()
    };
    (words.into_iter().map(AtomicU32::new).collect(), b)
}

#[test]
fn the_bundle_box_holds_every_segment_the_rasterizer_draws() {
    let oob = AtomicU64::new(0);
    for seed in 0..24u32 {
        let n = 2 + seed % 15;
        let (atoms, b) = styled_bundle(n, seed);
        let layers = Words::new(&atoms, &oob);
        let (lo, hi) = bundle_box(&layers, &b);
        let inside = |p: [f32; 3]| (0..3).all(|a| p[a] >= lo[a] && p[a] <= hi[a]);
        let opts = Assembly {
            width: 32,
            cooperative: true,
            styling: true,
            max_strip: 4,
        };
        for c in [3, 5, 9, 17, 33, 65, 129] {
            let lod = BundleLod {
                strands: b.strands,
                control_points: c,
                first_strand: 0,
                flags: 0,
            };
            for k in 0..b.strands {
                assemble(&layers, &b, &lod, k, &opts, &mut |a, _, e, _| {
                    assert!(
                        inside(a.pos) && inside(e.pos),
                        "seed {seed}, C {c}, strand {k}: {:?} {:?} outside {lo:?}..{hi:?}",
                        a.pos,
                        e.pos
                    );
                });
            }
        }
    }
    assert_eq!(oob.into_inner(), 0);
}

#[test]
fn a_box_reaching_behind_the_camera_covers_the_screen() {
    use bytemuck::Zeroable;
    let mut f = FrameData::zeroed();
    for i in 0..4 {
        f.view_proj[i * 5] = 1.0;
    }
    f.screen = [800.0, 600.0, 1.0 / 800.0, 1.0 / 600.0];
    f.near = 0.1;
    // clip = world, w = 1 > near: NDC ±0.5 is the middle half, grown by PAD.
    let r = screen_rect(&f, [-0.5, -0.5, 0.0], [0.5, 0.5, 0.5]);
    assert_eq!(
        r,
        Rect {
            x0: 198,
            y0: 148,
            x1: 602,
            y1: 452
        }
    );
    // Make w depend on z: a corner at w <= near.
    f.view_proj[11] = 1.0;
    f.view_proj[15] = 0.0;
    assert_eq!(
        screen_rect(&f, [-0.5, -0.5, 0.05], [0.5, 0.5, 1.0]),
        Rect::full(800, 600)
    );
}
