//! Offline baked hair self-shadowing, after Kulikov, "Strand hair in Indiana
//! Jones and the Great Circle" (SIGGRAPH 2025 Advances), "Precomputed
//! self-shadowing": "Trace visibility rays for each hair vertex offline, bake
//! results to a spherical function. Fetch baked visibility at runtime and use
//! for all lights."
//!
//! - [`intersect`]: rays against thin strand cylinders and head triangles;
//! - [`bvh`]: the occluders (two obvhs CWBVHs: strand segments, head mesh)
//!   and the per-ray scattering-event count, with a BVH-free brute force for
//!   tests;
//! - [`sh`]: clamped L1 SH of the event count with the zero-event bias
//!   ("Encode number of scattering events for any direction to clamped L1
//!   SH"; "Bias ray misses to have negative number of scattering events");
//! - [`bake()`]: every vertex in parallel (rayon), with a progress bar;
//! - [`cache`]: the result on disk, keyed by a content hash of the inputs.
//!
//! Everything is in world space at the scene's rest pose. The runtime side
//! (`kulikov.shade`, `self_shadow: "Baked"`) evaluates
//! `visibility = exp(-absorption * max(0, SH · light direction))`.

pub mod bake;
pub mod blob;
pub mod bvh;
pub mod cache;
pub mod intersect;
pub mod sh;

pub use bake::{bake, bake_with_progress};
pub use cache::{BakeOutcome, bake_cached, cache_dir};

/// Kulikov: "Shipped with HAIR_MAX_SCATTER_EVENTS = 5".
pub const HAIR_MAX_SCATTER_EVENTS: f32 = 5.0;

/// Bumped whenever the meaning or layout of a bake changes, so older cache
/// files stop matching (it is part of the cache key).
pub const FORMAT_VERSION: u32 = 1;

/// What a bake depends on besides the geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BakeSettings {
    /// Rays per vertex, spread over the whole sphere.
    pub rays: u32,
    /// `HAIR_MAX_SCATTER_EVENTS`: the zero-event bias is its negation, and a
    /// ray that reaches the (opaque) head counts at least this many events.
    pub max_scatter_events: f32,
    /// Rays stop after this many metres: "for self-shadowing what matters
    /// most is short neighborhood of each segment".
    pub max_distance: f32,
    /// Seed of the per-vertex rotation of the direction set.
    pub seed: u64,
    /// Trace against every n-th strand, n times as thick (same expected
    /// crossings; see [`bvh::Occluders::new`]). 1: every strand as it is.
    pub occluder_stride: u32,
    /// Longest piece (metres) a segment is cut into for the BVH.
    pub max_piece: f32,
    /// Rays are cast from every n-th vertex of a strand (and its tip); the
    /// vertices between interpolate the SH linearly. Kulikov found "1 probe
    /// per 4 vertices [...] very similar to 1 probe per 1 vertex".
    pub vertex_stride: u32,
}

impl Default for BakeSettings {
    fn default() -> Self {
        Self {
            rays: 32,
            max_scatter_events: HAIR_MAX_SCATTER_EVENTS,
            max_distance: 0.15,
            seed: 0x5eed,
            occluder_stride: 1,
            max_piece: 0.004,
            vertex_stride: 1,
        }
    }
}

impl BakeSettings {
    /// Rejects settings no bake can run with, saying which and why.
    pub fn check(&self) -> Result<(), BakeError> {
        let bad = |m: String| Err(BakeError::Settings(m));
        if self.rays == 0 || self.rays > 1 << 16 {
            return bad(format!("rays: expected 1..=65536, got {}", self.rays));
        }
        if !(self.max_scatter_events.is_finite() && self.max_scatter_events > 0.0) {
            return bad(format!(
                "max_scatter_events: expected a positive number, got {}",
                self.max_scatter_events
            ));
        }
        if !(self.max_distance.is_finite() && self.max_distance > 0.0) {
            return bad(format!(
                "max_distance: expected a positive number of metres, got {}",
                self.max_distance
            ));
        }
        if self.occluder_stride == 0 || self.occluder_stride > 64 {
            return bad(format!(
                "occluder_stride: expected 1..=64, got {}",
                self.occluder_stride
            ));
        }
        if self.vertex_stride == 0 || self.vertex_stride > 64 {
            return bad(format!(
                "vertex_stride: expected 1..=64, got {}",
                self.vertex_stride
            ));
        }
        if !(self.max_piece.is_finite() && self.max_piece >= 1e-4) {
            return bad(format!(
                "max_piece: expected at least 0.1 mm, got {} m",
                self.max_piece
            ));
        }
        Ok(())
    }
}

/// The geometry of one bake, in world space, in the packed order of the
/// `groom.vertices` / `groom.strands` resources (so the result lines up with
/// the packed vertices one to one).
#[derive(Debug, Clone, Copy)]
pub struct BakeInput<'a> {
    /// Per vertex: position (metres) and strand thickness (diameter, metres).
    pub vertices: &'a [[f32; 4]],
    /// Per strand: first vertex and vertex count.
    pub strands: &'a [[u32; 2]],
    /// Opaque occluders (the head), world-space corners.
    pub triangles: &'a [[[f32; 3]; 3]],
}

impl BakeInput<'_> {
    /// Strand ranges must lie inside `vertices`.
    fn check(&self) -> Result<(), BakeError> {
        for (s, &[first, count]) in self.strands.iter().enumerate() {
            let end = u64::from(first) + u64::from(count);
            if end > self.vertices.len() as u64 {
                return Err(BakeError::Input(format!(
                    "strand {s} spans vertices {first}..{end}, but there are only {}",
                    self.vertices.len()
                )));
            }
        }
        Ok(())
    }
}

/// Clamped L1 SH per vertex: `[Y00, Y1-1 (y), Y10 (z), Y11 (x)]` coefficients
/// of the (biased) scattering-event count, see [`sh`].
pub type ShadowSh = [f32; 4];

#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error("self-shadowing bake settings: {0}")]
    Settings(String),
    #[error("self-shadowing bake input: {0}")]
    Input(String),
    #[error("self-shadowing bake cache {path}: {source}")]
    Io {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
}
