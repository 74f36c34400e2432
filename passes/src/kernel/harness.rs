//! Runs one kernel on hand-made buffers, for unit tests beside each pass.

use super::{CounterValues, Counters, Ctx, Words};
use crate::contract::CpuKernel;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};
use strandgraph_graph::Quantities;

/// Named buffers and the settings a dispatch needs.
pub struct Harness {
    buffers: Vec<(String, Vec<AtomicU32>)>,
    oob: AtomicU64,
    pub quantities: Quantities,
    pub subgroup_width: u32,
    pub instrument: bool,
}

impl Harness {
    pub fn new(quantities: Quantities) -> Self {
        Self {
            buffers: Vec::new(),
            oob: AtomicU64::new(0),
            quantities,
            subgroup_width: 32,
            instrument: true,
        }
    }

    /// Adds (or replaces) a buffer.
    pub fn buffer(&mut self, name: &str, words: Vec<u32>) -> &mut Self {
        self.buffers.retain(|(n, _)| n != name);
        self.buffers.push((
            name.to_string(),
            words.into_iter().map(AtomicU32::new).collect(),
        ));
        self
    }

    /// Runs `groups` workgroups in parallel and returns the counters.
    pub fn run(&self, kernel: &dyn CpuKernel, groups: u32, workgroup_size: u32) -> CounterValues {
        let counters = Counters::default();
        let ctx = Ctx {
            bindings: self
                .buffers
                .iter()
                .map(|(n, w)| (n.as_str(), Words::new(w, &self.oob)))
                .collect(),
            quantities: self.quantities,
            workgroups: groups,
            workgroup_size,
            subgroup_width: self.subgroup_width,
            instrument: self.instrument,
            counters: &counters,
        };
        kernel.prologue(&ctx);
        (0..groups)
            .into_par_iter()
            .for_each(|g| kernel.run_workgroup(g, &ctx));
        counters.snapshot()
    }

    pub fn read(&self, name: &str) -> Vec<u32> {
        self.buffers
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, w)| w.iter().map(|x| x.load(Relaxed)).collect())
            .unwrap_or_default()
    }

    pub fn out_of_bounds(&self) -> u64 {
        self.oob.load(Relaxed)
    }
}
