//! Three-way differential test of the Lipp graph (`scenes/graphs/lipp.ron`):
//! the CPU simulator (the reference), wgpu and ash (lavapipe in CI; ash
//! under the Khronos validation layer with synchronization validation) run
//! the same WGSL-described passes on a small groom (the mid view's camera and
//! hair mesh style and studio environment map, 8,000 strands in 128
//! bundles, at 200×120).
//!
//! Gates:
//! - `bundle_lod` and `raster_args` (integer decisions from float screen
//!   bounds) identical on at least 99% of bundles, strand totals within 1%;
//! - G-buffer coverage: per layer, pixels covered on one side and not the
//!   other at most 2% of those covered on either (strand positions are float
//!   math before the 1/256-pixel snap; a different ULP in sin/cos can move a
//!   sample across a pixel or centre-distance boundary);
//! - on pixels both cover, depth (24 bits) within 1e-4 on 98%;
//! - deep opacity maps: texels hit by one side only at most 2%, first-hit
//!   depths within 1e-4 on 98%, total opacity within 2%;
//! - `output.final` within a mean FLIP of 0.02 of the CPU, each GPU backend;
//! - ash with memory aliasing gives the same image as without.
//!
//! No device or no validation layer is a failure, not a skip.

use std::path::PathBuf;
use strandgraph::frame::{Prepared, override_param, prepare};
use strandgraph_passes::lipp::rect::{ARGS_RECT_HI, ARGS_RECT_LO, Rect};
use strandgraph_passes::lipp::tiles::{filter_groups, filter_lanes};
use strandgraph_passes::lipp::{ARGS_BUNDLES_HI, ARGS_BUNDLES_LO};

mod common;
use common::{ash, ash_with, check_flip, cpu, out_dir, read_ash, root, wgpu, wgpu_with};

const W: u32 = 200;
const H: u32 = 120;
const MAX_MEAN_FLIP: f32 = 0.02;

/// The mid view with a small groom, written next to the other outputs.
const BEARD: &str = r#", (
        name: "beard",
        source: HairMesh(style: Beard, strands: 3000, points: 8, seed: 13),
        parent: "head",
        hair_mesh: (bundles: 64, layers: 4, style: (curl_radius: 0.001, curl_turns: 3.0, twist: 0.5, noise: 0.002)),
        material: (color: (0.30, 0.09, 0.03), roughness: 0.35),
        facial_hair: true,
    )"#;

/// With `beard`, a second groom drawn after the hair (Lipp §3.5).
fn small_scene(tag: &str, beard: bool) -> PathBuf {
    let graph = root().join("scenes/graphs/lipp.ron");
    // The studio map, so the prefiltered lookup is compared (a constant
    // environment would make every probe texel the same).
    let map = root().join("scenes/env/studio.exr");
    // The mid view; with the beard, scenes/grooms.ron's three-quarter view,
    // where the beard shows between the strands of the hair's curtain.
    let (camera, beard) = if beard {
        (
            "LookAt(position: (0.42, 1.62, 0.78), target: (0.0, 1.52, 0.0), fov_deg: 35.0)",
            BEARD,
        )
    } else {
        (
            "Orbit(target: (0.0, 1.5, 0.0), distance: 1.5, yaw_deg: 25.0, pitch_deg: 5.0, fov_deg: 40.0)",
            "",
        )
    };
    let text = format!(
        r#"Scene(
    resolution: ({W}, {H}),
    camera: {camera},
    lights: [Directional(direction: (0.3, -0.7, -0.6), color: (1.0, 0.97, 0.92), intensity: 3.0)],
    environment: (color: (1.0, 1.0, 1.0), intensity: 0.5, map: {map:?}),
    meshes: [(name: "head", source: Head(resolution: 48), transform: (translation: (0.0, 1.6, 0.0)))],
    grooms: [(
        name: "small",
        source: HairMesh(style: Long, strands: 8000, points: 16, seed: 7),
        parent: "head",
        hair_mesh: (bundles: 128, layers: 8, style: (curl_radius: 0.002, curl_turns: 5.0, twist: 0.25, noise: 0.003)),
        material: (melanin: 0.4, roughness: 0.3),
    ){beard}],
    graph: {graph:?},
)
"#
    );
    // One file per test: tests run in parallel.
    let path = out_dir("diff_lipp").join(format!("small_{tag}.ron"));
    std::fs::write(&path, text).unwrap();
    path
}

