//! `strandgraph view` in a real window: under Xvfb (scripts/test.sh
//! installs it), presenting through wgpu on lavapipe. The viewer renders
//! the built-in demo for 30 frames and saves its window; that picture must
//! be the one `render` writes for the same scene, camera and size on wgpu,
//! hair included. Split-screen against a second graph, each half must be
//! that graph's render. Fails, never skips, without Xvfb.

use image::RgbaImage;
use std::path::{Path, PathBuf};
use std::process::Command;
use strandgraph::compare::flip;

const SIZE: &str = "320x180";

fn out_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("view");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(command: &mut Command, what: &str) {
    let out = command.output().unwrap_or_else(|e| {
        panic!("{what}: {e} (xvfb-run comes with xvfb: scripts/test.sh installs it)")
    });
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `strandgraph view ARGS --size SIZE --no-panel --screenshot SHOT` in a
/// virtual X server, the window read back.
fn view(args: &[&str], shot: &Path) -> RgbaImage {
    let _ = std::fs::remove_file(shot);
    // -a: a free display number; the screen is larger than the window.
    let mut c = Command::new("xvfb-run");
    c.args([
        "-a",
        "-s",
        "-screen 0 800x600x24",
        env!("CARGO_BIN_EXE_strandgraph"),
    ])
    .arg("view")
    .args(args)
    .args(["--size", SIZE, "--no-panel", "--screenshot"])
    .arg(shot);
    run(&mut c, "strandgraph view under xvfb-run");
    image::open(shot).unwrap().to_rgba8()
}

/// `strandgraph render ARGS --backend wgpu --size SIZE -o PICTURE`, read back.
fn render(args: &[&str], picture: &Path) -> RgbaImage {
    let mut c = Command::new(env!("CARGO_BIN_EXE_strandgraph"));
    c.arg("render")
        .args(args)
        .args(["--backend", "wgpu", "--size", SIZE, "-o"])
        .arg(picture);
    run(&mut c, "strandgraph render");
    image::open(picture).unwrap().to_rgba8()
}

#[test]
fn the_viewer_window_shows_the_demo_as_render_writes_it() {
    let dir = out_dir();
    let shot = view(&["--demo", "--frames", "30"], &dir.join("viewer.png"));
    let coverage = dir.join("coverage.png");
    let cov = coverage.to_str().unwrap();
    let rendered = render(&["--demo", "--coverage", cov], &dir.join("render.png"));
    let coverage = image::open(&coverage).unwrap().to_luma16();
    assert_eq!(
        shot.dimensions(),
        rendered.dimensions(),
        "the window is the render's size"
    );

    let diff = flip(&rendered, &shot).unwrap();
    assert!(
        diff.mean < 0.005,
        "viewer against render: mean FLIP {}",
        diff.mean
    );

    // Hair over the head: where `render` says the hair covers a pixel, the
    // window shows the render's colour there.
    let hair: Vec<(u32, u32)> = coverage
        .enumerate_pixels()
        .filter(|(_, _, c)| c.0[0] > u16::MAX / 2)
        .map(|(x, y, _)| (x, y))
        .collect();
    let pixels = shot.width() * shot.height();
    assert!(
        hair.len() as u32 * 20 > pixels,
        "only {} of {pixels} pixels have hair in the demo",
        hair.len()
    );
    let off: f64 = hair
        .iter()
        .map(|&(x, y)| {
            let (a, b) = (shot.get_pixel(x, y).0, rendered.get_pixel(x, y).0);
            (0..3).map(|c| f64::from(a[c].abs_diff(b[c]))).sum::<f64>() / 3.0
        })
        .sum::<f64>()
        / hair.len() as f64;
    assert!(
        off < 2.0,
        "hair pixels differ by {off:.2} of 255 on average"
    );
}

#[test]
fn split_screen_shows_each_graph_on_its_side() {
    let dir = out_dir();
    let root = env!("CARGO_MANIFEST_DIR");
    let scene = format!("{root}/scenes/showcase.ron");
    let other = format!("{root}/scenes/graphs/scheuermann.ron");
    let args = [scene.as_str(), "--compare", &other, "--frames", "3"];
    let shot = view(&args, &dir.join("split.png"));
    let left = render(&[&scene], &dir.join("split_kulikov.png"));
    let right = render(
        &[&scene, "--graph", &other],
        &dir.join("split_scheuermann.png"),
    );

    // The divider is a 2-point line in the middle: compare beside it.
    let (w, h) = shot.dimensions();
    let half = w / 2 - 4;
    let crop = |img: &RgbaImage, x: u32| image::imageops::crop_imm(img, x, 0, half, h).to_image();
    for (name, reference, x) in [("kulikov", &left, 0), ("scheuermann", &right, w - half)] {
        let diff = flip(&crop(reference, x), &crop(&shot, x)).unwrap();
        assert!(
            diff.mean < 0.005,
            "{name}'s side against its render: mean FLIP {}",
            diff.mean
        );
    }
    // Else the comparison proves nothing.
    let apart = flip(&crop(&left, w - half), &crop(&right, w - half)).unwrap();
    assert!(
        apart.mean > 0.02,
        "the two graphs render alike: mean FLIP {}",
        apart.mean
    );
}
