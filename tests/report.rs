//! `strandgraph report` end to end: a small report rendered on this
//! machine (the CPU simulator and wgpu on lavapipe), opened in headless
//! Chromium. The page checks itself (every <img> decoded, every chart's
//! SVG present, no script error) into `<body data-report-check>`, which
//! `--dump-dom` prints. Then the same page regenerated with `--from` into
//! another directory, as the H100 report is made, and once more cut to a
//! 64x48 crop as JPEG, as the committed report is.
//!
//! Chromium is required: the test fails, not skips, without it
//! (scripts/test.sh installs Debian's `chromium`).

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const CHROMIUM: &str = "/usr/bin/chromium";
/// Kulikov's rows have a reference (FLIP, maps, the Pareto chart);
/// Scheuermann's has none yet (its time, "—" for FLIP). Few rows, and no
/// pipeline whose reference takes long on the CPU simulator (lavapipe's
/// references fall back to it).
const ROWS: [&str; 3] = [
    "Kulikov: all optimisations",
    "Kulikov: no sort",
    "Scheuermann: Z-primed",
];

fn strandgraph() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_strandgraph"));
    cmd.current_dir(env!("CARGO_MANIFEST_DIR"));
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        cmd.env("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    cmd
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("strandgraph-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Runs `cmd` to its end or kills it after `limit` (a hung browser must
/// fail the test, not stall it). Its output is drained while it runs: a
/// DOM over the pipe's 64 KiB would otherwise block the browser forever.
fn run_for(mut cmd: Command, limit: Duration) -> Output {
    let child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let pid = child.id();
    let (done, result) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = done.send(child.wait_with_output().expect("output"));
    });
    match result.recv_timeout(limit) {
        Ok(out) => out,
        Err(_) => {
            let _ = Command::new("kill")
                .args(["-KILL", &pid.to_string()])
                .status();
            panic!("{cmd:?} ran past {limit:?}");
        }
    }
}

/// The page's DOM after load, and Chromium's log.
fn open_in_chromium(index: &Path) -> (String, String) {
    assert!(
        Path::new(CHROMIUM).exists(),
        "{CHROMIUM} is missing: install Debian's `chromium` package (scripts/test.sh does)"
    );
    let profile = scratch("report-chromium-profile");
    let mut cmd = Command::new(CHROMIUM);
    cmd.args(["--headless", "--no-sandbox", "--disable-gpu"])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(["--enable-logging=stderr", "--v=0"])
        // Load events run, then the DOM is printed (virtual time: no wait).
        .args(["--virtual-time-budget=10000", "--dump-dom"])
        .arg(format!(
            "file://{}",
            index.canonicalize().expect("index.html").display()
        ));
    let out = run_for(cmd, Duration::from_secs(120));
    let _ = std::fs::remove_dir_all(&profile);
    assert!(out.status.success(), "chromium: {out:?}");
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The value of `attr` on the page's <body>.
fn body_attr<'a>(dom: &'a str, attr: &str) -> Option<&'a str> {
    let body = &dom[dom.find("<body")?..];
    let body = &body[..body.find('>')?];
    let at = body.find(&format!("{attr}=\""))? + attr.len() + 2;
    Some(&body[at..at + body[at..].find('"')?])
}

