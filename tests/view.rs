//! `strandgraph view` in a real window: under Xvfb (scripts/test.sh
//! installs it), presenting through wgpu on lavapipe. The viewer renders
//! the built-in demo for 30 frames and saves its window; that picture must
//! be the one `render` writes for the same scene, camera and size on wgpu,
//! hair included. Fails, never skips, without Xvfb.

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

#[test]
fn the_viewer_window_shows_the_demo_as_render_writes_it() {
    let dir = out_dir();
    let (shot, rendered, coverage) = (
        dir.join("viewer.png"),
        dir.join("render.png"),
        dir.join("coverage.png"),
    );
    let _ = std::fs::remove_file(&shot);
    // -a: a free display number; the screen is larger than the window.
    run(
        Command::new("xvfb-run")
            .args([
                "-a",
                "-s",
                "-screen 0 800x600x24",
                env!("CARGO_BIN_EXE_strandgraph"),
            ])
            .args([
                "view",
                "--demo",
                "--size",
                SIZE,
                "--no-panel",
                "--frames",
                "30",
            ])
            .arg("--screenshot")
            .arg(&shot),
        "strandgraph view under xvfb-run",
    );
    run(
        Command::new(env!("CARGO_BIN_EXE_strandgraph"))
            .args([
                "render",
                "--demo",
                "--backend",
                "wgpu",
                "--size",
                SIZE,
                "-o",
            ])
            .arg(&rendered)
            .arg("--coverage")
            .arg(&coverage),
        "strandgraph render",
    );
    let shot = image::open(&shot).unwrap().to_rgba8();
    let rendered = image::open(&rendered).unwrap().to_rgba8();
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
