//! Three-way differential test: the CPU simulator (the reference), wgpu and
//! the ash backend (lavapipe in CI, any Vulkan 1.3 device elsewhere) must
//! agree, with the ash backend under the Khronos validation layer and
//! synchronization validation: any validation message fails the run.
//!
//! Gates, as in `tests/diff_wgpu.rs`: the three visibility layers identical
//! on at least 99.9% of covered atlas texels (docs/architecture.md,
//! "Agreement across backends"), the debug view identical on 99.9% of pixels, final images
//! within a mean FLIP of 0.01 (`strandgraph::compare::flip`). The ash run
//! with the plan's memory aliasing must produce the same images as the run
//! without (which the atlases are read from: aliased transients are
//! overwritten by the end of the frame).
//!
//! No device or no validation layer is a failure, not a skip: CI installs
//! lavapipe and `vulkan-validationlayers` (`scripts/test.sh`).

use strandgraph::compare::flip;
use strandgraph::frame::{Prepared, prepare};
use strandgraph::images::{Display, to_picture};

mod common;
use common::{ash, cpu, out_dir, read_ash, root, wgpu};

// Rows of 250 texels: not a multiple of any copy alignment.
const W: u32 = 250;
const H: u32 = 140;
const MAX_MEAN_FLIP: f32 = 0.01;
const MAX_PIXEL_FLIP: f32 = 0.5;

/// Identical covered texels of the three visibility layers, over texels
/// either side covers; `(same, covered)`.
fn layer_agreement(cv: &[u32], cc: &[u32], av: &[u32], ac: &[u32]) -> (usize, usize) {
    let texels = cc.len();
    assert_eq!(cv.len(), 3 * texels, "three visibility layers");
    assert_eq!((av.len(), ac.len()), (cv.len(), cc.len()));
    let mut covered = 0;
    let mut same = 0;
    for t in 0..texels {
        if cc[t] == 0 && ac[t] == 0 {
            continue;
        }
        covered += 1;
        let layers = |v: &[u32]| [v[t], v[texels + t], v[2 * texels + t]];
        same += usize::from(layers(cv) == layers(av));
    }
    (same, covered)
}

fn identical(a: &[u32], b: &[u32]) -> f64 {
    assert_eq!(a.len(), b.len(), "sizes differ");
    a.iter().zip(b).filter(|(x, y)| x == y).count() as f64 / a.len().max(1) as f64
}

/// FLIP of two renderings of image resource `name`; saves both and the map on failure.
fn assert_flip(
    p: &Prepared,
    name: &str,
    reference: (&str, &[u32]),
    test: (&str, &[u32]),
    w: u32,
    h: u32,
) {
    let r = p.plan.graph.resource_id(name).unwrap();
    let a = to_picture(&p.plan, r, reference.1, w, h, Display::CLIP).unwrap();
    let b = to_picture(&p.plan, r, test.1, w, h, Display::CLIP).unwrap();
    let d = flip(&a, &b).unwrap();
    eprintln!(
        "{name}: {} vs {}: mean FLIP {:.5}, max {:.4} at {:?}",
        reference.0, test.0, d.mean, d.max, d.max_at
    );
    if d.mean > MAX_MEAN_FLIP || d.max > MAX_PIXEL_FLIP {
        let dir = out_dir("diff_ash");
        a.save(dir.join(format!("{name}.{}.png", reference.0)))
            .unwrap();
        b.save(dir.join(format!("{name}.{}.png", test.0))).unwrap();
        d.error_map
            .save(dir.join(format!("{name}.flip.png")))
            .unwrap();
        panic!(
            "{name}: {} and {} differ: mean FLIP {} (max {MAX_MEAN_FLIP}), worst pixel {} (max {MAX_PIXEL_FLIP}); images in {}",
            reference.0,
            test.0,
            d.mean,
            d.max,
            dir.display()
        );
    }
}

