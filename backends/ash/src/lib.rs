//! # strandgraph-ash
//!
//! Runs a compiled `Plan` on raw Vulkan 1.3 through ash 0.38, a thin runner
//! like the CPU and wgpu backends that does what wgpu cannot:
//! - **aliased transients**: each heap of the plan's memory plan
//!   (`graph/src/alias.rs`) is one `VkDeviceMemory`, and transients are bound
//!   at the plan's offsets ([`memory`]);
//! - **the plan's barriers**: every same-queue dependency of the plan's sync
//!   section (`graph/src/sync.rs`) becomes a `vkCmdPipelineBarrier2` with its
//!   stage and access masks and image layouts, and nothing else ([`barriers`]);
//! - **async compute**: when the device has a compute-only queue family,
//!   AsyncCompute lanes run there, ordered by timeline semaphores at the plan's
//!   sync points ([`record`], [`submit`]); with one queue (lavapipe) the lanes
//!   are serialised in plan order and the frame notes say so;
//! - **per-pass timestamps per queue** ([`timing`]).
//!
//! Shaders are the WGSL under `shaders/` (built into the binary), composed by
//! [`strandgraph_passes::wgsl`] and translated by naga to SPIR-V 1.3 with the
//! capabilities each pass needs ([`spirv`]). Binding 0 is the pass's parameter
//! block ([`PassDef::gpu_params`]), then its `bindings()` in order.
//!
//! Every Vulkan object is owned by a value that destroys it on drop
//! ([`owned`]): children hold the device, the device holds the instance, so
//! an early `?` frees whatever was made and destruction order follows from
//! ownership.
//!
//! A [`Session`] creates the device, pipelines, memory and command buffers
//! once ([`AshBackend::open`]); [`Session::run`] uploads a frame's inputs and
//! runs it; [`Session::read`] reads any resource back. Validation
//! ([`Validation::Sync`]) collects every message of the Khronos layer,
//! synchronization validation included, and fails the run with them.
//!
//! ## What it does not do (yet)
//! - **Queue-family ownership transfers**: with two families every resource
//!   is `VK_SHARING_MODE_CONCURRENT` (memory.rs says why).
//! - **Narrow semaphore waits**: cross-queue waits use `ALL_COMMANDS`,
//!   because the plan's happens-before chains continue through lane order
//!   after the wait; only the plan's sync points wait at all.
//! - **Frames in flight**: each [`Session::run`] waits on the host for its
//!   frame (with [`AshBackend::timeout`]) before returning.
//! - **Workgroup counts of aliased indirect arguments**: the frame's end has
//!   reused their bytes, so [`PassTiming::workgroups`] is `None` there.
//! - **Raster passes on the compute queue** are refused (a raster pass must
//!   be on the Graphics lane).
//! - **`VK_EXT_layer_settings`**: Debian 12's layer (1.3.239) predates it, so
//!   synchronization validation is enabled through `VK_EXT_validation_features`.
//! - **Pipeline cache, subgroup size control, robustness2**: none; bounds
//!   checks are naga's `Restrict` policy (as wgpu-hal without robustness2).
//! - Concurrent reads of one image in different layouts (a depth image
//!   sampled on one queue and depth-tested on the other) share one layout
//!   that serves all of them (barriers.rs), not the plan's per-pass layouts.

mod barriers;
mod descriptors;
mod device;
mod error;
mod features;
mod host;
mod interface;
mod level_timing;
mod loader;
mod memory;
mod owned;
mod pipelines;
mod placement;
mod prepare;
mod prologue;
mod raster;
mod readback;
mod record;
mod session;
mod spirv;
mod stats;
mod submit;
mod timing;

pub use error::AshError;
pub use loader::keep_driver_loaded;
pub use session::{Frame, Session};
pub use timing::PassTiming;

use std::path::PathBuf;
use std::time::Duration;
use strandgraph_graph::{Instance, Plan};
use strandgraph_passes::upload::Upload;
use strandgraph_passes::{Definitions, LoopCounters, Registry};

/// Whether to load the Khronos validation layer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Validation {
    Off,
    /// `VK_LAYER_KHRONOS_validation` with synchronization validation; any
    /// warning or error fails the run. A missing layer is an error.
    Sync,
}

impl Validation {
    /// `Sync` when `STRANDGRAPH_VK_VALIDATION` is set to anything but `0`.
    pub fn from_env() -> Self {
        match std::env::var("STRANDGRAPH_VK_VALIDATION") {
            Ok(v) if v != "0" && !v.is_empty() => Validation::Sync,
            _ => Validation::Off,
        }
    }
}

