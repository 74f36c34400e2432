//! # strandgraph-cpu
//!
//! The reference simulator. It executes a compiled `Plan` the way a GPU
//! would, so the CPU and GPU backends can be diffed:
//! - transients live in one arena at the plan's aliasing offsets, so an
//!   aliasing bug corrupts results instead of hiding ([`memory`]);
//! - each queue lane runs on its own thread and waits at the plan's sync
//!   points, so a missing sync point shows up as a race ([`timeline`]);
//! - workgroups run in parallel on rayon, with real atomics;
//! - every pass is timed, and an instrumented mode counts lane utilisation,
//!   atomics and pixels written.

pub mod execute;
mod interface;
pub mod memory;
pub mod timeline;

pub use execute::{Captured, CpuBackend, CpuError, Frame, PassTiming, Session};
pub use memory::Inputs;
