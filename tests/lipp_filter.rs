//! Lipp §3.3 on the CPU simulator, measured against the 8-sample reference
//! (the MSAA reference mode, `scenes/graphs/lipp_msaa.ron`) by mean FLIP over
//! the hair's screen bounds, far view at 960×540.
//!
//! What holds and is asserted: the alpha estimate of §3.3.3 (H_center /
//! (H_center + H_cons)) brings the filtered image closer to the reference
//! than the same filter with opaque output, and the filtered image stays
//! within a FLIP of 0.08 of it (a regression guard).
//!
//! What does not hold on our groom (printed, not asserted): Lipp Fig. 7's
//! claim that SWR 1+F recovers detail "comparable to MSAA 4-8" better than
//! SWR 1. Measured on this machine (CPU simulator): far 960×540, SWR 1
//! 0.052, SWR 1+F 0.062 (0.057 and 0.069, opaque 0.089, since the
//! distances scenes are lit by the studio environment map with a
//! prefiltered specular probe); mid 480×270, 0.045 vs 0.048; no setting of
//! front_threshold, radius, s_parallel, sigma_c or depth_threshold tried got
//! SWR 1+F below SWR 1 (front_threshold 10 m, i.e. no front blending: 0.053).
//! The procedural groom covers the hair's screen bounds densely, where the
//! filter's reconnection has little to reconnect and its blur along the
//! strand costs FLIP; the paper's thresholds are in an unstated depth unit.

use std::path::Path;
use strandgraph::compare::flip;
use strandgraph::frame::{Prepared, override_param, prepare};
use strandgraph::images::{Display, to_picture};
use strandgraph_cpu::CpuBackend;

const W: u32 = 960;
const H: u32 = 540;

fn render(p: &Prepared) -> image::RgbaImage {
    let frame = CpuBackend::default()
        .execute(&p.plan, &p.instance, &p.upload)
        .unwrap_or_else(|e| panic!("cpu backend failed: {e}"));
    let name = "output.final";
    let words = frame.read(&p.plan, name).unwrap();
    let r = p.plan.graph.resource_id(name).unwrap();
    to_picture(&p.plan, r, &words, W, H, Display::CLIP).unwrap()
}

/// The hair's rows and columns: where any of the images differs from the
/// background (the top-left pixel), padded by 4 pixels.
fn crop(images: &[&image::RgbaImage]) -> (u32, u32, u32, u32) {
    let bg = images[0].get_pixel(0, 0);
    let (mut x0, mut y0, mut x1, mut y1) = (W, H, 0, 0);
    for im in images {
        for (x, y, p) in im.enumerate_pixels() {
            if p != bg {
                (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
            }
        }
    }
    assert!(x0 <= x1, "no hair on screen");
    (
        x0.saturating_sub(4),
        y0.saturating_sub(4),
        (x1 + 5).min(W) - x0.saturating_sub(4),
        (y1 + 5).min(H) - y0.saturating_sub(4),
    )
}

#[test]
fn opacity_reconstruction_brings_the_filter_closer_to_msaa8() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("scenes/distances/far.ron");
    let mut p = prepare(&scene, None, Some((W, H))).unwrap_or_else(|e| panic!("{e:?}"));
    let filtered = render(&p);
    override_param(&mut p.plan, "filter.opacity_reconstruction=false").unwrap();
    let opaque = render(&p);
    override_param(&mut p.plan, "filter.enabled=false").unwrap();
    let single = render(&p);
    let msaa = root.join("scenes/graphs/lipp_msaa.ron");
    let reference = render(&prepare(&scene, Some(&msaa), Some((W, H))).unwrap());
    let (x, y, w, h) = crop(&[&reference, &single, &filtered]);
    let cut = |im: &image::RgbaImage| image::imageops::crop_imm(im, x, y, w, h).to_image();
    let (r, s, f, o) = (cut(&reference), cut(&single), cut(&filtered), cut(&opaque));
    let (ds, df, dop) = (
        flip(&r, &s).unwrap().mean,
        flip(&r, &f).unwrap().mean,
        flip(&r, &o).unwrap().mean,
    );
    eprintln!(
        "far view {W}x{H}, hair bounds {w}x{h}: mean FLIP against MSAA 8: SWR 1 {ds:.4}, \
         SWR 1+F {df:.4}, SWR 1+F without opacity reconstruction {dop:.4}"
    );
    if df >= dop || df > 0.08 {
        let dir = root.join("target/lipp_filter");
        std::fs::create_dir_all(&dir).unwrap();
        for (name, im) in [
            ("msaa8", &r),
            ("swr1", &s),
            ("swr1f", &f),
            ("swr1f_opaque", &o),
        ] {
            let big = image::imageops::resize(
                im,
                im.width() * 6,
                im.height() * 6,
                image::imageops::FilterType::Nearest,
            );
            big.save(dir.join(format!("{name}.png"))).unwrap();
        }
        panic!(
            "SWR 1+F {df} vs without alpha {dop} (limit 0.08); images (x6) in {}",
            dir.display()
        );
    }
}
