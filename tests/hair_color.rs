//! Hair colour from physics, seen as a user sees it: `scenes/showcase.ron`
//! rendered on the CPU simulator at 480×270 through the default display
//! transform, with only the hair's melanin changed between 0.1 and 0.9.
//! Over the pixels that change, dark hair must be dark (every sRGB channel
//! ≤ 80) and warm (red over blue ≥ 1.3); light hair light and yellow-brown.

use std::path::Path;
use strandgraph::frame::prepare;
use strandgraph::images::{Display, to_picture};
use strandgraph_cpu::CpuBackend;

const W: u32 = 480;
const H: u32 = 270;

/// The showcase with the hair's melanin set to `melanin`, rendered and displayed.
fn render(melanin: f32) -> image::RgbaImage {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("scenes/showcase.ron")).unwrap();
    let original = "material: (melanin: 0.9, roughness: 0.28),";
    assert!(
        text.contains(original),
        "the showcase's hair material changed: update this test"
    );
    let graph = root.join("scenes/graphs/kulikov.ron");
    let text = text
        .replace(
            original,
            &format!("material: (melanin: {melanin}, roughness: 0.28),"),
        )
        .replace(
            "graph: \"graphs/kulikov.ron\"",
            &format!("graph: {:?}", graph),
        );
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("hair_color");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("showcase_{melanin}.ron"));
    std::fs::write(&path, text).unwrap();
    let p = prepare(&path, None, Some((W, H))).unwrap_or_else(|e| panic!("{e:?}"));
    let frame = CpuBackend::default()
        .execute(&p.plan, &p.instance, &p.upload)
        .unwrap_or_else(|e| panic!("cpu backend failed: {e}"));
    let (r, _) = p.plan.graph.outputs[0];
    let name = &p.plan.graph.resources[r].name;
    let words = frame.read(&p.plan, name).unwrap();
    let img = to_picture(&p.plan, r, &words, W, H, Display::default()).unwrap();
    img.save(dir.join(format!("showcase_{melanin}.png")))
        .unwrap();
    img
}

#[test]
fn melanin_gives_dark_warm_hair_and_light_yellow_brown_hair() {
    let (light, dark) = (render(0.1), render(0.9));
    let mut sum = [[0f64; 3]; 2];
    let mut n = 0u32;
    for (a, b) in light.pixels().zip(dark.pixels()) {
        if (0..3).any(|k| a[k].abs_diff(b[k]) > 2) {
            for k in 0..3 {
                sum[0][k] += f64::from(a[k]);
                sum[1][k] += f64::from(b[k]);
            }
            n += 1;
        }
    }
    assert!(n > 2000, "only {n} pixels changed");
    let mean = sum.map(|s| s.map(|c| c / f64::from(n)));
    let [light, dark] = mean;
    eprintln!("changed pixels: {n}; mean sRGB at melanin 0.1 {light:.1?}, at 0.9 {dark:.1?}");
    assert!(
        dark.iter().all(|&c| c <= 80.0),
        "dark hair is not dark: {dark:?}"
    );
    assert!(dark[0] / dark[2] >= 1.3, "dark hair is not warm: {dark:?}");
    // Light and yellow-brown: every channel at least 40% brighter than the
    // dark hair's (over the same pixels, so both include the R lobe's white
    // highlight and the thin strands' background), red ≥ green > blue.
    assert!(
        (0..3).all(|k| light[k] >= 1.4 * dark[k]),
        "light hair is not light: {light:?}"
    );
    assert!(
        light[0] >= light[1] && light[1] > light[2],
        "not yellow-brown: {light:?}"
    );
    assert!(light[0] / light[2] >= 1.3, "not yellow-brown: {light:?}");
}