/// Per G-buffer layer, over the groom's screen rectangle `r` (outside it
/// `lipp.clear_gbuffer` leaves the buffer as it was: passes/src/lipp/rect.rs):
/// (covered by exactly one side, covered by either, covered by both, both
/// covered with depth within 1e-4, bit-identical).
fn gbuffer_agreement(a: &[u32], b: &[u32], r: &Rect) -> Vec<(usize, usize, usize, usize, usize)> {
    let pixels = (W * H) as usize;
    let layers = a.len() / (2 * pixels);
    assert_eq!(a.len(), b.len());
    (0..layers)
        .map(|layer| {
            let (mut one, mut either, mut both, mut close, mut exact) = (0, 0, 0, 0, 0);
            for i in 0..pixels {
                if !r.contains(i as u32 % W, i as u32 / W) {
                    continue;
                }
                let slot = layer * pixels + i;
                let pa = u64::from(a[2 * slot]) | (u64::from(a[2 * slot + 1]) << 32);
                let pb = u64::from(b[2 * slot]) | (u64::from(b[2 * slot + 1]) << 32);
                let (ca, cb) = (pa != u64::MAX, pb != u64::MAX);
                if !(ca || cb) {
                    continue;
                }
                either += 1;
                if ca != cb {
                    one += 1;
                    continue;
                }
                both += 1;
                let depth = |p: u64| (p >> 40) as f64 / 16_777_215.0;
                close += usize::from((depth(pa) - depth(pb)).abs() <= 1e-4);
                exact += usize::from(pa == pb);
            }
            (one, either, both, close, exact)
        })
        .collect()
}

/// `min_covered`: pixels a layer must cover for the comparison to mean
/// something; `args`: the groom's `raster_args` on the CPU (its rectangle).
fn check_gbuffer(label: &str, reference: &[u32], test: &[u32], args: &[u32], min_covered: usize) {
    let r = Rect::from_args(args[ARGS_RECT_LO], args[ARGS_RECT_HI]);
    for (layer, (one, either, both, close, exact)) in gbuffer_agreement(reference, test, &r)
        .into_iter()
        .enumerate()
    {
        eprintln!(
            "gbuffer layer {layer} {label}: covered by one side {one} of {either}, depth close on {close} of {both}, payload bit-identical on {exact}"
        );
        assert!(
            either > min_covered,
            "layer {layer}: only {either} covered pixels"
        );
        assert!(
            one as f64 <= 0.02 * either as f64,
            "{label} layer {layer}: coverage differs on {one} of {either}"
        );
        assert!(
            close as f64 >= 0.98 * both as f64,
            "{label} layer {layer}: depth differs on {} of {both}",
            both - close
        );
    }
}

/// Deep opacity maps: texels hit on one side only at most 2% of those hit,
/// first-hit depths within 1e-4 on 98% of both-hit texels, total opacity
/// within 2%.
fn check_dom(label: &str, depth_a: &[u32], layers_a: &[u32], depth_b: &[u32], layers_b: &[u32]) {
    assert_eq!(depth_a.len(), depth_b.len());
    let (mut one, mut either, mut both, mut close) = (0, 0, 0, 0);
    for (a, b) in depth_a.iter().zip(depth_b) {
        let (ha, hb) = (*a != u32::MAX, *b != u32::MAX);
        if !(ha || hb) {
            continue;
        }
        either += 1;
        if ha != hb {
            one += 1;
            continue;
        }
        both += 1;
        close += usize::from((f32::from_bits(*a) - f32::from_bits(*b)).abs() <= 1e-4);
    }
    let sum = |v: &[u32]| v.iter().map(|&x| u64::from(x)).sum::<u64>() as f64;
    let (sa, sb) = (sum(layers_a), sum(layers_b));
    eprintln!(
        "dom {label}: texels hit by one side {one} of {either}, depth close on {close} of {both}; \
         opacity sums {sa} vs {sb}"
    );
    assert!(either > 1000, "{label}: only {either} DOM texels hit");
    assert!(one as f64 <= 0.02 * either as f64, "{label}: DOM coverage");
    assert!(close as f64 >= 0.98 * both as f64, "{label}: DOM depths");
    assert!((sa - sb).abs() <= 0.02 * sa, "{label}: DOM opacity sums");
}

