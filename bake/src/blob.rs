//! Keyed files of f32s, the on-disk form of every bake (the self-shadowing
//! SH, `cache`; the head collision fields, `strandgraph-passes`' `sim`):
//! one file per content hash of everything the result depends on.
//!
//! Layout (little endian): an 8-byte magic naming the kind, its format
//! version (u32), the item count (u64), the 32-byte key, `count ×
//! floats_per_item` f32s, and a BLAKE3 checksum of those floats. A file is
//! only trusted if its size is exactly what the expected count implies
//! (nothing is allocated from its header) and every field matches.

use std::io::Write;
use std::path::{Path, PathBuf};

/// One kind of cached file.
#[derive(Debug, Clone, Copy)]
pub struct Kind {
    pub magic: &'static [u8; 8],
    pub version: u32,
    /// What it holds, for errors and file names (`shadow_sh`).
    pub name: &'static str,
}

/// Bytes before the payload.
pub const HEADER: usize = 8 + 4 + 8 + 32;
const CHECKSUM: usize = 32;

fn hex(key: &[u8; 32]) -> String {
    key.iter().map(|b| format!("{b:02x}")).collect()
}

impl Kind {
    /// The file an item with `key` lives in under `dir`.
    pub fn path(&self, dir: &Path, key: &[u8; 32]) -> PathBuf {
        dir.join(format!("{}-{}.bin", self.name, hex(key)))
    }

    /// Reads `count` items of `floats_per_item` f32s: `Ok(None)` if there is
    /// no file, `Err` saying what is wrong with one that is there but unusable.
    pub fn read(
        &self,
        path: &Path,
        key: &[u8; 32],
        count: usize,
        floats_per_item: usize,
    ) -> Result<Option<Vec<f32>>, String> {
        let payload_bytes = count
            .checked_mul(4 * floats_per_item)
            .ok_or_else(|| format!("{count} items do not fit a cache file"))?;
        let expected = payload_bytes
            .checked_add(HEADER + CHECKSUM)
            .ok_or_else(|| format!("{count} items do not fit a cache file"))?;
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
        let (payload, checksum) = rest.split_at(payload_bytes);
        if &header[..8] != self.magic {
            return Err(format!("not a strandgraph {} file (bad magic)", self.name));
        }
        let version = u32::from_le_bytes(header[8..12].try_into().unwrap_or_default());
        if version != self.version {
            return Err(format!(
                "format version {version}, expected {}",
                self.version
            ));
        }
        let n = u64::from_le_bytes(header[12..20].try_into().unwrap_or_default());
        if n != count as u64 {
            return Err(format!("{n} items, expected {count}"));
        }
        if &header[20..52] != key {
            return Err("key does not match its file name".into());
        }
        if blake3::hash(payload).as_bytes() != checksum {
            return Err("checksum mismatch (corrupt)".into());
        }
        Ok(Some(
            payload
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect(),
        ))
    }

    /// Writes `count` items (`floats`, every item's f32s in turn)
    /// atomically: a temporary file renamed into place, so a reader never
    /// sees half a file, even with two writers racing.
    pub fn write(
        &self,
        path: &Path,
        key: &[u8; 32],
        count: usize,
        floats: &[f32],
    ) -> std::io::Result<()> {
        let dir = path.parent().unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir)?;
        let payload: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
        let mut bytes = Vec::with_capacity(HEADER + payload.len() + CHECKSUM);
        bytes.extend_from_slice(self.magic);
        bytes.extend_from_slice(&self.version.to_le_bytes());
        bytes.extend_from_slice(&(count as u64).to_le_bytes());
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
}
