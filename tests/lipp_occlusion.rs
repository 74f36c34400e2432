//! `lipp.occlusion` (ours) on the CPU simulator, at the close view
//! (`scenes/distances/close.ron`, where the long groom hangs behind the
//! head and shoulders): the rasterizer must skip part of its segments and
//! change nothing it writes, since the pass hides only bundles and parts of
//! bundles every sample of which the scene-depth test would reject, and
//! nothing shading reads (β of Eq. 8 counts the culled strands).

use std::path::Path;
use strandgraph::frame::{Prepared, override_param, prepare};
use strandgraph_cpu::CpuBackend;
use strandgraph_passes::lipp::LOD_OCCLUDED;
use strandgraph_passes::lipp::lod::occlusion::segment_hidden;

struct Drawn {
    strands: u64,
    occluded_bundles: usize,
    /// Segments the rasterizer draws, and those it skips in hidden boxes.
    segments: u64,
    skipped: u64,
    args: Vec<u32>,
    gbuffer: Vec<u32>,
    output: Vec<u32>,
}

fn run(p: &Prepared) -> Drawn {
    let frame = CpuBackend {
        alias: false,
        ..CpuBackend::default()
    }
    .execute(&p.plan, &p.instance, &p.upload)
    .unwrap_or_else(|e| panic!("cpu backend failed: {e}"));
    let read = |name: &str| frame.read(&p.plan, name).unwrap();
    let bundles = p.upload.quantities.bundles as usize;
    let lod = read("bundle_lod");
    let records = read("hairmesh.bundles");
    let (mut segments, mut skipped) = (0u64, 0u64);
    for (b, l) in lod.chunks(4).take(bundles).enumerate() {
        let n = records[b * 16 + 1].clamp(2, 16);
        let c = l[1];
        let w = |k: u32| k as f32 / (c - 1) as f32;
        let hidden = (0..c - 1)
            .filter(|&k| segment_hidden(l[3], n, w(k), w(k + 1)))
            .count() as u64;
        segments += u64::from(l[0]) * u64::from(c - 1);
        skipped += u64::from(l[0]) * hidden;
    }
    Drawn {
        segments,
        skipped,
        strands: lod.chunks(4).take(bundles).map(|b| u64::from(b[0])).sum(),
        occluded_bundles: lod
            .chunks(4)
            .take(bundles)
            .filter(|b| b[3] & LOD_OCCLUDED != 0)
            .count(),
        args: read("raster_args"),
        gbuffer: read("gbuffer"),
        output: read("output.final"),
    }
}

#[test]
fn occlusion_culls_bundles_behind_the_head_and_changes_no_pixel() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/distances/close.ron");
    let mut p = prepare(&scene, None, Some((480, 270))).unwrap_or_else(|e| panic!("{e:?}"));
    let on = run(&p);
    override_param(&mut p.plan, "occlusion.enabled=false").unwrap();
    let off = run(&p);
    eprintln!(
        "close view 480x270: strands drawn {} -> {} with occlusion ({} bundles occluded); \
         segments walked {} -> {} ({} in hidden boxes)",
        off.strands,
        on.strands,
        on.occluded_bundles,
        off.segments,
        on.segments - on.skipped,
        on.skipped
    );
    assert_eq!((off.occluded_bundles, off.skipped), (0, 0));
    let walked = on.segments - on.skipped;
    assert!(
        walked * 10 < off.segments * 9,
        "at least a tenth of the segments behind the head: {walked} of {} walked",
        off.segments
    );
    assert_eq!(
        on.args[3], on.strands as u32,
        "the dispatch draws what bundle_lod says"
    );
    assert_eq!(on.args[4..6], off.args[4..6], "β of Eq. 8 unchanged");
    assert!(on.gbuffer == off.gbuffer, "the G-buffer is the same");
    assert!(on.output == off.output, "the image is the same");
}