/// `bundle_lod` over the bundles of the groom it was scanned for (`args`,
/// its `raster_args` on the CPU: lipp::ARGS_BUNDLES_LO); the scan leaves the
/// others' records as they were.
fn check_lod(label: &str, args: &[u32], reference: &[u32], test: &[u32]) {
    let range = args[ARGS_BUNDLES_LO] as usize..args[ARGS_BUNDLES_HI] as usize;
    let bundles = range.len();
    let same = range
        .filter(|&b| reference[4 * b..4 * b + 4] == test[4 * b..4 * b + 4])
        .count();
    eprintln!("bundle_lod {label}: {same} of {bundles} bundles identical");
    assert!(bundles > 0, "{label}: no bundles scanned");
    assert!(same as f64 >= 0.99 * bundles as f64, "{label}: bundle_lod");
}

#[test]
fn lipp_graph_matches_on_cpu_wgpu_and_ash() {
    run(None, false);
}

/// The MSAA reference mode (`scenes/graphs/lipp_msaa.ron`, 8 sample layers).
#[test]
fn lipp_msaa_graph_matches_on_cpu_wgpu_and_ash() {
    run(Some("scenes/graphs/lipp_msaa.ron"), false);
}

/// Two grooms drawn one after another (the per-model block): the second
/// groom's G-buffer, rejected against the first's hair depth, and the image.
#[test]
fn lipp_two_grooms_match_on_cpu_wgpu_and_ash() {
    run(None, true);
}

/// `lipp.filter`'s lanes a pixel (ours, passes/src/lipp/tiles.rs) split
/// each window's sums, not what is summed: on ash, the sixteen lanes the
/// small groom's few tiles get (at most the subgroup's: eight on lavapipe),
/// then four, two, one, and two again through a dispatch of a workgroup a
/// tile, give the same image up to the order of the additions (a few
/// half-float steps), and each dispatch is the one the shade pass's budget
/// sized.
#[test]
fn the_filters_lanes_change_only_the_order_of_its_sums() {
    let mut p = prepare(&small_scene("lanes", false), None, Some((W, H)))
        .unwrap_or_else(|e| panic!("{e:?}"));
    let frame = |p: &Prepared| {
        let s = ash(p, false);
        (read_ash(&s, "output"), read_ash(&s, "filter_args"))
    };
    let (widest, args) = frame(&p);
    let tiles = args[3];
    assert!(tiles > 0, "no tiles listed: {args:?}");
    assert_eq!(args[0], filter_groups(tiles, 1 << 19), "{args:?}");
    assert_eq!(
        filter_lanes(args[0], tiles, 16),
        16,
        "{tiles} tiles, {args:?}"
    );
    for (set, groups) in [
        ("filter.lanes=4", args[0]),
        ("filter.lanes=2", args[0]),
        ("filter.lanes=1", args[0]),
        ("filter.lanes=8", args[0]),
        ("filter.lanes=16", args[0]),
        ("shade.filter_lane_budget=0", tiles),
    ] {
        override_param(&mut p.plan, set).unwrap();
        let (image, a) = frame(&p);
        assert_eq!((a[0], a[3]), (groups, tiles), "{set}: {a:?}");
        let halves = |w: &[u32]| -> Vec<i32> {
            w.iter()
                .flat_map(|&x| [(x & 0xFFFF) as i32, (x >> 16) as i32])
                .collect()
        };
        let (a, b) = (halves(&widest), halves(&image));
        let steps = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).max().unwrap();
        let changed = a.iter().zip(&b).filter(|(x, y)| x != y).count();
        eprintln!(
            "{set}: {changed} of {} half floats differ, by at most {steps} steps",
            a.len()
        );
        assert!(
            steps <= 4,
            "{set}: a channel moved {steps} half-float steps"
        );
    }
}

