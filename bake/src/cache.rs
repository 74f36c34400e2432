//! The bake on disk, so it runs once per groom: one file per content hash of
//! everything the result depends on (packed vertices and strands, head
//! triangles, settings, [`FORMAT_VERSION`]).
//!
//! File layout (little endian): magic `SGSHBAKE`, format version (u32),
//! vertex count (u64), the 32-byte key, `count × 4` f32 coefficients, and a
//! BLAKE3 checksum of those coefficients. A file is only trusted if its size
//! is exactly what the expected vertex count implies (nothing is allocated
//! from its header) and every field matches; anything else is logged as an
//! error and baked again.

use crate::{BakeError, BakeInput, BakeSettings, FORMAT_VERSION, ShadowSh, bake};
use std::io::Write;
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"SGSHBAKE";
const HEADER: usize = 8 + 4 + 8 + 32;
const CHECKSUM: usize = 32;

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

fn hex(key: &[u8; 32]) -> String {
    key.iter().map(|b| format!("{b:02x}")).collect()
}

/// The file a bake with `key` lives in under `dir`.
pub fn path(dir: &Path, key: &[u8; 32]) -> PathBuf {
    dir.join(format!("shadow_sh-{}.bin", hex(key)))
}

/// Reads a bake of `count` vertices: `Ok(None)` if there is none, `Err`
/// saying what is wrong with a file that is there but unusable.
pub fn read(path: &Path, key: &[u8; 32], count: usize) -> Result<Option<Vec<ShadowSh>>, String> {
    let expected = count
        .checked_mul(16)
        .and_then(|b| b.checked_add(HEADER + CHECKSUM))
        .ok_or_else(|| format!("{count} vertices do not fit a cache file"))?;
    let len = match std::fs::metadata(path) {
        Ok(m) => m.len(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e.to_string()),
    };
    if len != expected as u64 {
        return Err(format!(
            "{len} bytes, expected {expected} (truncated or foreign)"
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    if bytes.len() != expected {
        return Err(format!("{} bytes read, expected {expected}", bytes.len()));
    }
    let (header, rest) = bytes.split_at(HEADER);
    let (payload, checksum) = rest.split_at(count * 16);
    if &header[..8] != MAGIC {
        return Err("not a strandgraph shadow_sh bake (bad magic)".into());
    }
    let version = u32::from_le_bytes(header[8..12].try_into().unwrap_or_default());
    if version != FORMAT_VERSION {
        return Err(format!(
            "format version {version}, expected {FORMAT_VERSION}"
        ));
    }
    let n = u64::from_le_bytes(header[12..20].try_into().unwrap_or_default());
    if n != count as u64 {
        return Err(format!("{n} vertices, expected {count}"));
    }
    if &header[20..52] != key {
        return Err("key does not match its file name".into());
    }
    if blake3::hash(payload).as_bytes() != checksum {
        return Err("checksum mismatch (corrupt)".into());
    }
    Ok(Some(
        payload
            .chunks_exact(16)
            .map(|c| {
                std::array::from_fn(|i| {
                    f32::from_le_bytes([c[4 * i], c[4 * i + 1], c[4 * i + 2], c[4 * i + 3]])
                })
            })
            .collect(),
    ))
}

/// Writes a bake atomically (a temporary file renamed into place), so a
/// reader never sees half a file, even with two bakes racing.
pub fn write(path: &Path, key: &[u8; 32], sh: &[ShadowSh]) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    let mut payload = Vec::with_capacity(sh.len() * 16);
    for c in sh.iter().flatten() {
        payload.extend_from_slice(&c.to_le_bytes());
    }
    let mut bytes = Vec::with_capacity(HEADER + payload.len() + CHECKSUM);
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    bytes.extend_from_slice(&(sh.len() as u64).to_le_bytes());
    bytes.extend_from_slice(key);
    bytes.extend_from_slice(&payload);
    bytes.extend_from_slice(blake3::hash(&payload).as_bytes());
    let tmp = dir.join(format!(
        ".{}.{}.tmp",
        path.file_name().and_then(|n| n.to_str()).unwrap_or("bake"),
        std::process::id()
    ));
    let mut f = std::fs::File::create(&tmp)?;
    f.write_all(&bytes)?;
    f.sync_all()?;
    drop(f);
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
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