#[test]
fn showcase_visibility_matches_cpu_and_wgpu_on_ash() {
    let graph = root().join("scenes/graphs/kulikov_visibility.ron");
    let p = prepare(
        &root().join("scenes/showcase.ron"),
        Some(&graph),
        Some((W, H)),
    )
    .unwrap_or_else(|e| panic!("{e:?}"));
    let plain = ash(&p, false);
    let aliased = ash(&p, true);
    assert!(
        aliased.transient_bytes < plain.transient_bytes,
        "aliasing saves memory"
    );
    let cpu = cpu(&p, plain.subgroup_size);
    let wgpu = wgpu(&p);

    eprintln!(
        "{:<16} {:>10} {:>10} {:>10}",
        "pass", "cpu ms", "wgpu ms", "ash ms"
    );
    for ((c, g), a) in cpu.timings.iter().zip(&wgpu.timings).zip(&plain.timings) {
        eprintln!(
            "{:<16} {:>10.3} {:>10.3} {:>10.3}",
            c.name,
            c.millis,
            g.millis,
            a.millis.unwrap_or(f64::NAN)
        );
    }
    let read_cpu = |name: &str| cpu.read(&p.plan, name).unwrap();
    let read_wgpu = |name: &str| wgpu.read(&p.plan, name).unwrap().unwrap();

    // Integer bookkeeping before the raster: exact.
    for name in ["lod_models", "lod_args", "atlas_tiles", "raster_args"] {
        assert_eq!(
            read_cpu(name),
            read_ash(&plain, name),
            "{name} differs (cpu vs ash)"
        );
    }
    let (cv, cc) = (read_cpu("vis_atlas"), read_cpu("coverage_atlas"));
    let (av, ac) = (
        read_ash(&plain, "vis_atlas"),
        read_ash(&plain, "coverage_atlas"),
    );
    let (gv, gc) = (read_wgpu("vis_atlas"), read_wgpu("coverage_atlas"));
    let (same, covered) = layer_agreement(&cv, &cc, &av, &ac);
    let (same_w, covered_w) = layer_agreement(&gv, &gc, &av, &ac);
    let sum = |v: &[u32]| v.iter().map(|&c| u64::from(c)).sum::<u64>();
    let coverage_error = (sum(&cc) as f64 - sum(&ac) as f64).abs() / sum(&cc).max(1) as f64;
    eprintln!(
        "layers identical on covered texels: cpu/ash {same}/{covered}, wgpu/ash {same_w}/{covered_w}; \
         coverage sums cpu {} ash {} ({:.4}% apart)",
        sum(&cc),
        sum(&ac),
        coverage_error * 100.0
    );
    assert!(covered > 1000, "only {covered} covered texels");
    assert!(
        same as f64 >= 0.999 * covered as f64,
        "cpu/ash layers: {same}/{covered}"
    );
    assert!(
        same_w as f64 >= 0.999 * covered_w as f64,
        "wgpu/ash layers: {same_w}/{covered_w}"
    );
    assert!(coverage_error <= 0.002, "coverage sums {coverage_error}");

    let (cd, gd, ad) = (
        read_cpu("debug_layers"),
        read_wgpu("debug_layers"),
        read_ash(&plain, "debug_layers"),
    );
    let (cpu_same, wgpu_same) = (identical(&cd, &ad), identical(&gd, &ad));
    eprintln!(
        "debug_layers identical: cpu/ash {:.4}%, wgpu/ash {:.4}%",
        cpu_same * 100.0,
        wgpu_same * 100.0
    );
    assert!(cpu_same >= 0.999 && wgpu_same >= 0.999);
    let (co, ao) = (read_cpu("output"), read_ash(&plain, "output"));
    assert_flip(&p, "output", ("cpu", &co), ("ash", &ao), W, H);

    // Aliasing changes where transients live, never what the frame computes.
    for name in ["debug_layers", "output"] {
        assert_eq!(
            read_ash(&plain, name),
            read_ash(&aliased, name),
            "{name}: aliased run differs"
        );
    }
}

