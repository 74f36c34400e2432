//! The built binary is self-contained: copied into an empty directory and
//! run from there, it renders a scene given by absolute path (the scene's
//! graph and grooms resolve relative to the scene file, the WGSL is built
//! into the binary), and `STRANDGRAPH_SHADERS` still points the GPU
//! backends at a directory of shaders instead.
//!
//! No Vulkan device is a failure, not a skip (as in tests/diff_ash.rs): CI
//! installs lavapipe.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh, empty directory holding only a copy of the binary.
fn relocated(name: &str) -> (PathBuf, PathBuf) {
    let dir = std::env::temp_dir().join(format!(
        "strandgraph-relocated-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let exe = dir.join("strandgraph");
    std::fs::copy(env!("CARGO_BIN_EXE_strandgraph"), &exe).unwrap();
    (dir, exe)
}

/// `strandgraph render <abs showcase> --size 160x90 -o out.png` from `dir`.
fn render(dir: &Path, exe: &Path, args: &[&str], shaders: Option<&Path>) -> Output {
    let scene = root().join("scenes/showcase.ron");
    assert!(scene.is_absolute());
    let mut cmd = Command::new(exe);
    cmd.current_dir(dir)
        .arg("render")
        .arg(&scene)
        .args(["--size", "160x90", "-o", "out.png"])
        .args(args)
        .env_remove("STRANDGRAPH_SHADERS");
    if let Some(s) = shaders {
        cmd.env("STRANDGRAPH_SHADERS", s);
    }
    // A test on another thread may fork while `fs::copy` still holds the
    // copy open for writing; the child inherits that descriptor and exec of
    // the copy fails with ETXTBSY until it execs or exits. Retry briefly.
    for _ in 0..50 {
        match cmd.output() {
            Err(e) if e.kind() == std::io::ErrorKind::ExecutableFileBusy => {
                std::thread::sleep(std::time::Duration::from_millis(20));
            }
            other => return other.expect("the copied binary runs"),
        }
    }
    panic!("the copied binary stayed busy (ETXTBSY) for a second")
}

/// The PNG exists at 160×90 and shows a picture: many colours, and most of
/// it differs from a flat fill.
fn assert_rendered(dir: &Path, o: &Output) {
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let png = dir.join("out.png");
    assert!(png.exists(), "no {}", png.display());
    let img = image::open(&png).unwrap().into_rgba8();
    assert_eq!(img.dimensions(), (160, 90));
    let mut colours: Vec<[u8; 4]> = img.pixels().map(|p| p.0).collect();
    let corner = colours[0];
    let differing = colours.iter().filter(|&&c| c != corner).count();
    colours.sort_unstable();
    colours.dedup();
    assert!(colours.len() >= 50, "only {} colours", colours.len());
    // The head and hair fill a good part of the frame.
    assert!(
        differing * 10 >= 160 * 90,
        "{differing} of {} pixels differ from the corner",
        160 * 90
    );
}

#[test]
fn a_copied_binary_renders_the_showcase_on_the_cpu_from_an_empty_directory() {
    let (dir, exe) = relocated("cpu");
    let o = render(&dir, &exe, &["--backend", "cpu"], None);
    assert_rendered(&dir, &o);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The GPU path needs WGSL: the embedded set, since there is no `shaders/`
/// anywhere near the copy. Then an empty `STRANDGRAPH_SHADERS` directory is
/// used instead of the embedded set, and the error names it.
#[test]
fn a_copied_binary_renders_on_ash_with_the_built_in_shaders_and_honours_the_override() {
    let (dir, exe) = relocated("ash");
    let o = render(&dir, &exe, &["--backend", "ash"], None);
    assert_rendered(&dir, &o);

    let empty = dir.join("no-shaders");
    std::fs::create_dir_all(&empty).unwrap();
    std::fs::remove_file(dir.join("out.png")).unwrap();
    let o = render(&dir, &exe, &["--backend", "ash"], Some(&empty));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "rendered without shaders:\n{err}");
    // miette wraps long paths; compare without its line breaks and frame.
    let unwrapped: String = err
        .chars()
        .filter(|c| !c.is_whitespace() && *c != '│')
        .collect();
    assert!(unwrapped.contains("no-shaders"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
