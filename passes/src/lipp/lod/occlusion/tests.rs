use super::*;
use crate::kernel::harness::Harness;
use crate::lipp::assemble::{Assembly, assemble};
use crate::lipp::{LAYER_WORDS, LOD_CULLED, pcg, unit};
use std::sync::atomic::{AtomicU32, AtomicU64};
use strandgraph_graph::Quantities;

/// Packed layers (`hairmesh.layers` words) from corner positions.
fn pack(layers: &[[V3; 4]]) -> Vec<u32> {
    let mut words = Vec::new();
    for (i, quad) in layers.iter().enumerate() {
        let w = i as f32 / (layers.len() - 1) as f32;
        for p in quad {
            words.extend([p[0], p[1], p[2], 1.0, 0.0, -1.0, 0.0, w].map(f32::to_bits));
        }
    }
    assert_eq!(words.len(), layers.len() * LAYER_WORDS);
    words
}

fn atoms(words: Vec<u32>) -> Vec<AtomicU32> {
    words.into_iter().map(AtomicU32::new).collect()
}

/// A random styled bundle: a bent chain of tilted quads.
fn random_bundle(seed: u32) -> (Vec<[V3; 4]>, BundleRecord) {
    let mut h = seed;
    let mut r = move |lo: f32, hi: f32| {
        h = pcg(h);
        lo + (hi - lo) * unit(h)
    };
    let n = 2 + (r(0.0, 7.0) as usize);
    let mut centre = [0.0f32; 3];
    let mut layers = Vec::new();
    for _ in 0..n {
        let (a, b) = (
            [r(0.002, 0.02), r(-0.01, 0.01), r(-0.01, 0.01)],
            [r(-0.01, 0.01), r(-0.01, 0.01), r(0.002, 0.02)],
        );
        let at = |s: f32, t: f32| [0, 1, 2].map(|i| centre[i] + a[i] * s + b[i] * t);
        layers.push([at(-1.0, -1.0), at(1.0, -1.0), at(1.0, 1.0), at(-1.0, 1.0)]);
        centre = [
            centre[0] + r(-0.05, 0.05),
            centre[1] - r(0.01, 0.08),
            centre[2] + r(-0.05, 0.05),
        ];
    }
    let rec = BundleRecord {
        layer_count: n as u32,
        strands: 64,
        curl_radius: r(0.0, 0.006),
        curl_turns: r(0.0, 8.0),
        twist: r(-1.0, 1.0),
        noise: r(0.0, 0.006),
        seed,
        ..Default::default()
    };
    (layers, rec)
}

/// Every segment the rasterizer can draw inside a Hermite piece lies in
/// that piece's box, one across a layer in the box around both pieces, at
/// every control-point count (some below the layer count: one box then).
#[test]
fn the_boxes_hold_every_segment_assembly_draws() {
    let oob = AtomicU64::new(0);
    for seed in 0..60 {
        let (quads, rec) = random_bundle(seed * 7919 + 1);
        let words = atoms(pack(&quads));
        let layers = Words::new(&words, &oob);
        let inside = |p: V3, (lo, hi): (V3, V3)| (0..3).all(|a| lo[a] <= p[a] && p[a] <= hi[a]);
        let opts = Assembly {
            width: 32,
            cooperative: true,
            styling: true,
        };
        let n = rec.layers();
        let piece = |w: f32| ((w * (n - 1) as f32).floor() as usize).min(n as usize - 2);
        for c in [3, 5, 9, 33, 127] {
            let boxes = bundle_boxes(&layers, &rec, c);
            let lod = BundleLod {
                strands: rec.strands,
                control_points: c,
                ..Default::default()
            };
            for k in 0..rec.strands {
                assemble(&layers, &rec, &lod, k, &opts, &mut |a, _, b, _| {
                    let (i, j) = (piece(a.w), piece(b.w));
                    let bx = if c < n {
                        boxes[0]
                    } else if i == j {
                        boxes[i]
                    } else {
                        assert_eq!(j, i + 1, "a chord spans at most one layer");
                        union(boxes[i], boxes[j])
                    };
                    assert!(
                        inside(a.pos, bx) && inside(b.pos, bx),
                        "seed {seed}, C {c}, strand {k}: segment {:?} -> {:?} outside {bx:?}",
                        a.pos,
                        b.pos
                    );
                });
            }
        }
    }
}

/// clip = world (w = 1) on a 1000 × 1000 screen: x, y in [−1, 1] cover it.
fn flat_frame() -> FrameData {
    let mut f: FrameData = bytemuck::Zeroable::zeroed();
    for i in 0..4 {
        f.view_proj[i * 5] = 1.0;
    }
    f.screen = [1000.0, 1000.0, 1e-3, 1e-3];
    f.near = 0.1;
    f
}