/// The full Kulikov graph (shading, composition as two draws with blending
/// and a hair-depth pipeline) on ash against the CPU, and a second frame
/// of the same session gives the same image.
#[test]
fn showcase_composed_matches_cpu_on_ash() {
    let (w, h) = (96, 54);
    let graph = root().join("scenes/graphs/kulikov.ron");
    let p = prepare(
        &root().join("scenes/showcase.ron"),
        Some(&graph),
        Some((w, h)),
    )
    .unwrap_or_else(|e| panic!("{e:?}"));
    let mut session = ash(&p, true);
    let cpu = cpu(&p, session.subgroup_size);
    let name = "output.composed";
    let c = cpu.read(&p.plan, name).unwrap();
    let a = read_ash(&session, name);
    assert_flip(&p, name, ("cpu", &c), ("ash", &a), w, h);
    let cd = cpu.read(&p.plan, "hair_depth").unwrap();
    let ad = read_ash(&session, "hair_depth");
    let depth_close = cd
        .iter()
        .zip(&ad)
        .filter(|(x, y)| (f32::from_bits(**x) - f32::from_bits(**y)).abs() <= 1e-5)
        .count() as f64
        / cd.len().max(1) as f64;
    eprintln!("hair_depth: {:.3}% within 1e-5", depth_close * 100.0);
    assert!(depth_close >= 0.99, "hair depth: {depth_close}");
    session
        .run(&p.upload)
        .unwrap_or_else(|e| panic!("second frame: {e}"));
    assert_eq!(read_ash(&session, name), a, "the second frame differs");
}

/// Barriers in dependency levels (`strandgraph_ash::Barriers::Levels`, the
/// default) reorder a queue's passes and drop barriers between them, and
/// change no bit of the frame: Kulikov's and Lipp's pictures are the same
/// with a barrier before each pass, with the plan's aliasing (whose
/// hand-overs the levels must respect) and synchronization validation on.
/// Nor does aliasing that adds no wait (`Aliasing::NoNewWaits`), which
/// drops hand-overs. lavapipe has one queue, so its levels mix both
/// queues' passes.
#[test]
fn barrier_levels_change_no_bit_of_the_frame() {
    use strandgraph_ash::{AshBackend, Barriers};
    use strandgraph_graph::alias::Aliasing;
    for (graph, output) in [("kulikov", "output.composed"), ("lipp", "output.final")] {
        let mut p = prepare(
            &root().join("scenes/showcase.ron"),
            Some(&root().join(format!("scenes/graphs/{graph}.ron"))),
            Some((96, 54)),
        )
        .unwrap_or_else(|e| panic!("{e:?}"));
        let frame = |barriers| {
            let s = common::ash_with(
                &p,
                AshBackend {
                    barriers,
                    ..Default::default()
                },
            );
            read_ash(&s, output)
        };
        let (levels, per_pass) = (frame(Barriers::Levels), frame(Barriers::PerPass));
        p.plan.aliasing = Aliasing::NoNewWaits;
        p.instance = p.plan.instantiate(&p.upload.quantities).unwrap();
        let no_new_waits = read_ash(&common::ash_with(&p, AshBackend::default()), output);
        assert!(
            levels.iter().any(|&w| w != levels[0]),
            "{graph}: a blank picture"
        );
        for (other, what) in [(&per_pass, "barrier"), (&no_new_waits, "aliasing")] {
            let differ = levels.iter().zip(other).filter(|(a, b)| a != b).count();
            assert_eq!(
                differ, 0,
                "{graph}: {differ} words differ between the {what} settings"
            );
        }
    }
}

/// A frame that does not finish within the session's timeout ends with an
/// error naming the pass it is stuck at, rather than waiting forever: with
/// no time at all, lavapipe has barely started the showcase.
#[test]
fn a_frame_past_its_timeout_names_the_unfinished_pass() {
    let graph = root().join("scenes/graphs/kulikov.ron");
    let p = prepare(
        &root().join("scenes/showcase.ron"),
        Some(&graph),
        Some((640, 360)),
    )
    .unwrap_or_else(|e| panic!("{e:?}"));
    let backend = strandgraph_ash::AshBackend {
        timeout: std::time::Duration::ZERO,
        ..Default::default()
    };
    let err = match backend.execute(&p.plan, &p.instance, &p.upload) {
        Ok(_) => panic!("the showcase finished within no time at all"),
        Err(e) => e.to_string(),
    };
    eprintln!("{err}");
    assert!(
        err.contains("no completion within 0 ms") && err.contains("unfinished: pass `"),
        "{err}"
    );
}