/// How a frame's batches (record.rs) reach the queues.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Submit {
    /// One `vkQueueSubmit2` per queue and frame with every batch of that
    /// queue, waits submitted before their signals (timeline semaphores
    /// allow it). On the H100 this shortened the GPU's gap at each batch
    /// boundary: Kulikov far 0.406 -> 0.363 ms timed at the frame's bounds
    /// (benches/results/kulikov-submit-h100.txt).
    PerQueue,
    /// One `vkQueueSubmit2` per batch, every signal submitted before its wait.
    PerBatch,
}

impl Submit {
    /// `PerBatch` when `STRANDGRAPH_ASH_SUBMIT=batch`, else `PerQueue`.
    pub fn from_env() -> Self {
        match std::env::var("STRANDGRAPH_ASH_SUBMIT") {
            Ok(v) if v == "batch" => Submit::PerBatch,
            _ => Submit::PerQueue,
        }
    }
}

/// How a queue's passes are separated by pipeline barriers (record.rs).
///
/// A Vulkan pipeline barrier waits for *every* earlier command of its source
/// stages, not only the pass it names. Recorded before each pass, it turns
/// a queue into a chain: two independent passes recorded one after the
/// other with a barrier between them never overlap, however small they are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Barriers {
    /// Passes in the plan's order, each after the barrier its own
    /// dependencies need.
    PerPass,
    /// Ours: between two cross-queue waits, the passes in dependency levels
    /// (a pass one level after the last pass on its queue it waits for),
    /// every barrier of a level in one `vkCmdPipelineBarrier2` before it:
    /// the passes of a level run side by side.
    #[default]
    Levels,
}

impl Barriers {
    /// The names `FromStr` takes.
    pub const NAMES: [&'static str; 2] = ["per-pass", "levels"];
}

impl std::str::FromStr for Barriers {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "per-pass" => Ok(Barriers::PerPass),
            "levels" => Ok(Barriers::Levels),
            _ => Err(format!(
                "`{s}` is not a barrier setting (one of {})",
                Self::NAMES.join(", ")
            )),
        }
    }
}

impl std::fmt::Display for Barriers {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Barriers::PerPass => "per-pass",
            Barriers::Levels => "levels",
        })
    }
}

/// How the ash backend runs.
#[derive(Debug, Clone)]
pub struct AshBackend {
    /// Read the WGSL from this directory instead of the shaders built into
    /// the binary ([`strandgraph_passes::wgsl::EMBEDDED`]); by default
    /// `$STRANDGRAPH_SHADERS` ([`strandgraph_passes::wgsl::override_dir`]).
    pub shader_dir: Option<PathBuf>,
    pub validation: Validation,
    /// Place transients at the plan's aliasing offsets; `false` gives each
    /// its own memory, so every transient can be read back after a frame.
    pub alias: bool,
    /// Use a compute-only queue family for AsyncCompute passes when there is one.
    pub async_compute: bool,
    /// The longest any fence or semaphore wait may take before the run fails
    /// (ten times this on a CPU implementation such as lavapipe).
    pub timeout: Duration,
    /// Pick the first device whose name contains this (else the first discrete GPU).
    pub device_name: Option<String>,
    /// By default from `$STRANDGRAPH_ASH_SUBMIT` ([`Submit::from_env`]).
    pub submit: Submit,
    /// Which passes get naga's loop counters
    /// (`spv::Options::force_loop_bounding`; [`LoopCounters`] says why).
    /// By default those whose graph keeps them.
    pub loop_counters: LoopCounters,
    /// How each queue's passes are separated by barriers ([`Barriers`]).
    pub barriers: Barriers,
}

impl Default for AshBackend {
    fn default() -> Self {
        Self {
            shader_dir: strandgraph_passes::wgsl::override_dir(),
            validation: Validation::from_env(),
            alias: true,
            async_compute: true,
            timeout: Duration::from_secs(60),
            device_name: std::env::var("STRANDGRAPH_VK_DEVICE").ok(),
            submit: Submit::from_env(),
            loop_counters: LoopCounters::Graph,
            barriers: Barriers::Levels,
        }
    }
}

impl AshBackend {
    /// Creates the device, memory, pipelines and command buffers for `plan`
    /// with the built-in pass definitions.
    pub fn open(&self, plan: &Plan, instance: &Instance) -> Result<Session, AshError> {
        self.open_with(&Registry, plan, instance)
    }

    /// Like [`AshBackend::open`], looking pass kinds up in `defs`.
    pub fn open_with(
        &self,
        defs: &dyn Definitions,
        plan: &Plan,
        instance: &Instance,
    ) -> Result<Session, AshError> {
        Session::open(self, defs, plan, instance)
    }

    /// One frame: open, upload `inputs`, run.
    pub fn execute(
        &self,
        plan: &Plan,
        instance: &Instance,
        inputs: &Upload,
    ) -> Result<(Session, Frame), AshError> {
        let mut session = self.open(plan, instance)?;
        let frame = session.run(inputs)?;
        Ok((session, frame))
    }
}
