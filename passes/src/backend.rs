//! The one interface every backend implements.
//!
//! The CPU simulator, wgpu and ash each open a compiled plan into a
//! [`Session`]: device, memory and pipelines created once, then frames run
//! with [`Session::run`] and resources read back with [`Session::read`]. The
//! CLI, the bench and the tests hold a `Box<dyn Session>` and contain no
//! per-backend code path beyond choosing which backend to open.
//!
//! The trait lives here, beside the pass definitions, because every backend
//! already depends on this crate and none depends on another.

use crate::kernel::CounterValues;
use crate::upload::Upload;
use strandgraph_graph::Queue;
use strandgraph_graph::resolve::PassId;

/// What a backend's pass times measure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Clock {
    /// Wall time of each pass on its queue's thread (the CPU simulator).
    CpuWall,
    /// GPU timestamps written before and after each pass.
    GpuTimestamps,
}

impl Clock {
    pub fn describe(self) -> &'static str {
        match self {
            Clock::CpuWall => "CPU wall time per pass",
            Clock::GpuTimestamps => "GPU timestamps per pass",
        }
    }
}

/// One pass of one frame, on any backend.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PassTime {
    pub pass: PassId,
    pub name: String,
    pub kind: String,
    /// The queue the plan gave it.
    pub queue: Queue,
    /// Workgroups launched (vertices for raster passes); `None` where the
    /// backend cannot tell (an indirect count whose bytes were aliased).
    pub workgroups: Option<u64>,
    /// `None` where the queue has no clock (a family without timestamps).
    pub millis: Option<f64>,
    /// Begin and end in ms from the frame's first timestamp on any queue,
    /// where queues overlap (ash): a frame is then a span, not a sum.
    pub span: Option<(f64, f64)>,
    /// Where the backend ran it, when that is more than the queue (ash:
    /// the Vulkan queue family).
    pub family: Option<u32>,
    /// Counted atomics, lanes and pixels (instrumented CPU runs only).
    pub counters: Option<CounterValues>,
}

/// One dependency level of one queue's batch (ash's barrier levels,
/// docs/architecture.md, "Synchronisation"), timed by
/// [`Session::run_levels_timed`]: its passes run side by side between two
/// barriers, so a level's time is its slowest pass with the others beside
/// it, and a queue's levels in a row show which chain sets the frame.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LevelTime {
    /// The backend's queue it ran on, in the backend's numbering (ash: 0
    /// for the graphics queue, 1 for async compute where the device has a
    /// compute-only family; with one queue, every plan queue's passes share
    /// 0 and its levels).
    pub queue: usize,
    /// Its batch on that queue (a batch ends where another queue waits).
    pub batch: usize,
    /// Its passes, in lane order.
    pub passes: Vec<String>,
    /// Begin and end in ms from the frame's first timestamp on any queue:
    /// the batch's start after its waits (a first level) or the previous
    /// level's end, then its own end.
    pub span: (f64, f64),
}

/// A frame's time: first begin to last end where passes carry spans (queues
/// overlap), else the sum of the passes.
pub fn frame_millis(passes: &[PassTime]) -> f64 {
    let spans: Vec<(f64, f64)> = passes.iter().filter_map(|p| p.span).collect();
    if spans.is_empty() {
        return passes.iter().filter_map(|p| p.millis).sum();
    }
    let begin = spans.iter().map(|s| s.0).fold(f64::INFINITY, f64::min);
    let end = spans.iter().map(|s| s.1).fold(f64::NEG_INFINITY, f64::max);
    end - begin
}

/// A backend's failure, with the backend's own error kept as the source.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[error("{backend}: {source}")]
pub struct BackendError {
    pub backend: &'static str,
    #[source]
    pub source: Box<dyn std::error::Error + Send + Sync>,
}

impl BackendError {
    pub fn new(backend: &'static str, e: impl std::error::Error + Send + Sync + 'static) -> Self {
        Self {
            backend,
            source: Box::new(e),
        }
    }
}

/// A plan opened on a backend.
pub trait Session {
    /// `cpu`, `wgpu` or `ash`.
    fn backend(&self) -> &'static str;
    /// The device and driver the times come from.
    fn device(&self) -> String;
    fn clock(&self) -> Clock;
    /// How the plan ran here (queues, aliasing, memory), for people.
    fn notes(&self) -> Vec<String>;
    /// Uploads `inputs` into the imported and history resources they name,
    /// runs one frame and returns its per-pass times in plan order.
    fn run(&mut self, inputs: &Upload) -> Result<Vec<PassTime>, BackendError>;
    /// Runs one frame as [`Session::run`] does, with GPU timestamps only
    /// where each queue's part of the frame begins and ends, and returns
    /// the frame's time in ms: first begin to last end. A timestamp after
    /// a pass waits for the queue's work before it, so per-pass queries
    /// keep independent passes of one queue from overlapping and add their
    /// own cost; this is the frame without them. `None` where the backend
    /// has no such mode (its frame time is [`frame_millis`] of `run`).
    fn run_frame_timed(&mut self, inputs: &Upload) -> Result<Option<f64>, BackendError> {
        self.run(inputs).map(|_| None)
    }
    /// Runs one frame as [`Session::run`] does, with GPU timestamps only
    /// where each batch begins and each of its dependency levels ends, and
    /// returns the levels in lane order per queue: where the frame's time
    /// goes with its queues overlapping, which per-pass queries prevent.
    /// `None` where the backend has no such mode (only ash records levels).
    fn run_levels_timed(
        &mut self,
        inputs: &Upload,
    ) -> Result<Option<Vec<LevelTime>>, BackendError> {
        self.run(inputs).map(|_| None)
    }
    /// A copy of resource `name`'s words after the last frame (a version
    /// reads its resource's memory); `None` when the plan gave it no memory.
    fn read(&self, name: &str) -> Result<Option<Vec<u32>>, BackendError>;
}
