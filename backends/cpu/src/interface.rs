//! The CPU simulator behind the backends' one interface
//! ([`strandgraph_passes::backend::Session`]).

use crate::execute::Session;
use strandgraph_passes::backend::{self as api, BackendError, Clock, PassTime};
use strandgraph_passes::upload::Upload;

impl api::Session for Session<'_> {
    fn backend(&self) -> &'static str {
        "cpu"
    }

    fn device(&self) -> String {
        let b = self.options();
        format!(
            "CPU simulator on {} ({} threads), emulated subgroup width {}{}",
            cpu_model(),
            std::thread::available_parallelism().map_or(1, |n| n.get()),
            b.subgroup_width,
            if b.instrument { ", instrumented" } else { "" }
        )
    }

    fn clock(&self) -> Clock {
        Clock::CpuWall
    }

    fn notes(&self) -> Vec<String> {
        let b = self.options();
        vec![format!(
            "{} queue lanes on threads; transient arena {:.2} MiB ({})",
            self.plan().lanes.len(),
            self.memory.arena_bytes as f64 / (1 << 20) as f64,
            if b.alias { "aliased" } else { "not aliased" }
        )]
    }

    fn run(&mut self, inputs: &Upload) -> Result<Vec<PassTime>, BackendError> {
        let instrument = self.options().instrument;
        Session::run(self, inputs).map_err(|e| BackendError::new("cpu", e))?;
        let oob = self
            .memory
            .out_of_bounds
            .load(std::sync::atomic::Ordering::Relaxed);
        if oob > 0 {
            tracing::warn!(oob, "kernels accessed memory out of range");
        }
        let plan = self.plan();
        Ok(self
            .timings
            .iter()
            .map(|t| PassTime {
                pass: t.pass,
                name: t.name.clone(),
                kind: plan.graph.passes[t.pass].kind.clone(),
                queue: t.queue,
                workgroups: Some(u64::from(t.workgroups)),
                millis: Some(t.millis),
                span: None,
                family: None,
                counters: instrument.then_some(t.counters),
            })
            .collect())
    }

    fn read(&self, name: &str) -> Result<Option<Vec<u32>>, BackendError> {
        Ok(self.memory.read(self.plan(), name))
    }
}

/// The CPU's model name from /proc/cpuinfo, or the architecture.
fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}
