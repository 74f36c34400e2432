//! The Kulikov visibility pipeline end to end on the CPU backend.

use std::path::Path;
use std::process::Command;
use strandgraph::frame::{Prepared, prepare};
use strandgraph_cpu::{CpuBackend, Frame};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn visibility(scene: &str, w: u32, h: u32) -> Prepared {
    let graph = root().join("scenes/graphs/kulikov_visibility.ron");
    prepare(&root().join(scene), Some(&graph), Some((w, h))).unwrap_or_else(|e| panic!("{e:?}"))
}

fn run(p: &Prepared, backend: &CpuBackend) -> Frame<'static> {
    let f = backend
        .execute(&p.plan, &p.instance, &p.upload)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        f.memory
            .out_of_bounds
            .load(std::sync::atomic::Ordering::Relaxed),
        0,
        "out-of-range accesses"
    );
    f
}

fn covered_texels(p: &Prepared, f: &Frame) -> usize {
    f.read(&p.plan, "coverage_atlas")
        .unwrap()
        .iter()
        .filter(|&&c| c > 0)
        .count()
}

#[test]
fn showcase_rasterizes_hair_over_the_head() {
    let p = visibility("scenes/showcase.ron", 320, 180);
    let f = run(&p, &CpuBackend::default());
    assert!(
        covered_texels(&p, &f) > 5_000,
        "too little hair: {}",
        covered_texels(&p, &f)
    );
    // The debug view differs from the opaque image exactly where hair is.
    let layers = f.read(&p.plan, "debug_layers").unwrap();
    let hair = layers.iter().filter(|&&w| w >> 24 > 0).count();
    assert!(hair > 3_000 && hair < 320 * 180, "{hair} hair pixels");
    // Every model got atlas tiles at full resolution.
    let tiles = f.read(&p.plan, "atlas_tiles").unwrap();
    for m in 0..p.upload.models.len() {
        assert_eq!(
            (tiles[8 * m + 5], tiles[8 * m + 6]),
            (1, 1),
            "model {m}: downscale, valid"
        );
    }
}

#[test]
fn crowd_renders_every_visible_character() {
    let p = visibility("scenes/crowd.ron", 320, 180);
    assert!(p.upload.models.len() >= 12);
    let f = run(
        &p,
        &CpuBackend {
            subgroup_width: 8,
            ..CpuBackend::default()
        },
    );
    let tiles = f.read(&p.plan, "atlas_tiles").unwrap();
    let drawn = (0..p.upload.models.len())
        .filter(|m| tiles[8 * m + 6] == 1)
        .count();
    assert!(drawn >= 6, "only {drawn} models reached the atlas");
    assert!(covered_texels(&p, &f) > 2_000);
}

#[test]
fn aliasing_plan_does_not_change_the_frame() {
    let p = visibility("scenes/showcase.ron", 256, 144);
    assert!(p.instance.memory.bytes_with_aliasing < p.instance.memory.bytes_without_aliasing);
    let aliased = run(&p, &CpuBackend::default());
    let separate = run(
        &p,
        &CpuBackend {
            alias: false,
            ..CpuBackend::default()
        },
    );
    for r in [
        "vis_atlas",
        "coverage_atlas",
        "output",
        "debug_layers",
        "atlas_tiles",
    ] {
        assert_eq!(
            aliased.read(&p.plan, r),
            separate.read(&p.plan, r),
            "{r} differs"
        );
    }
}