/// 63 × 63 blocks of farthest depth `far`, with block (bx, by) at `hole`.
fn hiz(far: f32, hole: Option<(usize, usize, f32)>) -> Vec<u32> {
    let mut v = vec![far.to_bits(); 63 * 63];
    if let Some((bx, by, d)) = hole {
        v[by * 63 + bx] = d.to_bits();
    }
    v
}

#[test]
fn a_box_is_hidden_only_behind_every_block_it_covers() {
    let (f, oob) = (flat_frame(), AtomicU64::new(0));
    let wall = atoms(hiz(0.5, None));
    let wall = Words::new(&wall, &oob);
    let behind = ([-0.1, -0.1, 0.8], [0.1, 0.1, 0.9]);
    assert!(box_hidden(&f, &wall, behind.0, behind.1));
    assert!(
        !box_hidden(&f, &wall, [-0.1, -0.1, 0.3], [0.1, 0.1, 0.9]),
        "nearer than the wall"
    );
    // The screen centre, block (31, 31), shows the background.
    let holed = atoms(hiz(0.5, Some((31, 31, 1.0))));
    assert!(!box_hidden(
        &f,
        &Words::new(&holed, &oob),
        behind.0,
        behind.1
    ));
    // The same hole away from the box changes nothing.
    let far_hole = atoms(hiz(0.5, Some((2, 2, 1.0))));
    assert!(box_hidden(
        &f,
        &Words::new(&far_hole, &oob),
        behind.0,
        behind.1
    ));
    // Off screen: hidden whatever the depth; across the near plane: never.
    let open = atoms(hiz(1.0, None));
    let open = Words::new(&open, &oob);
    assert!(box_hidden(&f, &open, [2.0, 0.0, 0.2], [3.0, 0.5, 0.3]));
    let mut near = f;
    near.near = 2.0;
    assert!(!box_hidden(&near, &wall, behind.0, behind.1));
}

#[test]
fn the_kernel_flags_hidden_bundles_and_keeps_their_counts() {
    // Bundle 0 behind the wall, bundle 1 in front of it, bundle 2 behind
    // but already frustum-culled.
    let quad = |z: f32| {
        [
            [-0.1, -0.1, z],
            [0.1, -0.1, z],
            [0.1, 0.1, z],
            [-0.1, 0.1, z],
        ]
    };
    let mut layers = Vec::new();
    let mut bundles = Vec::new();
    for (b, z) in [0.8f32, 0.3, 0.8].into_iter().enumerate() {
        layers.extend(pack(&[quad(z), quad(z + 0.01)]));
        let rec = BundleRecord {
            first_layer: 2 * b as u32,
            layer_count: 2,
            strands: 50,
            ..Default::default()
        };
        bundles.extend(rec.words());
    }
    let choices = vec![40, 33, 0, 0, 40, 33, 0, 0, 40, 33, 0, LOD_CULLED];
    let frame: Vec<u32> = bytemuck::cast_slice(&[flat_frame()]).to_vec();
    for enabled in [true, false] {
        let mut h = Harness::new(Quantities {
            bundles: 3,
            width: 1000,
            height: 1000,
            ..Default::default()
        });
        h.buffer("frame", frame.clone())
            .buffer("hairmesh.bundles", bundles.clone())
            .buffer("hairmesh.layers", layers.clone())
            .buffer("hiz", hiz(0.5, None))
            .buffer("lod_choices", choices.clone())
            .buffer("lod_visible", vec![0; choices.len()]);
        h.run(&OcclusionKernel(OcclusionParams { enabled }), 1, GROUP);
        let visible = h.read("lod_visible");
        let flags: Vec<u32> = visible.chunks(4).map(|w| w[3]).collect();
        let expect = if enabled {
            [LOD_OCCLUDED, 0, LOD_CULLED]
        } else {
            [0, 0, LOD_CULLED]
        };
        assert_eq!(flags, expect, "enabled: {enabled}");
        assert!(
            visible.chunks(4).all(|w| w[..3] == [40, 33, 0]),
            "N_LOD and C kept"
        );
    }
}

#[test]
fn a_segment_is_hidden_inside_a_hidden_piece() {
    let flags = |mask: u32| mask << BOX_BITS_SHIFT;
    // 8 layers: pieces 0..=6, w in sevenths.
    let at = |i: f32| i / 7.0;
    assert!(!segment_hidden(0, 8, at(3.2), at(3.4)), "nothing hidden");
    assert!(segment_hidden(flags(1 << 3), 8, at(3.2), at(3.4)));
    assert!(!segment_hidden(flags(1 << 3), 8, at(4.2), at(4.4)));
    assert!(
        !segment_hidden(flags(0b11 << 3), 8, at(3.8), at(4.2)),
        "across layer 4"
    );
    // The tip's w of 1 is in the last piece.
    assert!(segment_hidden(flags(1 << 6), 8, at(6.5), 1.0));
    assert!(segment_hidden(flags(1), 2, 0.2, 1.0));
}
