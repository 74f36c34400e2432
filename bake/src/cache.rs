//! The bake on disk, so it runs once per groom: one file per content hash of
//! everything the result depends on (packed vertices and strands, head
//! triangles, settings, [`FORMAT_VERSION`]).
//!
//! Files are [`crate::blob`]s (magic `SGSHBAKE`, one item of four f32
//! coefficients per vertex); one that cannot be trusted is logged as an
//! error and baked again.

use crate::blob::Kind;

use crate::{BakeError, BakeInput, BakeSettings, FORMAT_VERSION, ShadowSh, bake};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"SGSHBAKE";

/// Whether [`bake_cached`] had to bake.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BakeOutcome {
    Baked,
    Cached,
}

/// `$STRANDGRAPH_CACHE`, else `$XDG_CACHE_HOME/strandgraph`, else
/// `~/.cache/strandgraph`; `None` when none of them is set.
pub fn cache_dir() -> Option<PathBuf> {
    cache_dir_from(|k| std::env::var_os(k))
}

/// [`cache_dir`] over any environment lookup (empty values count as unset).
pub fn cache_dir_from(env: impl Fn(&str) -> Option<std::ffi::OsString>) -> Option<PathBuf> {
    let var = |k: &str| env(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    var("STRANDGRAPH_CACHE")
        .or_else(|| var("XDG_CACHE_HOME").map(|d| d.join("strandgraph")))
        .or_else(|| var("HOME").map(|d| d.join(".cache").join("strandgraph")))
}

/// The content hash that names a bake.
pub fn key(input: &BakeInput<'_>, settings: &BakeSettings) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(b"strandgraph shadow_sh");
    h.update(&FORMAT_VERSION.to_le_bytes());
    h.update(&settings.rays.to_le_bytes());
    h.update(&settings.max_scatter_events.to_le_bytes());
    h.update(&settings.max_distance.to_le_bytes());
    h.update(&settings.seed.to_le_bytes());
    h.update(&settings.occluder_stride.to_le_bytes());
    h.update(&settings.max_piece.to_le_bytes());
    h.update(&settings.vertex_stride.to_le_bytes());
    let mut section = |name: &[u8], len: usize, floats: &mut dyn Iterator<Item = u32>| {
        h.update(name);
        h.update(&(len as u64).to_le_bytes());
        for w in floats {
            h.update(&w.to_le_bytes());
        }
    };
    section(
        b"vertices",
        input.vertices.len(),
        &mut input.vertices.iter().flatten().map(|f| f.to_bits()),
    );
    section(
        b"strands",
        input.strands.len(),
        &mut input.strands.iter().flatten().copied(),
    );
    section(
        b"triangles",
        input.triangles.len(),
        &mut input
            .triangles
            .iter()
            .flatten()
            .flatten()
            .map(|f| f.to_bits()),
    );
    *h.finalize().as_bytes()
}

/// The self-shadowing bake's files ([`crate::blob`]): items are vertices
/// of four SH coefficients.
const FILES: Kind = Kind {
    magic: MAGIC,
    version: FORMAT_VERSION,
    name: "shadow_sh",
};

/// The file a bake with `key` lives in under `dir`.
pub fn path(dir: &Path, key: &[u8; 32]) -> PathBuf {
    FILES.path(dir, key)
}

/// Reads a bake of `count` vertices: `Ok(None)` if there is none, `Err`
/// saying what is wrong with a file that is there but unusable.
pub fn read(path: &Path, key: &[u8; 32], count: usize) -> Result<Option<Vec<ShadowSh>>, String> {
    Ok(FILES.read(path, key, count, 4)?.map(|floats| {
        floats
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()
    }))
}

/// Writes a bake atomically ([`Kind::write`]).
pub fn write(path: &Path, key: &[u8; 32], sh: &[ShadowSh]) -> std::io::Result<()> {
    let floats: Vec<f32> = sh.iter().flatten().copied().collect();
    FILES.write(path, key, sh.len(), &floats)
}

/// The bake of `input`, from `dir` if it holds one, else baked and stored
/// there. A cache file that cannot be used is logged and baked over; a cache
/// that cannot be written is logged, and the fresh bake returned anyway.
/// With `dir` `None` it always bakes.
pub fn bake_cached(
    input: &BakeInput<'_>,
    settings: &BakeSettings,
    dir: Option<&Path>,
) -> Result<(Vec<ShadowSh>, BakeOutcome), BakeError> {
    let Some(dir) = dir else {
        tracing::warn!("no cache directory (set STRANDGRAPH_CACHE): baking without a cache");
        return Ok((bake(input, settings)?, BakeOutcome::Baked));
    };
    let key = key(input, settings);
    let file = path(dir, &key);
    // One bake at a time in this process: tests rendering the same groom in
    // parallel wait for the first bake and then read its file.
    static BAKING: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one = BAKING
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    match read(&file, &key, input.vertices.len()) {
        Ok(Some(sh)) => {
            tracing::info!(path = %file.display(), "hair self-shadowing bake from cache");
            return Ok((sh, BakeOutcome::Cached));
        }
        Ok(None) => {}
        Err(why) => {
            tracing::error!(path = %file.display(), "unusable self-shadowing cache file, baking again: {why}");
        }
    }
    let sh = bake(input, settings)?;
    match write(&file, &key, &sh) {
        Ok(()) => tracing::info!(path = %file.display(), "hair self-shadowing bake cached"),
        Err(e) => {
            tracing::error!(path = %file.display(), "could not cache the self-shadowing bake: {e}")
        }
    }
    Ok((sh, BakeOutcome::Baked))
}

#[cfg(test)]
mod tests;
