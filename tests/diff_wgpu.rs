//! Differential test: the Kulikov visibility pipeline on the CPU simulator
//! and on wgpu (lavapipe in CI, any Vulkan adapter elsewhere) must agree.
//!
//! Both sides snap to the same fixed-point grid and pack visibility the same
//! way (docs/architecture.md, "Agreement across backends"), so the three visibility
//! layers must be identical on at least 99.9% of covered atlas texels; only
//! a float rounding that flips a snap may differ. Coverage (an additive
//! atomic sum) must agree within a small bound.
//!
//! No adapter is a failure, not a skip: CI installs lavapipe
//! (`scripts/test.sh`).

use std::path::{Path, PathBuf};
use strandgraph::compare::flip;
use strandgraph::frame::{Prepared, override_param, prepare};
use strandgraph::images::{Display, to_picture};
use strandgraph_cpu::CpuBackend;
use strandgraph_wgpu::WgpuBackend;

// Rows of 250 texels are not a multiple of wgpu's 256-byte copy alignment
// in either image format, so reading images back exercises the unpadding.
const W: u32 = 250;
const H: u32 = 140;
const EMPTY: u32 = u32::MAX;
/// Final images: the mean FLIP bound, and the bound on any pixel.
const MAX_MEAN_FLIP: f32 = 0.01;
const MAX_PIXEL_FLIP: f32 = 0.5;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Where failing comparisons write images: `$STRANDGRAPH_DIFF_OUT`, else
/// `target/diff_wgpu`.
fn out_dir() -> PathBuf {
    let dir = std::env::var_os("STRANDGRAPH_DIFF_OUT")
        .map_or_else(|| root().join("target/diff_wgpu"), PathBuf::from);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes both backends' `debug_layers` and a diff image (red: pixels that differ).
fn write_images(p: &Prepared, cpu: &[u32], gpu: &[u32]) -> PathBuf {
    let dir = out_dir();
    let r = p.plan.graph.resource_id("debug_layers").unwrap();
    for (name, words) in [("cpu", cpu), ("wgpu", gpu)] {
        if let Some(img) = to_picture(&p.plan, r, words, W, H, Display::CLIP) {
            img.save(dir.join(format!("debug_layers.{name}.png")))
                .unwrap();
        }
    }
    let mut diff = image::RgbaImage::new(W, H);
    for (i, px) in diff.pixels_mut().enumerate() {
        let (a, b) = (cpu.get(i), gpu.get(i));
        *px = if a == b {
            let g = a.map_or(0, |w| (w >> 24) as u8 / 2);
            image::Rgba([g, g, g, 255])
        } else {
            image::Rgba([255, 0, 0, 255])
        };
    }
    diff.save(dir.join("debug_layers.diff.png")).unwrap();
    dir
}

/// `STRANDGRAPH_DIFF_PARAMS` (comma-separated `pass.key=value`) adds
/// overrides, to bisect a disagreement on a new device by ablation.
#[test]
fn showcase_visibility_matches_cpu_on_wgpu() {
    let extra = std::env::var("STRANDGRAPH_DIFF_PARAMS").unwrap_or_default();
    let overrides: Vec<&str> = extra.split(',').filter(|s| !s.is_empty()).collect();
    compare_visibility(&format!("default {extra}"), &overrides);
}

/// Every ablation changes how the raster works, never what it writes: each
/// variant must agree with the CPU as the default does.
#[test]
fn raster_ablations_match_cpu_on_wgpu() {
    for (name, overrides) in [
        (
            "no request stacks",
            &[
                "raster.pixel_request_stack=false",
                "raster.depth_test_stack=false",
            ][..],
        ),
        ("nested loops", &["raster.loop_flattening=false"][..]),
        (
            "no sort, no last-layer cull",
            &["raster.morton_sort=false", "raster.last_layer_cull=false"][..],
        ),
    ] {
        compare_visibility(name, overrides);
    }
}

fn compare_visibility(variant: &str, overrides: &[&str]) {
    eprintln!("--- {variant}");
    let p = prepare_visibility(overrides);
    let frames = Frames::run(&p);
    frames.print_timings();

    // Everything before the raster is integer bookkeeping: exact.
    for name in ["lod_models", "lod_args", "atlas_tiles", "raster_args"] {
        assert_eq!(frames.cpu(name), frames.gpu(name), "{name} differs");
    }
    report_clip_positions(&frames);
    report_depth_and_cull(&frames);
    let atlas = atlas_agreement(&frames);
    let (cd, gd) = (frames.cpu("debug_layers"), frames.gpu("debug_layers"));
    let (layers_same, output_same) = image_agreement(&frames, &cd, &gd);

    let pass = atlas.covered > 1000
        && atlas.agreement >= 0.999
        && atlas.coverage_error <= 0.002
        && atlas.texel_error <= 0.002
        && layers_same >= 0.999
        && output_same >= 0.99;
    if !pass {
        let dir = write_images(&p, &cd, &gd);
        panic!(
            "{variant}: CPU and wgpu visibility differ (need >= 99.9% identical covered texels, coverage within 0.2%, \
             at least 1000 covered texels; images: 99.9% of debug_layers and 99% of output words identical):\n{}\nimages in {}",
            atlas.differing.join("\n"),
            dir.display()
        );
    }
}

/// The showcase through the visibility graph at `W`×`H`, with `overrides`.
fn prepare_visibility(overrides: &[&str]) -> Prepared {
    let graph = root().join("scenes/graphs/kulikov_visibility.ron");
    let mut p = prepare(
        &root().join("scenes/showcase.ron"),
        Some(&graph),
        Some((W, H)),
    )
    .unwrap_or_else(|e| panic!("{e:?}"));
    for o in overrides {
        override_param(&mut p.plan, o).unwrap_or_else(|e| panic!("{e:?}"));
    }
    p
}

/// One frame on the CPU simulator, as wgpu runs it: without aliasing, so
/// every transient can be read back at the end (wgpu cannot alias either);
/// lavapipe's subgroups are 8 wide.
fn cpu_frame(p: &Prepared) -> strandgraph_cpu::Frame<'static> {
    CpuBackend {
        subgroup_width: 8,
        alias: false,
        ..CpuBackend::default()
    }
    .execute(&p.plan, &p.instance, &p.upload)
    .unwrap_or_else(|e| panic!("cpu backend failed: {e}"))
}

