//! Choosing and opening a backend: the one place in the CLI, the bench and
//! the tests that names each backend. Everything after opening goes through
//! [`Session`], the interface every backend implements
//! ([`strandgraph_passes::backend`]).

use miette::{IntoDiagnostic, Result};
pub use strandgraph_ash::Barriers;
use strandgraph_graph::{Instance, Plan};
pub use strandgraph_passes::LoopCounters;
use strandgraph_passes::Registry;
pub use strandgraph_passes::backend::{BackendError, Clock, PassTime, Session, frame_millis};

/// A backend a plan can run on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, clap::ValueEnum)]
pub enum Backend {
    /// The CPU reference simulator; times are wall clock per pass.
    Cpu,
    /// wgpu on Vulkan; times are GPU timestamps per pass.
    Wgpu,
    /// Raw Vulkan through ash; times are GPU timestamps per pass per queue.
    Ash,
}

impl Backend {
    pub const ALL: [Backend; 3] = [Backend::Cpu, Backend::Wgpu, Backend::Ash];

    pub fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::Wgpu => "wgpu",
            Backend::Ash => "ash",
        }
    }

    pub fn is_gpu(self) -> bool {
        self != Backend::Cpu
    }

    /// What its pass times measure (the same as its sessions' [`Session::clock`]).
    pub fn clock(self) -> Clock {
        if self.is_gpu() {
            Clock::GpuTimestamps
        } else {
            Clock::CpuWall
        }
    }
}

/// How to open a backend: what the CPU simulator, aliasing and the GPU
/// backends' shader translation need.
#[derive(Debug, Clone, Copy)]
pub struct OpenOptions {
    /// The CPU simulator's subgroup width.
    pub subgroup_width: u32,
    /// Count atomics, active lanes and pixels per pass (CPU, slower).
    pub instrument: bool,
    /// Place transients at the plan's aliasing offsets (cpu, ash; wgpu
    /// cannot alias); off gives every transient its own memory.
    pub alias: bool,
    /// Which passes' GPU shaders get naga's loop counters
    /// ([`LoopCounters`]; by default those whose graph keeps them).
    pub loop_counters: LoopCounters,
    /// How ash separates a queue's passes with barriers ([`Barriers`]; by
    /// default in dependency levels). The other backends place their own.
    pub barriers: Barriers,
}

impl Default for OpenOptions {
    fn default() -> Self {
        Self {
            subgroup_width: 32,
            instrument: false,
            alias: true,
            loop_counters: LoopCounters::Graph,
            barriers: Barriers::Levels,
        }
    }
}

/// Opens `plan` on `backend`: creates the device, memory and pipelines
/// (not timed by [`Session::run`]).
pub fn open(
    backend: Backend,
    plan: &Plan,
    instance: &Instance,
    options: OpenOptions,
) -> Result<Box<dyn Session>> {
    Ok(match backend {
        Backend::Cpu => {
            let b = strandgraph_cpu::CpuBackend {
                subgroup_width: options.subgroup_width.clamp(1, 64),
                instrument: options.instrument,
                alias: options.alias,
                ..Default::default()
            };
            Box::new(b.open(&Registry, plan, instance).into_diagnostic()?)
        }
        Backend::Wgpu => {
            // NVIDIA's driver fails after some thirty reloads in one
            // process; hold it loaded (strandgraph_ash::keep_driver_loaded
            // says why). Without a loader wgpu reports its own error.
            let _ = strandgraph_ash::keep_driver_loaded();
            let b = strandgraph_wgpu::WgpuBackend {
                loop_counters: options.loop_counters,
                ..Default::default()
            };
            let session = b.open(&Registry, plan, instance).map_err(|e| match e {
                strandgraph_wgpu::WgpuError::MissingFeature { .. } => {
                    Unsupported(e.to_string()).into()
                }
                e => miette::Report::from_err(e),
            })?;
            Box::new(session)
        }
        Backend::Ash => {
            let b = strandgraph_ash::AshBackend {
                alias: options.alias,
                loop_counters: options.loop_counters,
                barriers: options.barriers,
                ..Default::default()
            };
            Box::new(b.open(plan, instance).map_err(|e| match e {
                strandgraph_ash::AshError::MissingFeature { .. } => {
                    Unsupported(e.to_string()).into()
                }
                e => miette::Report::from_err(e),
            })?)
        }
    })
}

/// A backend refused the plan for something the device lacks (a feature,
/// a sample count, a binding size): the bench marks such a cell skipped.
#[derive(Debug)]
pub struct Unsupported(pub String);

impl std::fmt::Display for Unsupported {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Unsupported {}
impl miette::Diagnostic for Unsupported {}

/// What the host checks after a frame of `plan`: where it runs the
/// reference's resolve, that its tile lists fit their buffer and, on
/// lavapipe, that no lane had more to walk than the driver's loop cap
/// ([`strandgraph_passes::reference::check_lists`]).
pub fn check_frame(plan: &Plan, instance: &Instance, session: &dyn Session) -> Result<()> {
    use strandgraph_passes::reference::{
        self, LLVMPIPE_LOOP_ITERATIONS, ListLimits, resolve::ResolveParams,
    };
    let resolve = plan
        .order
        .iter()
        .find(|&&p| plan.live[p] && plan.graph.passes[p].kind == reference::resolve::RESOLVE.kind);
    let (Some(&p), Some(lists)) = (resolve, plan.graph.resource_id("reference_segments")) else {
        return Ok(());
    };
    let params: ResolveParams = plan.graph.passes[p]
        .params
        .clone()
        .into_rust()
        .map_err(|e| miette::miette!("pass `{}`: {e}", plan.pass_name(p)))?;
    let Some(offsets) = session.read("reference_offsets").into_diagnostic()? else {
        return Ok(());
    };
    let q = &instance.quantities;
    let (tx, ty) = reference::tiles(q.width, q.height);
    let limits = ListLimits {
        capacity: (instance.sizes[lists].bytes / 4) as usize,
        loop_cap: session
            .device()
            .contains("llvmpipe")
            .then_some(LLVMPIPE_LOOP_ITERATIONS),
        samples_per_axis: params.samples_per_axis,
    };
    reference::check_lists(&offsets, (tx * ty) as usize, limits).map_err(|e| miette::miette!("{e}"))
}