/// The page loads in Chromium with every picture and chart and no
/// console error; its DOM.
fn check_page(index: &Path, json: &serde_json::Value) -> String {
    let (dom, log) = open_in_chromium(index);
    let check = body_attr(&dom, "data-report-check");
    assert_eq!(
        check,
        Some("ok"),
        "{}: the page's self-check ({:?}); chromium log:\n{log}",
        index.display(),
        body_attr(&dom, "data-report-counts")
    );
    // Console messages reach the log as `INFO:CONSOLE:line] "text"`; the page writes
    // none, so any is an error or a warning to look at.
    let console: Vec<&str> = log.lines().filter(|l| l.contains(":CONSOLE")).collect();
    assert!(console.is_empty(), "console output: {console:#?}");
    let images: usize = body_attr(&dom, "data-expect-images")
        .unwrap()
        .parse()
        .unwrap();
    let charts: usize = body_attr(&dom, "data-expect-charts")
        .unwrap()
        .parse()
        .unwrap();
    // Two sections (cpu, wgpu), each with a Pareto chart (Kulikov has a
    // reference) and per-pass bars for each of its two pipelines.
    let (pareto, passes) = expected_charts(json);
    assert_eq!(images, expected_images(json), "{}", index.display());
    assert_eq!((pareto, passes), (2, 2 * 2), "{}", index.display());
    assert_eq!(charts, pareto + passes, "{}", index.display());
    assert_eq!(dom.matches("data-chart=\"pareto\"").count(), pareto);
    assert_eq!(dom.matches("data-chart=\"passes\"").count(), passes);
    // A row without a reference shows its time and no FLIP.
    let unreferenced = json["cells"]
        .as_array()
        .unwrap()
        .iter()
        .any(|c| c["flip"].is_null());
    assert_eq!(dom.contains("no reference"), unreferenced);
    dom
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Every picture path that `json` names.
fn pictures(json: &serde_json::Value) -> Vec<&str> {
    let mut out: Vec<&str> = json["cells"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|c| ["picture", "flip_map", "reference_picture"].map(|k| c[k].as_str()))
        .flatten()
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// Every file under `dir`, relative, with `/`.
fn files_under(dir: &Path, root: &Path, out: &mut Vec<String>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let path = e.unwrap().path();
        if path.is_dir() {
            files_under(&path, root, out);
        } else {
            let rel = path.strip_prefix(root).unwrap();
            out.push(rel.to_string_lossy().replace('\\', "/"));
        }
    }
}

/// stderr as words (miette wraps its lines and draws a margin).
fn words(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr)
        .replace('│', " ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// `report --from` of `json` into `out` with `extra` flags.
fn report_from(json: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut cmd = strandgraph();
    cmd.args(["report", "--from"])
        .arg(json)
        .arg("-o")
        .arg(out)
        .args(extra);
    run_for(cmd, Duration::from_secs(60))
}

/// The run cut to 64x48 at the frame's centre, as JPEG: the page passes
/// the same check, says what the crop is, and holds only 64x48 JPEGs.
fn check_cropped(run: &Path) {
    let small = scratch("report-small");
    let out = report_from(
        &run.join("bench.json"),
        &small,
        &["--crop", "64x48", "--jpeg", "80"],
    );
    assert!(out.status.success(), "{}", words(&out));
    let json = read_json(&small.join("bench.json"));
    let dom = check_page(&small.join("index.html"), &json);
    let note = "1:1 crop 64x48 at (48, 21) of the 160x90 frame; FLIP is over the whole frame, coverage error over its pixels with hair";
    assert!(dom.contains(note), "no crop note in the page");
    let named = pictures(&json);
    for rel in &named {
        let bytes = std::fs::read(small.join(rel)).unwrap();
        assert!(
            rel.ends_with(".jpg") && bytes.starts_with(&[0xFF, 0xD8, 0xFF]),
            "{rel}"
        );
        let size = image::load_from_memory_with_format(&bytes, image::ImageFormat::Jpeg)
            .map(|i| (i.width(), i.height()));
        assert_eq!(size.ok(), Some((64, 48)), "{rel}");
    }
    let mut files = Vec::new();
    files_under(&small.join("pictures"), &small, &mut files);
    files.sort();
    assert_eq!(files, named, "only the page's pictures are copied");
    let _ = std::fs::remove_dir_all(&small);
}

/// The cells' sections, as (view, backend), in order of appearance.
fn section_of(c: &serde_json::Value) -> (&str, &str) {
    (c["view"].as_str().unwrap(), c["backend"].as_str().unwrap())
}

/// The pictures the page should hold, counted from bench.json: per view
/// and backend the viewer, each reference once (pipelines sharing a
/// reference graph share its picture), and every cell's picture and FLIP
/// map.
fn expected_images(json: &serde_json::Value) -> usize {
    let cells = json["cells"].as_array().unwrap();
    let mut sections: Vec<(&str, &str)> = Vec::new();
    let mut references: Vec<((&str, &str), &str)> = Vec::new();
    let mut n = 0;
    for c in cells {
        let section = section_of(c);
        if !sections.contains(&section) {
            sections.push(section);
        }
        if let Some(r) = c["reference_picture"].as_str() {
            let key = c["flip_reference"].as_str().unwrap_or(r);
            if !references.contains(&(section, key)) {
                references.push((section, key));
            }
        }
        n += usize::from(c["picture"].is_string()) + usize::from(c["flip_map"].is_string());
    }
    n + sections.len() + references.len()
}

/// The charts the page should hold, counted from bench.json: per view and
/// backend a time-versus-FLIP chart where a row has a FLIP, and per-pass
/// bars for each pipeline whose measured rows have passes.
fn expected_charts(json: &serde_json::Value) -> (usize, usize) {
    let cells = json["cells"].as_array().unwrap();
    let measured = |c: &&serde_json::Value| c["skipped"].is_null();
    let mut pareto: Vec<(&str, &str)> = Vec::new();
    let mut passes: Vec<((&str, &str), &str)> = Vec::new();
    for c in cells.iter().filter(measured) {
        let section = section_of(c);
        if c["flip"].is_number() && !pareto.contains(&section) {
            pareto.push(section);
        }
        let pipeline = (section, c["pipeline"].as_str().unwrap());
        let has_passes = c["passes"].as_array().is_some_and(|p| !p.is_empty());
        if has_passes && !passes.contains(&pipeline) {
            passes.push(pipeline);
        }
    }
    (pareto.len(), passes.len())
}

#[test]
fn report_renders_and_loads_in_chromium() {
    let t0 = Instant::now();
    let dir = scratch("report");
    let mut cmd = strandgraph();
    cmd.args([
        "report",
        "scenes/distances/far.ron",
        "--backend",
        "cpu,wgpu",
    ])
    .args(["--quick", "--size", "160x90", "--frames", "1", "-o"])
    .arg(&dir);
    for row in ROWS {
        cmd.args(["--row", row]);
    }
    let out = run_for(cmd, Duration::from_secs(600));
    assert!(
        out.status.success(),
        "report: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = read_json(&dir.join("bench.json"));
    // Rewritten after every row while it ran; complete now.
    assert_eq!(json["partial"], false);
    for cell in json["cells"].as_array().unwrap() {
        let pic = cell["picture"].as_str().expect("every cell has a picture");
        assert!(dir.join(pic).is_file(), "{pic}");
        // A map and a reference exactly where there is a FLIP; Kulikov
        // has a reference.
        let judged = cell["flip"].is_number();
        assert!(judged || cell["pipeline"] != "Kulikov", "{cell}");
        assert_eq!(cell["flip_map"].is_string(), judged, "{cell}");
        assert_eq!(cell["reference_picture"].is_string(), judged, "{cell}");
        for key in ["flip_map", "reference_picture"] {
            if let Some(p) = cell[key].as_str() {
                assert!(dir.join(p).is_file(), "{p}");
            }
        }
    }
    check_page(&dir.join("index.html"), &json);

    // The page again from the run's bench.json, elsewhere: the pictures
    // come along.
    let again = scratch("report-again");
    let out = report_from(&dir.join("bench.json"), &again, &[]);
    assert!(out.status.success(), "{out:?}");
    check_page(&again.join("index.html"), &json);
    check_cropped(&dir);
    eprintln!("report test took {:.0} s", t0.elapsed().as_secs_f64());
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&again);
}

/// A bench.json without pictures is refused, naming the file and why.
#[test]
fn from_a_bench_without_pictures_says_so() {
    let dir = scratch("report-nopictures");
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("bench.json");
    let cell = r#"{"backend":"cpu","pipeline":"Kulikov","variant":"all optimisations","view":"far",
        "frame":{"median_ms":1.0,"min_ms":1.0,"max_ms":1.0},"passes":[]}"#;
    let text = format!(r#"{{"size":"160x90","frames":1,"warmup":0,"cells":[{cell}]}}"#);
    std::fs::write(&json, text).unwrap();
    let out = report_from(&json, &dir, &[]);
    let err = words(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("bench.json") && err.contains("without --pictures"),
        "{err}"
    );
    assert!(!dir.join("index.html").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A crop must lie inside the pictures: one larger is refused, naming the
/// picture and its size. And a picture the page does not show (a skipped
/// cell's) is not copied.
#[test]
fn a_crop_larger_than_the_pictures_is_refused() {
    let dir = scratch("report-bigcrop");
    std::fs::create_dir_all(dir.join("pictures")).unwrap();
    for name in ["a.png", "unshown.png"] {
        image::RgbaImage::new(16, 8)
            .save(dir.join("pictures").join(name))
            .unwrap();
    }
    let shown = r#"{"backend":"cpu","pipeline":"Kulikov","variant":"all optimisations","view":"far",
        "frame":{"median_ms":1.0,"min_ms":1.0,"max_ms":1.0},"passes":[],"picture":"pictures/a.png"}"#;
    let skipped = r#"{"backend":"cpu","pipeline":"Kulikov","variant":"no sort","view":"far",
        "skipped":"x","picture":"pictures/unshown.png"}"#;
    let text = format!(r#"{{"size":"16x8","frames":1,"warmup":0,"cells":[{shown},{skipped}]}}"#);
    let json = dir.join("bench.json");
    std::fs::write(&json, text).unwrap();
    let other = scratch("report-bigcrop-out");
    let out = report_from(&json, &other, &["--crop", "32x8"]);
    let err = words(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("pictures/a.png is 16x8"), "{err}");
    assert!(!other.join("index.html").exists());
    let out = report_from(&json, &other, &["--crop", "far=16x4+0+4"]);
    assert!(out.status.success(), "{}", words(&out));
    assert_eq!(
        image::image_dimensions(other.join("pictures/a.png")).unwrap(),
        (16, 4)
    );
    assert!(!other.join("pictures/unshown.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&other);
}