/// One frame of a prepared scene on both backends.
struct Frames<'p> {
    p: &'p Prepared,
    cpu: strandgraph_cpu::Frame<'static>,
    gpu: strandgraph_wgpu::Frame,
}

impl<'p> Frames<'p> {
    fn run(p: &'p Prepared) -> Self {
        let gpu = WgpuBackend::default()
            .execute(&p.plan, &p.instance, &p.upload)
            .unwrap_or_else(|e| {
                panic!(
                    "wgpu backend failed: {e}\n(no adapter? install a Vulkan driver: \
                     apt-get install mesa-vulkan-drivers libvulkan1, or run scripts/test.sh)"
                )
            });
        for n in &gpu.notes {
            eprintln!("wgpu: {n}");
        }
        Self {
            p,
            cpu: cpu_frame(p),
            gpu,
        }
    }

    fn cpu(&self, name: &str) -> Vec<u32> {
        self.cpu.read(&self.p.plan, name).unwrap()
    }

    /// A resource's words after the frame (it must have memory on wgpu).
    fn gpu(&self, name: &str) -> Vec<u32> {
        self.gpu
            .read(&self.p.plan, name)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .unwrap_or_else(|| panic!("{name}: no memory on wgpu"))
    }

    fn print_timings(&self) {
        eprintln!("{:<16} {:>12} {:>12}", "pass", "cpu ms", "wgpu ms");
        for (c, g) in self.cpu.timings.iter().zip(&self.gpu.timings) {
            eprintln!("{:<16} {:>12.3} {:>12.3}", c.name, c.millis, g.millis);
        }
    }
}