/// `lipp.dom_opacity` walking the points `lipp.dom_depth` kept (ours,
/// `shared_points`: passes/src/lipp/dom.rs) draws the same maps, bit for
/// bit, as assembling every strand again, on ash and on the CPU: with the
/// shadow LOD, whose strands all fit the room the graph's `dom_points`
/// gives, and with every strand at C_max (no LOD, no groom cap), where none
/// fits and both passes assemble them.
#[test]
fn the_maps_are_the_same_whether_opacity_assembles_or_reads_the_points() {
    let mut p = prepare(&small_scene("shared", false), None, Some((W, H)))
        .unwrap_or_else(|e| panic!("{e:?}"));
    let share = |p: &mut Prepared, on: bool| {
        for pass in ["dom_depth", "dom_opacity"] {
            override_param(&mut p.plan, &format!("{pass}.shared_points={on}")).unwrap();
        }
    };
    let no_lod: &[&str] = &[
        "shadow_lod.enabled=false",
        "shadow_lod.groom_resolution=false",
    ];
    for (case, sets) in [("LOD", &[][..]), ("C_max", no_lod)] {
        for set in sets {
            override_param(&mut p.plan, set).unwrap();
        }
        share(&mut p, true);
        let s = ash(&p, false);
        let (depth, layers) = (read_ash(&s, "dom_depth"), read_ash(&s, "dom_layers"));
        let room = read_ash(&s, "dom_points")[0];
        // Each drawn bundle's C (bundle_lod: strands, C, first strand, flags).
        let cs: Vec<u32> = read_ash(&s, "shadow_lod")
            .chunks(4)
            .filter(|r| r[0] > 0)
            .map(|r| r[1])
            .collect();
        let kept = cs.iter().filter(|&&c| c <= room).count();
        eprintln!("{case}: room {room}, {kept} of {} bundles kept", cs.len());
        let expected = if sets.is_empty() { cs.len() } else { 0 };
        assert_eq!(kept, expected, "{case}: room {room}, C {cs:?}");
        if sets.is_empty() {
            let c = cpu(&p, s.subgroup_size);
            let read = |name: &str| c.read(&p.plan, name).unwrap();
            assert_eq!(read("dom_points")[0], room, "cpu: the room");
            let (d, l) = (read("dom_depth"), read("dom_layers"));
            share(&mut p, false);
            let c = cpu(&p, s.subgroup_size);
            let read = |name: &str| c.read(&p.plan, name).unwrap();
            assert!(
                read("dom_depth") == d && read("dom_layers") == l,
                "cpu: the maps differ"
            );
        }
        share(&mut p, false);
        let s = ash(&p, false);
        assert_eq!(
            read_ash(&s, "dom_points")[0],
            0,
            "{case}: kept with the switch off"
        );
        assert!(
            read_ash(&s, "dom_depth") == depth,
            "{case}: ash: the depth maps differ"
        );
        assert!(
            read_ash(&s, "dom_layers") == layers,
            "{case}: ash: the opacity maps differ"
        );
    }
}

fn run(graph: Option<&str>, beard: bool) {
    let tag = match (graph, beard) {
        (_, true) => "grooms",
        (None, false) => "lipp",
        (Some(g), false) if g.contains("msaa") => "msaa",
        _ => "other",
    };
    let graph = graph.map(|g| root().join(g));
    let p = prepare(&small_scene(tag, beard), graph.as_deref(), Some((W, H)))
        .unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(
        p.upload.quantities.bundles,
        if beard { 128 + 64 } else { 128 }
    );
    let plain = ash(&p, false);
    let aliased = ash(&p, true);
    let cpu = cpu(&p, plain.subgroup_size);
    let wgpu = wgpu(&p);
    eprintln!(
        "{:<16} {:>10} {:>10} {:>10}",
        "pass", "cpu ms", "wgpu ms", "ash ms"
    );
    for c in &cpu.timings {
        let g = wgpu.timings.iter().find(|t| t.name == c.name);
        let a = plain.timings.iter().find(|t| t.name == c.name);
        eprintln!(
            "{:<16} {:>10.3} {:>10.3} {:>10.3}",
            c.name,
            c.millis,
            g.map_or(f64::NAN, |t| t.millis),
            a.and_then(|t| t.millis).unwrap_or(f64::NAN)
        );
    }
    let read_cpu = |name: &str| cpu.read(&p.plan, name).unwrap();
    let read_wgpu = |name: &str| wgpu.read(&p.plan, name).unwrap().unwrap();

    let (lod, args) = (read_cpu("bundle_lod"), read_cpu("raster_args"));
    check_lod("cpu/ash", &args, &lod, &read_ash(&plain, "bundle_lod"));
    check_lod("cpu/wgpu", &args, &lod, &read_wgpu("bundle_lod"));
    let total = |args: &[u32]| f64::from(args[3]);
    for (label, other) in [
        ("ash", read_ash(&plain, "raster_args")),
        ("wgpu", read_wgpu("raster_args")),
    ] {
        assert!(
            (total(&args) - total(&other)).abs() <= 0.01 * total(&args),
            "{label}: raster_args {args:?} vs {other:?}"
        );
    }

    let g = read_cpu("gbuffer");
    check_gbuffer("cpu/ash", &g, &read_ash(&plain, "gbuffer"), &args, 500);
    check_gbuffer("cpu/wgpu", &g, &read_wgpu("gbuffer"), &args, 500);
    if beard {
        // The second groom's own copy of the G-buffer: what shows of the
        // beard through the hair (about 190 pixels per layer).
        let (g, args) = (read_cpu("gbuffer[1]"), read_cpu("raster_args[1]"));
        check_gbuffer(
            "beard cpu/ash",
            &g,
            &read_ash(&plain, "gbuffer[1]"),
            &args,
            100,
        );
        check_gbuffer("beard cpu/wgpu", &g, &read_wgpu("gbuffer[1]"), &args, 100);
    }

    let (dd, dl) = (read_cpu("dom_depth"), read_cpu("dom_layers"));
    check_dom(
        "cpu/ash",
        &dd,
        &dl,
        &read_ash(&plain, "dom_depth"),
        &read_ash(&plain, "dom_layers"),
    );
    check_dom(
        "cpu/wgpu",
        &dd,
        &dl,
        &read_wgpu("dom_depth"),
        &read_wgpu("dom_layers"),
    );

    let out = read_cpu("output");
    check_flip(
        &p,
        "diff_lipp",
        "ash",
        &out,
        &read_ash(&plain, "output"),
        MAX_MEAN_FLIP,
    );
    check_flip(
        &p,
        "diff_lipp",
        "wgpu",
        &out,
        &read_wgpu("output"),
        MAX_MEAN_FLIP,
    );
    assert_eq!(
        read_ash(&plain, "output"),
        read_ash(&aliased, "output"),
        "ash: the aliased run's image differs"
    );
}

