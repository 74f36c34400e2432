//! One face over the backends' sessions, for code that runs the same plan on
//! whichever backends a machine has (`strandgraph bench`, the criterion
//! benches): open once (device, pipelines, memory), run frames, get per-pass
//! times and the name of what ran them.
//!
//! Adding a backend is a variant of [`Backend`] and of [`Runner`], and an arm
//! in each `match` below.

use miette::{IntoDiagnostic, Result};
use strandgraph_graph::{Instance, Plan};
use strandgraph_passes::Registry;
use strandgraph_passes::upload::Upload;

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
    pub fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::Wgpu => "wgpu",
            Backend::Ash => "ash",
        }
    }

    /// What the times of this backend measure.
    pub fn clock(self) -> &'static str {
        match self {
            Backend::Cpu => "CPU wall time per pass",
            Backend::Wgpu | Backend::Ash => "GPU timestamps per pass",
        }
    }

    pub fn is_gpu(self) -> bool {
        self != Backend::Cpu
    }
}

/// Options that only the CPU simulator reads.
#[derive(Debug, Clone, Copy)]
pub struct CpuOptions {
    pub subgroup_width: u32,
    /// Count atomics, active lanes and pixels per pass (slower).
    pub instrument: bool,
}

impl Default for CpuOptions {
    fn default() -> Self {
        Self {
            subgroup_width: 32,
            instrument: false,
        }
    }
}

/// One pass of one frame.
#[derive(Debug, Clone)]
pub struct PassTime {
    pub name: String,
    pub kind: String,
    pub millis: f64,
    /// Atomics the pass performed (instrumented CPU runs only).
    pub atomics: Option<u64>,
    /// Begin and end in ms from the frame's first timestamp on any queue
    /// (ash only: its queues overlap, so a frame is a span, not a sum).
    pub span: Option<(f64, f64)>,
}

/// A frame's GPU time: first begin to last end where passes carry spans
/// (ash, whose async compute overlaps graphics), else the sum of the
/// passes (wgpu's one queue).
pub fn gpu_frame_millis(passes: &[PassTime]) -> f64 {
    let spans: Vec<(f64, f64)> = passes.iter().filter_map(|p| p.span).collect();
    if spans.is_empty() {
        return passes.iter().map(|p| p.millis).sum();
    }
    let begin = spans.iter().map(|s| s.0).fold(f64::INFINITY, f64::min);
    let end = spans.iter().map(|s| s.1).fold(f64::NEG_INFINITY, f64::max);
    end - begin
}

/// An open session on one backend.
pub enum Runner {
    Cpu {
        session: Box<strandgraph_cpu::Session<'static>>,
        device: String,
        instrument: bool,
    },
    Wgpu(Box<strandgraph_wgpu::Session>),
    Ash(Box<strandgraph_ash::Session>),
}

impl Runner {
    /// Opens `plan` on `backend`: creates the device, memory and pipelines
    /// (not timed by [`Runner::run`]).
    pub fn open(
        backend: Backend,
        plan: &Plan,
        instance: &Instance,
        cpu: CpuOptions,
    ) -> Result<Runner> {
        match backend {
            Backend::Cpu => {
                let b = strandgraph_cpu::CpuBackend {
                    subgroup_width: cpu.subgroup_width.clamp(1, 64),
                    instrument: cpu.instrument,
                    ..Default::default()
                };
                let session = b.open(&Registry, plan, instance).into_diagnostic()?;
                let device = format!(
                    "CPU simulator on {} ({} threads), emulated subgroup width {}{}",
                    cpu_model(),
                    std::thread::available_parallelism().map_or(1, |n| n.get()),
                    b.subgroup_width,
                    if cpu.instrument { ", instrumented" } else { "" }
                );
                Ok(Runner::Cpu {
                    session: Box::new(session),
                    device,
                    instrument: cpu.instrument,
                })
            }
            Backend::Wgpu => {
                // NVIDIA's driver fails after some thirty reloads in one
                // process; hold it loaded (strandgraph_ash::keep_driver_loaded
                // says why). Without a loader wgpu reports its own error.
                let _ = strandgraph_ash::keep_driver_loaded();
                let session = strandgraph_wgpu::WgpuBackend::default()
                    .open(&Registry, plan, instance)
                    .into_diagnostic()?;
                Ok(Runner::Wgpu(Box::new(session)))
            }
            Backend::Ash => {
                let session = strandgraph_ash::AshBackend::default()
                    .open(plan, instance)
                    .into_diagnostic()?;
                Ok(Runner::Ash(Box::new(session)))
            }
        }
    }

    pub fn backend(&self) -> Backend {
        match self {
            Runner::Cpu { .. } => Backend::Cpu,
            Runner::Wgpu(_) => Backend::Wgpu,
            Runner::Ash(_) => Backend::Ash,
        }
    }

    /// The device and driver the times come from.
    pub fn device(&self) -> String {
        match self {
            Runner::Cpu { device, .. } => device.clone(),
            Runner::Wgpu(s) => s.adapter.clone(),
            Runner::Ash(s) => s.device.clone(),
        }
    }

    /// How the plan ran on this backend (wgpu: one queue, no aliasing;
    /// ash: queues and transient bytes with and without aliasing).
    pub fn notes(&self) -> Vec<String> {
        match self {
            Runner::Cpu { .. } => Vec::new(),
            Runner::Wgpu(s) => s.notes.clone(),
            Runner::Ash(s) => {
                let mib = |b: u64| b as f64 / (1 << 20) as f64;
                let mut notes = s.notes.clone();
                notes.push(format!(
                    "transients {:.2} MiB aliased, {:.2} MiB unaliased",
                    mib(s.transient_bytes),
                    mib(s.unaliased_bytes)
                ));
                notes
            }
        }
    }

    /// Uploads `upload` and runs one frame; per-pass times in plan order.
    pub fn run(&mut self, plan: &Plan, upload: &Upload) -> Result<Vec<PassTime>> {
        let kind = |p: usize| plan.graph.passes[p].kind.clone();
        match self {
            Runner::Cpu {
                session,
                instrument,
                ..
            } => {
                let timings = session.run(upload).into_diagnostic()?;
                Ok(timings
                    .iter()
                    .map(|t| PassTime {
                        name: t.name.clone(),
                        kind: kind(t.pass),
                        millis: t.millis,
                        atomics: instrument.then_some(t.counters.atomics),
                        span: None,
                    })
                    .collect())
            }
            Runner::Wgpu(session) => {
                let timings = session.run(upload).into_diagnostic()?;
                Ok(timings
                    .iter()
                    .map(|t| PassTime {
                        name: t.name.clone(),
                        kind: kind(t.pass),
                        millis: t.millis,
                        atomics: None,
                        span: None,
                    })
                    .collect())
            }
            Runner::Ash(session) => {
                let frame = session.run(upload).into_diagnostic()?;
                Ok(frame
                    .timings
                    .iter()
                    .map(|t| PassTime {
                        name: t.name.clone(),
                        kind: kind(t.pass),
                        // NaN where the queue family has no timestamps.
                        millis: t.millis.unwrap_or(f64::NAN),
                        atomics: None,
                        span: t.span,
                    })
                    .collect())
            }
        }
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