#[test]
fn render_command_writes_pngs_and_a_timing_table() {
    let dir = std::env::temp_dir().join(format!("strandgraph-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("showcase.png");
    let o = Command::new(env!("CARGO_BIN_EXE_strandgraph"))
        .current_dir(root())
        .args([
            "render",
            "scenes/showcase.ron",
            "--graph",
            "scenes/graphs/kulikov_visibility.ron",
        ])
        .args([
            "--size",
            "200x120",
            "--instrument",
            "--param",
            "raster.loop_flattening=false",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        text.contains("kulikov.raster") && text.contains("async-compute  total"),
        "{text}"
    );
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (200, 120));
    assert!(out.with_extension("debug_layers.png").exists());
}

/// `-o NAME.exr` writes linear float images and `--depth` the view depth.
#[test]
fn render_command_writes_linear_exr_and_depth() {
    let dir = std::env::temp_dir().join(format!("strandgraph-exr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (out, depth) = (dir.join("showcase.exr"), dir.join("depth.exr"));
    let o = Command::new(env!("CARGO_BIN_EXE_strandgraph"))
        .current_dir(root())
        .args(["render", "scenes/showcase.ron", "--graph"])
        .args(["scenes/graphs/kulikov_visibility.ron", "--size", "160x90"])
        .arg("-o")
        .arg(&out)
        .arg("--depth")
        .arg(&depth)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(&out).unwrap().into_rgba32f();
    assert_eq!(img.dimensions(), (160, 90));
    // Linear, unclamped values: the lit head is brighter than the background.
    let max = img.pixels().map(|p| p[0]).fold(0.0f32, f32::max);
    assert!(max > 0.05, "brightest red {max}");
    let d = image::open(&depth).unwrap().into_rgb32f();
    let near = d.pixels().map(|p| p[0]).fold(f32::MAX, f32::min);
    let far = d.pixels().map(|p| p[0]).fold(0.0f32, f32::max);
    // The camera is ~0.9 m from the head; empty pixels read the far plane.
    assert!((0.3..2.0).contains(&near), "nearest depth {near} m");
    assert!(far > 100.0, "background depth {far} m");
}

/// `--motion` writes the per-pixel motion EXR (zero on a single frame:
/// nothing came before it), and names the missing resource on a graph
/// without motion.
#[test]
fn render_command_writes_motion_or_says_why_not() {
    let dir = std::env::temp_dir().join(format!("strandgraph-motion-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let motion = dir.join("motion.exr");
    let render = |graph: &str, params: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_strandgraph"))
            .current_dir(root())
            .args([
                "render",
                "scenes/showcase.ron",
                "--size",
                "96x54",
                "--graph",
                graph,
            ])
            .args(params)
            .arg("-o")
            .arg(dir.join("m.png"))
            .arg("--motion")
            .arg(&motion)
            .output()
            .unwrap()
    };
    // No self-shadowing: this test is about motion, not the bake.
    let o = render(
        "scenes/graphs/kulikov.ron",
        &["--param", "shade.self_shadow=\"None\""],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m = image::open(&motion).unwrap().into_rgb32f();
    assert_eq!(m.dimensions(), (96, 54));
    assert!(m.pixels().all(|p| p[0] == 0.0 && p[1] == 0.0));
    let o = render("scenes/graphs/kulikov_visibility.ron", &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("pixel_motion"), "{err}");
}

#[test]
fn render_rejects_a_bad_parameter_by_name() {
    let o = Command::new(env!("CARGO_BIN_EXE_strandgraph"))
        .current_dir(root())
        .args([
            "render",
            "scenes/showcase.ron",
            "--graph",
            "scenes/graphs/kulikov_visibility.ron",
        ])
        .args([
            "--size",
            "64x64",
            "--param",
            "raster.workgroup_size=128",
            "-o",
            "/dev/null",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("workgroup_size"));
}

/// Rgba16Float words to linear RGB.
fn rgb16f(words: &[u32], i: usize) -> [f32; 3] {
    let h = |w: u32| half::f16::from_bits(w as u16).to_f32();
    [h(words[2 * i]), h(words[2 * i] >> 16), h(words[2 * i + 1])]
}

#[test]
fn showcase_renders_lit_and_composited_with_its_own_graph() {
    let p = prepare(&root().join("scenes/showcase.ron"), None, Some((320, 180)))
        .unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(p.plan.graph.name, "kulikov");
    let f = run(&p, &CpuBackend::default());
    let out = f.read(&p.plan, "output.composed").unwrap();
    let n = 320 * 180;
    let bg = [0.02f32, 0.02, 0.025];
    let mut hair = 0;
    let mut bright = 0;
    let mut sum = 0.0f64;
    for i in 0..n {
        let c = rgb16f(&out, i);
        assert!(
            c.iter().all(|x| x.is_finite() && *x >= 0.0),
            "pixel {i}: {c:?}"
        );
        if (0..3).any(|k| (c[k] - bg[k]).abs() > 0.01) {
            hair += 1;
            let luma = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
            sum += f64::from(luma);
            if luma > 0.15 {
                bright += 1;
            }
        }
    }
    // Hair and head cover about a third of the frame; the hair is lit (a mean
    // above the ambient floor, highlights) without blowing out.
    let mean = sum / hair.max(1) as f64;
    assert!(hair > n / 5 && hair < n * 3 / 4, "{hair} covered pixels");
    assert!(mean > 0.03 && mean < 1.5, "mean luminance {mean}");
    assert!(bright > n / 50, "{bright} bright pixels");
    // Hair wrote depth where it is nearly opaque: far more than the head alone.
    let depth = f.read(&p.plan, "hair_depth").unwrap();
    let deep = depth.iter().filter(|&&d| f32::from_bits(d) < 1.0).count();
    assert!(deep > n / 6, "{deep} pixels with depth");
}

/// Kulikov, "Hair volumetric shadows": the showcase's head is shadowed where
/// hair lies between it and the light, lit elsewhere, and occluded under hair.
#[test]
fn hair_shadows_the_head_where_hair_lies_between_it_and_the_light() {
    let p = prepare(&root().join("scenes/showcase.ron"), None, Some((320, 180)))
        .unwrap_or_else(|e| panic!("{e:?}"));
    let backend = CpuBackend {
        alias: false,
        ..CpuBackend::default()
    };
    let f = run(&p, &backend);
    let mask = f.read(&p.plan, "skin_shadow").unwrap();
    let head: Vec<u32> = mask.iter().copied().filter(|&m| m != u32::MAX).collect();
    let vis = |m: u32| (m & 0xFF) as f32 / 255.0;
    let shadowed = head.iter().filter(|&&m| vis(m) < 0.5).count();
    let occluded = head.iter().filter(|&&m| (m >> 24) < 230).count();
    assert!(
        head.len() > 500,
        "{} head pixels with any shadow",
        head.len()
    );
    assert!(
        shadowed > head.len() / 20,
        "{shadowed} of {} shadowed",
        head.len()
    );
    assert!(shadowed < head.len() * 19 / 20, "all {shadowed} shadowed");
    assert!(occluded > 0, "no ambient occlusion under hair");
    // Switching the march off leaves every pixel lit.
    let mut off = p.plan.clone();
    strandgraph::frame::override_param(&mut off, "skin_shadow.steps=0").unwrap();
    strandgraph::frame::override_param(&mut off, "skin_shadow.ao_steps=0").unwrap();
    let f = backend
        .execute(&off, &p.instance, &p.upload)
        .unwrap_or_else(|e| panic!("{e}"));
    let mask = f.read(&off, "skin_shadow").unwrap();
    assert!(mask.iter().all(|&m| m == u32::MAX));
}

/// `compose.workgroup_cull` (ours) only skips models no pixel of a
/// workgroup can sample: the crowd composes to the same words without it.
#[test]
fn compose_workgroup_cull_changes_no_pixel() {
    let frame = |cull: &str| {
        let params = [
            "shade.self_shadow=\"VoxelMarch\"".to_string(),
            format!("compose.workgroup_cull={cull}"),
        ];
        let p = strandgraph::frame::prepare_with(
            &root().join("scenes/crowd.ron"),
            None,
            Some((320, 180)),
            &params,
        )
        .unwrap_or_else(|e| panic!("{e:?}"));
        let f = run(&p, &CpuBackend::default());
        let words = |name: &str| f.read(&p.plan, name).unwrap();
        (words("output.composed"), words("hair_depth"))
    };
    let (culled, all) = (frame("true"), frame("false"));
    assert!(culled.0 == all.0, "composed colour differs");
    assert!(culled.1 == all.1, "hair depth differs");
}

/// `sort.wave_aggregated_atomics` (ours) reorders segments within a bucket,
/// which the raster's atomics make irrelevant: the showcase rasterizes to
/// the same layers either way, from the same segments per bucket.
#[test]
fn sort_aggregation_changes_no_layer() {
    let frame = |aggregate: &str| {
        let params = [format!("sort.wave_aggregated_atomics={aggregate}")];
        let p = strandgraph::frame::prepare_with(
            &root().join("scenes/showcase.ron"),
            Some(&root().join("scenes/graphs/kulikov_visibility.ron")),
            Some((320, 180)),
            &params,
        )
        .unwrap_or_else(|e| panic!("{e:?}"));
        // Unaliased: the sort's buffers are read after the frame.
        let f = run(
            &p,
            &CpuBackend {
                alias: false,
                ..CpuBackend::default()
            },
        );
        let words = |name: &str| f.read(&p.plan, name).unwrap();
        let (offsets, mut sorted) = (words("sort_offsets"), words("sorted_segments"));
        // Each bucket's segments in id order: after the scatter, a bucket's
        // offset is its end, rising to the total (the arrival counter after
        // the buckets is 0 when sorting).
        let mut start = 0;
        for &end in &offsets {
            let end = end as usize;
            if end < start {
                break;
            }
            sorted[start..end].sort_unstable();
            start = end;
        }
        (
            sorted[..start].to_vec(),
            words("vis_atlas"),
            words("coverage_atlas"),
        )
    };
    let (aggregated, per_lane) = (frame("true"), frame("false"));
    assert!(!aggregated.0.is_empty(), "nothing sorted");
    assert!(
        aggregated.0 == per_lane.0,
        "buckets hold different segments"
    );
    assert!(aggregated.1 == per_lane.1, "vis_atlas differs");
    assert!(aggregated.2 == per_lane.2, "coverage_atlas differs");
}