/// `lipp.dom_depth` with and without its plain load before the atomicMin
/// (ours, `test_first`: passes/src/lipp/dom.rs) draws the same maps, bit
/// for bit, on ash: the load only skips atomics that could not lower the
/// texel.
#[test]
fn the_maps_are_the_same_whether_depth_tests_before_its_atomic() {
    let mut p = prepare(&small_scene("test_first", false), None, Some((W, H)))
        .unwrap_or_else(|e| panic!("{e:?}"));
    let maps = |p: &mut Prepared, on: bool| {
        override_param(&mut p.plan, &format!("dom_depth.test_first={on}")).unwrap();
        let s = ash(p, false);
        (read_ash(&s, "dom_depth"), read_ash(&s, "dom_layers"))
    };
    let (depth, layers) = maps(&mut p, true);
    assert!(
        depth
            .iter()
            .any(|&t| t != strandgraph_passes::lipp::dom::NO_HIT),
        "no strand reached the depth map"
    );
    let (d, l) = maps(&mut p, false);
    assert!(d == depth, "the depth maps differ");
    assert!(l == layers, "the opacity maps differ");
}

/// naga's loop counters (passes/src/loop_counters.rs) add a counter to
/// every loop and change nothing else: the LOD, the maps and the picture are
/// the same bits in every pass or in none, on ash and on wgpu. (The G-buffer
/// and the shaded records are defined only inside the groom's rectangle,
/// lipp::rect; the picture is made of them.)
#[test]
fn the_frame_is_the_same_with_naga_s_loop_counters() {
    use strandgraph_passes::LoopCounters;
    let p = prepare(&small_scene("loop_counters", false), None, Some((W, H)))
        .unwrap_or_else(|e| panic!("{e:?}"));
    let read = [
        "raster_args",
        "bundle_lod",
        "dom_depth",
        "dom_layers",
        "output.final",
    ];
    let ash_frame = |loop_counters| {
        let backend = strandgraph_ash::AshBackend {
            alias: false,
            loop_counters,
            ..Default::default()
        };
        let s = ash_with(&p, backend);
        read.map(|r| read_ash(&s, r))
    };
    let wgpu_frame = |loop_counters| {
        let backend = strandgraph_wgpu::WgpuBackend {
            loop_counters,
            ..Default::default()
        };
        let f = wgpu_with(&p, backend);
        read.map(|r| f.read(&p.plan, r).unwrap().unwrap())
    };
    let (every, none) = (LoopCounters::Every, LoopCounters::None);
    for (backend, free, bounded) in [
        ("ash", ash_frame(none), ash_frame(every)),
        ("wgpu", wgpu_frame(none), wgpu_frame(every)),
    ] {
        assert!(free[0][3] > 0, "{backend}: no strand drawn");
        let hit = |t: &u32| *t != strandgraph_passes::lipp::dom::NO_HIT;
        assert!(free[2].iter().any(hit), "{backend}: no strand in the maps");
        for ((name, a), b) in read.iter().zip(&free).zip(&bounded) {
            let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
            assert!(
                a.len() == b.len() && differ == 0,
                "{backend} {name}: {differ} words differ with the loop counters"
            );
        }
    }
}