/// Skinned clip positions are float: report how far apart they are (a
/// difference can flip a 1/256-pixel snap in the raster).
fn report_clip_positions(frames: &Frames) {
    let (cc, gc) = (frames.cpu("clip_positions"), frames.gpu("clip_positions"));
    let ulps = cc
        .iter()
        .zip(&gc)
        .map(|(a, b)| (*a as i32).abs_diff(*b as i32))
        .collect::<Vec<_>>();
    eprintln!(
        "clip_positions: {} of {} words differ, at most {} ulp",
        ulps.iter().filter(|&&u| u > 0).count(),
        ulps.len(),
        ulps.iter().max().unwrap_or(&0)
    );
    let bucket = |lo: u32, hi: u32| ulps.iter().filter(|&&u| u >= lo && u < hi).count();
    eprintln!(
        "  by ulp: 1: {}, 2-15: {}, 16-1023: {}, >= 1024: {}",
        bucket(1, 2),
        bucket(2, 16),
        bucket(16, 1024),
        bucket(1024, u32::MAX)
    );
    if let Some((i, _)) = ulps.iter().enumerate().max_by_key(|(_, u)| **u) {
        let v = i / 4 * 4;
        let f = |w: &[u32]| {
            w[v..v + 4]
                .iter()
                .map(|&x| f32::from_bits(x))
                .collect::<Vec<_>>()
        };
        eprintln!(
            "  worst: vertex {} cpu {:?} wgpu {:?}",
            v / 4,
            f(&cc),
            f(&gc)
        );
    }
}

/// The head's depth (hardware raster on the GPU) and the cull's decisions
/// (occlusion against it) feed the raster too: report where they differ.
fn report_depth_and_cull(frames: &Frames) {
    let (cd, gd) = (frames.cpu("scene.depth"), frames.gpu("scene.depth"));
    let depth_words = cd.iter().zip(&gd).filter(|(a, b)| a != b).count();
    let (cs, gs) = (
        frames.cpu("segment_visibility"),
        frames.gpu("segment_visibility"),
    );
    let culled_bits: u32 = cs.iter().zip(&gs).map(|(a, b)| (a ^ b).count_ones()).sum();
    eprintln!(
        "scene.depth: {depth_words} of {} words differ; segment_visibility: {culled_bits} segments decided differently",
        cd.len()
    );
}

/// How far the two backends' visibility and coverage atlases agree.
struct AtlasAgreement {
    /// Texels either side covers.
    covered: usize,
    /// The share of covered texels whose three layers are identical.
    agreement: f64,
    /// How far apart the coverage sums are, relative to the CPU's.
    coverage_error: f64,
    /// How far apart the numbers of covered texels are, relative to the CPU's.
    texel_error: f64,
    /// The first texels that differ, described.
    differing: Vec<String>,
}

fn atlas_agreement(frames: &Frames) -> AtlasAgreement {
    let (cv, gv) = (frames.cpu("vis_atlas"), frames.gpu("vis_atlas"));
    let (cc, gc) = (frames.cpu("coverage_atlas"), frames.gpu("coverage_atlas"));
    assert_eq!(cv.len(), gv.len());
    assert_eq!(cc.len(), gc.len());
    assert_eq!(cv.len(), 3 * cc.len(), "three visibility layers");
    let (covered, same, differing) = compare_texels(&cv, &cc, &gv, &gc);

    let filled = |v: &[u32]| v.iter().filter(|&&w| w != EMPTY).count();
    let covered_cpu = cc.iter().filter(|&&c| c > 0).count();
    let covered_gpu = gc.iter().filter(|&&c| c > 0).count();
    let sum = |v: &[u32]| v.iter().map(|&c| u64::from(c)).sum::<u64>();
    let (sum_cpu, sum_gpu) = (sum(&cc), sum(&gc));
    let agreement = same as f64 / covered.max(1) as f64;
    let coverage_error = (sum_cpu as f64 - sum_gpu as f64).abs() / sum_cpu.max(1) as f64;
    let texel_error = covered_cpu.abs_diff(covered_gpu) as f64 / covered_cpu.max(1) as f64;
    eprintln!(
        "covered texels: cpu {covered_cpu}, wgpu {covered_gpu}; layers identical on {same}/{covered} ({:.4}%); \
         filled layer words cpu {} wgpu {}; coverage sum cpu {sum_cpu} wgpu {sum_gpu} ({:.4}% apart)",
        agreement * 100.0,
        filled(&cv),
        filled(&gv),
        coverage_error * 100.0
    );
    AtlasAgreement {
        covered,
        agreement,
        coverage_error,
        texel_error,
        differing,
    }
}

