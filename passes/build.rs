//! Embeds every `.wgsl` file under the workspace's `shaders/` in the crate
//! (`wgsl::EMBEDDED`), so a built binary renders wherever it is copied to.
//!
//! Writes `$OUT_DIR/embedded_shaders.rs`: a slice of `(path relative to
//! shaders/ with '/' separators, include_str!(absolute path))`, sorted by
//! path. `include_str!` makes rustc track each file's contents; the
//! `rerun-if-changed` on the directory (which cargo scans recursively) makes
//! an added, removed or renamed shader regenerate the table.

use std::path::{Path, PathBuf};

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("readable directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            collect(&path, out);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            out.push(path);
        }
    }
}

fn main() {
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let shaders = manifest.join("../shaders");
    let shaders = shaders
        .canonicalize()
        .unwrap_or_else(|e| panic!("{}: {e}", shaders.display()));
    println!("cargo:rerun-if-changed={}", shaders.display());
    let mut files = Vec::new();
    collect(&shaders, &mut files);
    let mut table = String::from("&[\n");
    for path in &files {
        println!("cargo:rerun-if-changed={}", path.display());
        let rel = path
            .strip_prefix(&shaders)
            .expect("under shaders/")
            .to_string_lossy()
            .replace('\\', "/");
        let abs = path.to_string_lossy();
        table.push_str(&format!("    ({rel:?}, include_str!({abs:?})),\n"));
    }
    table.push(']');
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets it"));
    std::fs::write(out.join("embedded_shaders.rs"), table).expect("OUT_DIR is writable");
}
