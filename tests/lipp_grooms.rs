//! Lipp §3.5, multiple grooms, on the CPU simulator (`scenes/grooms.ron`:
//! scalp hair, then a beard, through `lipp.ron`'s per-model block).
//!
//! - each groom runs its own LOD, raster, shade and filter (`raster[0]`,
//!   `raster[1]`, …) and is shaded with its own material;
//! - "preserving the depth buffer between groom passes, strands occluded by
//!   previously rendered grooms are rejected early": no beard sample lies
//!   behind the hair depth the first groom's filter wrote, and the beard's
//!   raster writes fewer pixels than with that depth switched off.
//!
//! And every groom of the showcase, its beard, brows and lashes too, keeps
//! most of its strands under Lipp's LOD at the showcase's close-up: the
//! scenes give short grooms their own λ (Eq. 2). At λ 1 the beard kept a
//! few per cent of them and Lipp's picture showed none.

use std::path::Path;
use strandgraph::agree::capture;
use strandgraph::frame::{Prepared, override_param, prepare};
use strandgraph_cpu::{CpuBackend, Frame};
use strandgraph_passes::lipp::payload::{EMPTY, from_words, unpack};
use strandgraph_passes::lipp::shaded::unpack_rgb9e5;

const W: u32 = 240;
const H: u32 = 135;

fn scene() -> Prepared {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/grooms.ron");
    prepare(&path, None, Some((W, H))).unwrap_or_else(|e| panic!("{e:?}"))
}

fn run(p: &Prepared) -> Frame<'_> {
    CpuBackend {
        instrument: true,
        alias: false,
        ..CpuBackend::default()
    }
    .execute(&p.plan, &p.instance, &p.upload)
    .unwrap_or_else(|e| panic!("cpu backend failed: {e}"))
}

fn read(p: &Prepared, frame: &Frame, name: &str) -> Vec<u32> {
    frame
        .read(&p.plan, name)
        .unwrap_or_else(|| panic!("no resource `{name}`"))
}

fn pixels_written(frame: &Frame, pass: &str) -> u64 {
    let t = frame.timings.iter().find(|t| t.name == pass);
    t.unwrap_or_else(|| panic!("no pass `{pass}`"))
        .counters
        .pixels_written
}

/// Mean red / green of the shaded centre samples in one groom's `shaded`.
fn redness(shaded: &[u32], gbuffer: &[u32]) -> f64 {
    let (mut r, mut g) = (0.0f64, 0.0f64);
    for i in 0..(W * H) as usize {
        if from_words(gbuffer[2 * i], gbuffer[2 * i + 1]) == EMPTY {
            continue;
        }
        // The centre layer's record (passes/src/lipp/shaded.rs).
        let c = unpack_rgb9e5(shaded[2 * i]);
        r += f64::from(c[0]);
        g += f64::from(c[1]);
    }
    r / g.max(1e-9)
}

#[test]
fn grooms_are_drawn_in_turn_with_their_materials_and_the_depth_between_them() {
    let mut p = scene();
    // `hair_depth` is one buffer carried from groom to groom: so that it
    // holds the hair's depth after the frame, the beard's filter (the last
    // groom's) does not add its own.
    override_param(&mut p.plan, "filter[1].depth_alpha=2.0").unwrap();
    for name in ["lod[1]", "raster[0]", "raster[1]", "shade[1]", "filter[1]"] {
        assert!(p.plan.graph.pass_id(name).is_some(), "no pass `{name}`");
    }
    let frame = run(&p);
    let (hair, beard) = (
        pixels_written(&frame, "raster[0]"),
        pixels_written(&frame, "raster[1]"),
    );
    assert!(hair > 0 && beard > 0, "both grooms draw: {hair}, {beard}");

    // Each groom's shading uses its own material: the beard is dark red.
    let hair_red = redness(&read(&p, &frame, "shaded"), &read(&p, &frame, "gbuffer"));
    let beard_red = redness(
        &read(&p, &frame, "shaded[1]"),
        &read(&p, &frame, "gbuffer[1]"),
    );
    eprintln!("red/green: hair {hair_red:.2}, beard {beard_red:.2}");
    assert!(beard_red > 1.5 * hair_red, "{beard_red} vs {hair_red}");

    // No beard sample behind the hair's depth (24-bit payload depth).
    let hair_depth = read(&p, &frame, "hair_depth.final[0]");
    let covered = hair_depth
        .iter()
        .filter(|&&d| f32::from_bits(d) < 1.0)
        .count();
    let gbuffer = read(&p, &frame, "gbuffer[1]");
    let pixels = (W * H) as usize;
    let mut behind = 0;
    for layer in 0..2 {
        for (i, d) in hair_depth.iter().enumerate() {
            let s = layer * pixels + i;
            let payload = from_words(gbuffer[2 * s], gbuffer[2 * s + 1]);
            if payload != EMPTY && unpack(payload).depth > f32::from_bits(*d) + 1e-6 {
                behind += 1;
            }
        }
    }
    assert!(covered > 1000, "the hair writes depth on {covered} pixels");
    assert_eq!(behind, 0, "beard samples behind the hair");

    // Without the hair's depth, more of the beard is rasterized.
    override_param(&mut p.plan, "filter[0].depth_alpha=2.0").unwrap();
    let unoccluded = pixels_written(&run(&p), "raster[1]");
    eprintln!(
        "beard pixels written: {beard} with the hair's depth, {unoccluded} without ({covered} hair-depth pixels)"
    );
    assert!(beard < unoccluded, "{beard} vs {unoccluded}");
}

/// Per groom drawn by `scene` through `lipp.ron`: (strands drawn, strands
/// of the groom), from the `raster_args` each groom's raster ran with
/// (words 3 and 4, lipp.lod_scan's).
fn strands_drawn(scene: &str, (w, h): (u32, u32)) -> Vec<(u32, u32)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let graph = root.join("scenes/graphs/lipp.ron");
    let p = prepare(&root.join(scene), Some(&graph), Some((w, h)))
        .unwrap_or_else(|e| panic!("{scene}: {e:?}"));
    let mut out = Vec::new();
    for c in capture(&p).unwrap_or_else(|e| panic!("{scene}: {e:?}")) {
        if p.plan.graph.passes[c.pass].kind != "lipp.raster" {
            continue;
        }
        let args = c.bindings.iter().find(|(n, _)| n == "raster_args");
        let args = &args
            .unwrap_or_else(|| panic!("raster without raster_args"))
            .1;
        out.push((args[3], args[4]));
    }
    out
}

#[test]
fn the_showcases_short_grooms_keep_most_of_their_strands_under_lipps_lod() {
    let grooms = strands_drawn("scenes/showcase.ron", (320, 180));
    // Hair, eyebrows, eyelashes, beard (the scene's order).
    assert_eq!(grooms.len(), 4, "{grooms:?}");
    for (i, &(drawn, all)) in grooms.iter().enumerate() {
        assert!(all > 0, "groom {i} has no strands: {grooms:?}");
        let kept = f64::from(drawn) / f64::from(all);
        assert!(
            kept >= 0.5,
            "groom {i} draws {drawn} of {all} strands: {grooms:?}"
        );
    }
}