/// Over texels either side covers: how many, how many have identical
/// layers, and the first dozen that do not, described.
fn compare_texels(cv: &[u32], cc: &[u32], gv: &[u32], gc: &[u32]) -> (usize, usize, Vec<String>) {
    let texels = cc.len();
    let mut covered = 0usize;
    let mut same = 0usize;
    let mut differing = Vec::new();
    for t in 0..texels {
        if cc[t] == 0 && gc[t] == 0 {
            continue;
        }
        covered += 1;
        let layers = |v: &[u32]| [v[t], v[texels + t], v[2 * texels + t]];
        if layers(cv) == layers(gv) {
            same += 1;
        } else if differing.len() < 12 {
            differing.push(format!(
                "texel {t} (tile {}, x {}, y {}): cpu {:08x?} cov {} | wgpu {:08x?} cov {}",
                t / 4096,
                t % 64,
                (t % 4096) / 64,
                layers(cv),
                cc[t],
                layers(gv),
                gc[t]
            ));
        }
    }
    (covered, same, differing)
}

/// The share of identical words of the debug view (`cd`, `gd`), and of
/// output channels within tolerance.
fn image_agreement(frames: &Frames, cd: &[u32], gd: &[u32]) -> (f64, f64) {
    let (co, go) = (frames.cpu("output"), frames.gpu("output"));
    let layers_same = identical(cd, gd);
    // The output is shaded in float (opaque lighting, coverage resolve): compare
    // its rgba16float channels with a tolerance, not bit for bit.
    let (ch, gh) = (halves(&co), halves(&go));
    assert_eq!(ch.len(), gh.len(), "output sizes differ");
    let close = ch
        .iter()
        .zip(&gh)
        .filter(|(a, b)| (*a - *b).abs() <= 2e-3 + 2e-3 * a.abs())
        .count() as f64
        / ch.len().max(1) as f64;
    let worst = ch
        .iter()
        .zip(&gh)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    eprintln!(
        "debug_layers words identical: {:.4}%; output channels within 0.2%: {:.4}% (worst {worst}), bit-identical words {:.2}%",
        layers_same * 100.0,
        close * 100.0,
        identical(&co, &go) * 100.0
    );
    (layers_same, close)
}

/// The share of words two images have in common.
fn identical(a: &[u32], b: &[u32]) -> f64 {
    assert_eq!(a.len(), b.len(), "image sizes differ");
    a.iter().zip(b).filter(|(x, y)| x == y).count() as f64 / a.len().max(1) as f64
}

/// An rgba16float image's channels.
fn halves(w: &[u32]) -> Vec<f32> {
    w.iter()
        .flat_map(|x| [x & 0xFFFF, x >> 16])
        .map(|h| half::f16::from_bits(h as u16).to_f32())
        .collect()
}

