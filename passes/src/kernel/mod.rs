//! What CPU kernels see: memory as atomic 32-bit words, emulated subgroups
//! and instrumentation counters. The CPU backend builds a [`Ctx`] per pass;
//! unit tests beside each pass build one with [`harness::Harness`].

pub mod harness;
pub mod subgroup;
mod wide;

use std::collections::HashMap;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

/// A bound buffer or image: its bytes as atomic 32-bit words.
///
/// Every access is atomic (relaxed), like storage memory on a GPU: plain
/// loads and stores cannot tear, and `fetch_*` are real atomics. Accesses out
/// of range behave like robust buffer access (reads give 0, writes are
/// dropped) and are counted, so tests can assert there were none.
#[derive(Clone, Copy)]
pub struct Words<'a> {
    words: &'a [AtomicU32],
    oob: &'a AtomicU64,
}

impl<'a> Words<'a> {
    pub fn new(words: &'a [AtomicU32], oob: &'a AtomicU64) -> Self {
        Self { words, oob }
    }
    pub fn len(&self) -> usize {
        self.words.len()
    }
    pub fn is_empty(&self) -> bool {
        self.words.is_empty()
    }
    fn at(&self, i: usize) -> Option<&'a AtomicU32> {
        let w = self.words.get(i);
        if w.is_none() {
            self.oob.fetch_add(1, Relaxed);
        }
        w
    }
    pub fn load(&self, i: usize) -> u32 {
        self.at(i).map_or(0, |w| w.load(Relaxed))
    }
    pub fn store(&self, i: usize, v: u32) {
        if let Some(w) = self.at(i) {
            w.store(v, Relaxed);
        }
    }
    pub fn load_f32(&self, i: usize) -> f32 {
        f32::from_bits(self.load(i))
    }
    pub fn store_f32(&self, i: usize, v: f32) {
        self.store(i, v.to_bits());
    }
    pub fn load_vec4(&self, i: usize) -> [f32; 4] {
        [
            self.load_f32(4 * i),
            self.load_f32(4 * i + 1),
            self.load_f32(4 * i + 2),
            self.load_f32(4 * i + 3),
        ]
    }
    pub fn store_vec4(&self, i: usize, v: [f32; 4]) {
        for (k, x) in v.into_iter().enumerate() {
            self.store_f32(4 * i + k, x);
        }
    }
    /// `atomicAdd`; returns the previous value.
    pub fn fetch_add(&self, i: usize, v: u32) -> u32 {
        self.at(i).map_or(0, |w| w.fetch_add(v, Relaxed))
    }
    /// `atomicMin`; returns the previous value.
    pub fn fetch_min(&self, i: usize, v: u32) -> u32 {
        self.at(i).map_or(u32::MAX, |w| w.fetch_min(v, Relaxed))
    }
    /// `atomicMax`; returns the previous value.
    pub fn fetch_max(&self, i: usize, v: u32) -> u32 {
        self.at(i).map_or(0, |w| w.fetch_max(v, Relaxed))
    }
    /// `atomicOr`; returns the previous value.
    pub fn fetch_or(&self, i: usize, v: u32) -> u32 {
        self.at(i).map_or(0, |w| w.fetch_or(v, Relaxed))
    }
}

/// Per-pass instrumentation, summed over workgroups.
#[derive(Debug, Default)]
pub struct Counters {
    /// Active lanes summed over every loop iteration of every subgroup.
    pub active_lanes: AtomicU64,
    /// Lanes summed over the same iterations (iterations × subgroup width).
    pub total_lanes: AtomicU64,
    pub atomics: AtomicU64,
    pub pixels_written: AtomicU64,
    /// Out-of-range accesses (should stay 0).
    pub out_of_bounds: AtomicU64,
    /// Work a kernel's own test skipped (`lipp.raster`'s occlusion-culled
    /// segments).
    pub culled: AtomicU64,
}

/// A plain snapshot of [`Counters`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct CounterValues {
    pub active_lanes: u64,
    pub total_lanes: u64,
    pub atomics: u64,
    pub pixels_written: u64,
    pub out_of_bounds: u64,
    pub culled: u64,
}

impl CounterValues {
    /// Fraction of lanes doing useful work per loop iteration (Kulikov: "45%").
    pub fn lane_utilisation(&self) -> Option<f64> {
        (self.total_lanes > 0).then(|| self.active_lanes as f64 / self.total_lanes as f64)
    }
}

impl Counters {
    pub fn snapshot(&self) -> CounterValues {
        CounterValues {
            active_lanes: self.active_lanes.load(Relaxed),
            total_lanes: self.total_lanes.load(Relaxed),
            atomics: self.atomics.load(Relaxed),
            pixels_written: self.pixels_written.load(Relaxed),
            out_of_bounds: self.out_of_bounds.load(Relaxed),
            culled: self.culled.load(Relaxed),
        }
    }
    /// Adds a workgroup's local tallies (one contended add per counter per workgroup).
    pub fn add(&self, local: &CounterValues) {
        self.active_lanes.fetch_add(local.active_lanes, Relaxed);
        self.total_lanes.fetch_add(local.total_lanes, Relaxed);
        self.atomics.fetch_add(local.atomics, Relaxed);
        self.pixels_written.fetch_add(local.pixels_written, Relaxed);
        self.culled.fetch_add(local.culled, Relaxed);
    }
}

/// Everything a CPU kernel can reach during one dispatch.
pub struct Ctx<'a> {
    pub bindings: HashMap<&'a str, Words<'a>>,
    /// Scene quantities and screen size, as the GPU's frame uniform carries them.
    pub quantities: strandgraph_graph::Quantities,
    pub workgroups: u32,
    pub workgroup_size: u32,
    /// Emulated subgroup width (default 32; lavapipe has 8).
    pub subgroup_width: u32,
    /// Whether kernels should tally [`Counters`]; off, they skip the bookkeeping.
    pub instrument: bool,
    pub counters: &'a Counters,
}

impl<'a> Ctx<'a> {
    /// The binding called `name`. The backend bound every declared binding
    /// before running the kernel, so a miss is a bug in the pass definition.
    pub fn words(&self, name: &str) -> Words<'a> {
        match self.bindings.get(name) {
            Some(w) => *w,
            None => panic!("pass kernel asked for unbound binding `{name}`"),
        }
    }
}
