//! Lipp §3.2 on the CPU simulator: at the far view (`scenes/distances/far.ron`,
//! camera 10 m away) the LOD prepass must cut the rasterizer's work at least
//! five-fold, measured by the raster pass's instrumentation (pixels written by
//! 64-bit atomicMin) and by the segments the LOD decisions imply
//! (Σ N_LOD · (C − 1) over bundles, read back from `bundle_lod`). Lipp's
//! Table 1 reports 127k → 21k strands and an 11× faster frame at far.

use std::path::Path;
use strandgraph::frame::{Prepared, override_param, prepare};
use strandgraph_cpu::CpuBackend;

const W: u32 = 480;
const H: u32 = 270;

struct Work {
    strands: u64,
    segments: u64,
    pixels: u64,
    millis: f64,
}

fn run(p: &Prepared) -> Work {
    let frame = CpuBackend {
        instrument: true,
        alias: false,
        ..CpuBackend::default()
    }
    .execute(&p.plan, &p.instance, &p.upload)
    .unwrap_or_else(|e| panic!("cpu backend failed: {e}"));
    let lod = frame.read(&p.plan, "bundle_lod").unwrap();
    let bundles = p.upload.quantities.bundles as usize;
    let (mut strands, mut segments) = (0u64, 0u64);
    for b in lod.chunks(4).take(bundles) {
        strands += u64::from(b[0]);
        segments += u64::from(b[0]) * u64::from(b[1].saturating_sub(1));
    }
    let raster = frame.timings.iter().find(|t| t.name == "raster").unwrap();
    assert_eq!(raster.counters.out_of_bounds, 0);
    Work {
        strands,
        segments,
        pixels: raster.counters.pixels_written,
        millis: raster.millis,
    }
}

#[test]
fn far_view_lod_cuts_raster_work_at_least_five_fold() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/distances/far.ron");
    let mut p = prepare(&scene, None, Some((W, H))).unwrap_or_else(|e| panic!("{e:?}"));
    let on = run(&p);
    override_param(&mut p.plan, "lod.enabled=false").unwrap();
    let off = run(&p);
    eprintln!(
        "far view {W}x{H}, LOD off -> on: strands {} -> {}, segments {} -> {} ({:.1}x), \
         pixels written {} -> {} ({:.1}x), raster {:.1} -> {:.1} ms (cpu)",
        off.strands,
        on.strands,
        off.segments,
        on.segments,
        off.segments as f64 / on.segments.max(1) as f64,
        off.pixels,
        on.pixels,
        off.pixels as f64 / on.pixels.max(1) as f64,
        off.millis,
        on.millis
    );
    assert_eq!(off.strands, 130_000, "LOD off draws every strand");
    assert!(on.pixels > 0 && on.segments > 0);
    assert!(off.segments >= 5 * on.segments, "segments");
    assert!(off.pixels >= 5 * on.pixels, "pixels written");
}

/// Strands each bundle draws into `resource` (a `bundle_lod` layout).
fn strands_in(p: &Prepared, resource: &str) -> u64 {
    let frame = CpuBackend {
        alias: false,
        ..CpuBackend::default()
    }
    .execute(&p.plan, &p.instance, &p.upload)
    .unwrap_or_else(|e| panic!("cpu backend failed: {e}"));
    let lod = frame.read(&p.plan, resource).unwrap();
    let bundles = p.upload.quantities.bundles as usize;
    lod.chunks(4).take(bundles).map(|b| u64::from(b[0])).sum()
}

/// The deep opacity maps' own LOD (`shadow_lod`, `view: Light`): measured
/// in the light's map, it does not move with the camera unless bound by it,
/// and at close range it keeps fewer strands than the camera's (λ 0.25).
#[test]
fn shadow_lod_is_measured_in_the_lights_map() {
    let scene =
        |v: &str| Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/distances/{v}.ron"));
    let prepared = |v: &str, params: &[&str]| {
        let mut p = prepare(&scene(v), None, Some((W, H))).unwrap_or_else(|e| panic!("{e:?}"));
        for spec in params {
            override_param(&mut p.plan, spec).unwrap();
        }
        p
    };
    let unbound = ["shadow_lod.camera_bound=false"];
    let (close, far) = (
        strands_in(&prepared("close", &unbound), "shadow_lod"),
        strands_in(&prepared("far", &unbound), "shadow_lod"),
    );
    assert_eq!(close, far, "the light's map does not see the camera move");
    let shipped = prepared("close", &[]);
    let (maps, camera) = (
        strands_in(&shipped, "shadow_lod"),
        strands_in(&shipped, "bundle_lod"),
    );
    let bound_far = strands_in(&prepared("far", &[]), "shadow_lod");
    eprintln!(
        "shadow LOD strands: {close} unbound (close and far), {maps} close and {bound_far} far \
         bound by the camera; camera LOD at close {camera}"
    );
    assert!(
        maps > 0 && maps * 2 < camera,
        "{maps} vs the camera's {camera}"
    );
    assert!(
        bound_far < maps,
        "bound by the camera, the far view keeps fewer"
    );
}

/// `lipp.raster`'s `strip_rounds` (ours: one point a lane, in rounds)
/// against Code 1's strips of up to four points a lane: with the LOD and
/// its groom-resolution cap off every strand keeps C_max = 127 points, four
/// rounds, and the G-buffer is the same words.
#[test]
fn strip_rounds_draw_what_code1_strips_draw() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/distances/mid.ron");
    let words = |rounds: bool| {
        let mut p = prepare(&scene, None, Some((160, 90))).unwrap_or_else(|e| panic!("{e:?}"));
        for spec in [
            "lod.enabled=false",
            "lod.groom_resolution=false",
            &format!("raster.strip_rounds={rounds}"),
        ] {
            override_param(&mut p.plan, spec).unwrap();
        }
        let frame = CpuBackend {
            alias: false,
            ..CpuBackend::default()
        }
        .execute(&p.plan, &p.instance, &p.upload)
        .unwrap_or_else(|e| panic!("cpu backend failed: {e}"));
        ["gbuffer", "bundle_lod"].map(|r| frame.read(&p.plan, r).unwrap())
    };
    let ([rounds, lod], [code1, _]) = (words(true), words(false));
    assert!(
        lod.chunks(4).any(|b| b[0] > 0 && b[1] == 127),
        "C_max strands"
    );
    assert!(
        rounds.iter().any(|&w| w != rounds[0]),
        "the G-buffer is blank"
    );
    assert!(rounds == code1, "the G-buffers differ");
}