/// `strandgraph render --backend all` runs both backends, prints their
/// per-pass times side by side and says how the plan degraded on wgpu.
#[test]
fn render_backend_all_prints_both_timings() {
    let out = out_dir().join("cli");
    std::fs::create_dir_all(&out).unwrap();
    let main = out.join("showcase.png");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_strandgraph"))
        .current_dir(root())
        .args([
            "render",
            "scenes/showcase.ron",
            "--graph",
            "scenes/graphs/kulikov_visibility.ron",
            "--size",
            "128x72",
            "--backend",
            "all",
            "-o",
        ])
        .arg(&main)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stdout}\n{stderr}");
    for needle in [
        "cpu wall ms",
        "wgpu GPU ms",
        "one queue",
        "cannot alias",
        "raster",
    ] {
        assert!(stdout.contains(needle), "no `{needle}` in:\n{stdout}");
    }
    assert!(main.exists() && main.with_extension("wgpu.png").exists());
}

/// The full Kulikov graph (shading and composition, `kulikov.compose` as
/// render pipelines with premultiplied blending and a hair-depth pipeline):
/// the composed image agrees with the CPU within float shading tolerance.
#[test]
fn showcase_composed_matches_cpu_on_wgpu() {
    let (w, h) = (96, 54);
    let graph = root().join("scenes/graphs/kulikov.ron");
    let p = prepare(
        &root().join("scenes/showcase.ron"),
        Some(&graph),
        Some((w, h)),
    )
    .unwrap_or_else(|e| panic!("{e:?}"));
    let gpu = WgpuBackend::default()
        .execute(&p.plan, &p.instance, &p.upload)
        .unwrap_or_else(|e| panic!("wgpu backend failed: {e}"));
    let cpu = cpu_frame(&p);
    let name = "output.composed";
    let c = cpu.read(&p.plan, name).unwrap();
    let g = gpu.read(&p.plan, name).unwrap().unwrap();
    assert_eq!(c.len(), g.len());
    // The gate: mean FLIP at most 0.01 and no pixel beyond a stated
    // bound. Shading is float on both sides (different FMA contraction and
    // transcendentals), so single pixels may differ by a few code values.
    let r = p.plan.graph.resource_id(name).unwrap();
    let (cpu_img, gpu_img) = (
        to_picture(&p.plan, r, &c, w, h, Display::CLIP).unwrap(),
        to_picture(&p.plan, r, &g, w, h, Display::CLIP).unwrap(),
    );
    let d = flip(&cpu_img, &gpu_img).unwrap();
    eprintln!(
        "{name}: mean FLIP {:.5}, max {:.4} at {:?}, {} pixels over {MAX_PIXEL_FLIP}",
        d.mean,
        d.max,
        d.max_at,
        d.pixels_over(MAX_PIXEL_FLIP)
    );
    // Hair depth written by kulikov.compose where coverage reaches the threshold.
    let cd = cpu.read(&p.plan, "hair_depth").unwrap();
    let gd = gpu.read(&p.plan, "hair_depth").unwrap().unwrap();
    assert_eq!(cd.len(), gd.len());
    let depth_close = cd
        .iter()
        .zip(&gd)
        .filter(|(a, b)| (f32::from_bits(**a) - f32::from_bits(**b)).abs() <= 1e-5)
        .count() as f64
        / cd.len() as f64;
    eprintln!("hair_depth: {:.3}% within 1e-5", depth_close * 100.0);
    if d.mean > MAX_MEAN_FLIP || d.max > MAX_PIXEL_FLIP || depth_close < 0.99 {
        let dir = out_dir();
        cpu_img.save(dir.join("composed.cpu.png")).unwrap();
        gpu_img.save(dir.join("composed.wgpu.png")).unwrap();
        d.error_map.save(dir.join("composed.flip.png")).unwrap();
        panic!(
            "composed images differ: mean FLIP {} (max {MAX_MEAN_FLIP}), worst pixel {} at {:?} \
             (max {MAX_PIXEL_FLIP}), hair depth {:.3}% within 1e-5; images in {}",
            d.mean,
            d.max,
            d.max_at,
            depth_close * 100.0,
            dir.display()
        );
    }
}
