//! Running a plan: one thread per queue lane, sync points as timeline waits,
//! workgroups in parallel.

use crate::memory::{Inputs, Memory};
use crate::timeline::{Timeline, WaitError};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use strandgraph_graph::resolve::PassId;
use strandgraph_graph::{Instance, Plan, Queue};
use strandgraph_passes::kernel::{CounterValues, Counters, Ctx, Words};
use strandgraph_passes::{CpuKernel, Definitions, Dispatch, PassDef, Registry};

#[derive(Debug, thiserror::Error)]
pub enum CpuError {
    #[error("pass `{pass}`: kind `{kind}` has no CPU kernel yet")]
    NoKernel { pass: String, kind: String },
    #[error(transparent)]
    MissingBinding(#[from] strandgraph_passes::bind::MissingBinding),
    #[error(transparent)]
    Param(#[from] strandgraph_passes::ParamError),
    #[error("input `{resource}`: {message}")]
    Input { resource: String, message: String },
    #[error("pass `{pass}` waited {seconds} s for {queue} to signal {value}: sync deadlock")]
    SyncTimeout {
        pass: String,
        queue: Queue,
        value: u64,
        seconds: u64,
    },
    #[error("pass `{pass}`: {message}")]
    Dispatch { pass: String, message: String },
    #[error("pass `{pass}`: kernel panicked: {message}")]
    KernelPanic { pass: String, message: String },
    #[error(
        "the plan needs {needed} of memory ({largest} the largest) and {available} is available: render smaller (--size) or on a GPU backend"
    )]
    OutOfMemory {
        needed: String,
        largest: String,
        available: String,
    },
}

/// How the simulator runs.
#[derive(Debug, Clone)]
pub struct CpuBackend {
    /// Emulated subgroup width (32 as on NVIDIA; lavapipe has 8).
    pub subgroup_width: u32,
    pub instrument: bool,
    /// Place transients at the plan's aliasing offsets (off: separate ranges).
    pub alias: bool,
    /// How long a queue may wait at a sync point before the frame fails.
    pub sync_timeout: Duration,
    /// Keep a copy of every pass's bindings as they are just before it runs
    /// ([`Session::captured`]): the inputs the per-pass agreement harness
    /// replays on the GPU backends.
    pub capture: bool,
    /// Refuse a plan needing more memory than this many bytes; `None`: what
    /// the host has available (`/proc/meminfo`), unchecked where unknown.
    pub memory_limit: Option<u64>,
}

impl Default for CpuBackend {
    fn default() -> Self {
        Self {
            subgroup_width: 32,
            instrument: false,
            alias: true,
            sync_timeout: Duration::from_secs(120),
            capture: false,
            memory_limit: None,
        }
    }
}

/// One pass's wall time on its queue thread, and its counters.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PassTiming {
    pub pass: PassId,
    pub name: String,
    pub queue: Queue,
    pub workgroups: u32,
    pub millis: f64,
    pub counters: CounterValues,
}

/// A pass's bindings just before it ran ([`CpuBackend::capture`]).
#[derive(Debug, Clone)]
pub struct Captured {
    pub pass: PassId,
    /// Binding name (as the kernel sees it) and the resource's words.
    pub bindings: Vec<(String, Vec<u32>)>,
}

/// A plan opened on the simulator: memory laid out and kernels built once;
/// each [`Session::run`] uploads a frame's inputs and runs every pass.
/// History resources keep their contents between runs.
pub struct Session<'d> {
    backend: CpuBackend,
    plan: Plan,
    instance: Instance,
    prepared: HashMap<PassId, Prepared<'d>>,
    pub memory: Memory,
    /// The last frame's per-pass timings, in plan order.
    pub timings: Vec<PassTiming>,
    /// With [`CpuBackend::capture`]: every pass's bindings before it ran, in
    /// plan order.
    pub captured: Vec<Captured>,
}

/// A session after one frame ([`CpuBackend::execute`]).
pub type Frame<'d> = Session<'d>;

impl Session<'_> {
    /// The options it was opened with.
    pub fn options(&self) -> &CpuBackend {
        &self.backend
    }

    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    pub fn read(&self, plan: &Plan, resource: &str) -> Option<Vec<u32>> {
        self.memory.read(plan, resource)
    }

    /// Uploads `inputs` and runs one frame; returns its per-pass timings.
    pub fn run(&mut self, inputs: &Inputs) -> Result<&[PassTiming], CpuError> {
        self.memory.upload(&self.plan, inputs)?;
        let (timings, captured) =
            self.backend
                .run_frame(&self.plan, &self.instance, &self.prepared, &self.memory)?;
        self.timings = timings;
        self.captured = captured;
        Ok(&self.timings)
    }
}

struct Prepared<'d> {
    kernel: Box<dyn CpuKernel>,
    def: &'d dyn PassDef,
    /// Binding name → resource id.
    bindings: Vec<(String, usize)>,
}

impl CpuBackend {
    /// Runs one frame with the built-in pass definitions.
    pub fn execute(
        &self,
        plan: &Plan,
        instance: &Instance,
        inputs: &Inputs,
    ) -> Result<Frame<'static>, CpuError> {
        self.execute_with(&Registry, plan, instance, inputs)
    }

    /// Runs one frame, looking pass kinds up in `defs`.
    pub fn execute_with<'d>(
        &self,
        defs: &'d dyn Definitions,
        plan: &Plan,
        instance: &Instance,
        inputs: &Inputs,
    ) -> Result<Frame<'d>, CpuError> {
        let mut session = self.open(defs, plan, instance)?;
        session.run(inputs)?;
        Ok(session)
    }

    /// Opens a session: builds every live pass's kernel and lays out memory.
    pub fn open<'d>(
        &self,
        defs: &'d dyn Definitions,
        plan: &Plan,
        instance: &Instance,
    ) -> Result<Session<'d>, CpuError> {
        Ok(Session {
            backend: self.clone(),
            prepared: self.prepare(defs, plan)?,
            memory: Memory::new(plan, instance, self.alias, self.memory_limit)?,
            plan: plan.clone(),
            instance: instance.clone(),
            timings: Vec::new(),
            captured: Vec::new(),
        })
    }

    /// One frame: a thread per queue lane, waiting at the plan's sync points.
    fn run_frame(
        &self,
        plan: &Plan,
        instance: &Instance,
        prepared: &HashMap<PassId, Prepared<'_>>,
        memory: &Memory,
    ) -> Result<(Vec<PassTiming>, Vec<Captured>), CpuError> {
        let timelines: HashMap<Queue, Timeline> = plan
            .lanes
            .iter()
            .map(|l| (l.queue, Timeline::default()))
            .collect();
        let abort = AtomicBool::new(false);
        let failure: Mutex<Option<CpuError>> = Mutex::new(None);
        let timings: Mutex<Vec<PassTiming>> = Mutex::new(Vec::new());
        let captured: Mutex<Vec<Captured>> = Mutex::new(Vec::new());

        std::thread::scope(|scope| {
            for lane in &plan.lanes {
                let (timelines, abort, failure, timings, captured) =
                    (&timelines, &abort, &failure, &timings, &captured);
                scope.spawn(move || {
                    for (i, &p) in lane.passes.iter().enumerate() {
                        if abort.load(Ordering::Relaxed) {
                            return;
                        }
                        let result = self.wait_for(plan, p, timelines, abort).and_then(|()| {
                            if self.capture {
                                let c = capture(plan, p, &prepared[&p], memory);
                                captured.lock().unwrap_or_else(|e| e.into_inner()).push(c);
                            }
                            self.run_pass(plan, instance, p, &prepared[&p], memory)
                        });
                        match result {
                            Ok(t) => timings.lock().unwrap_or_else(|e| e.into_inner()).push(t),
                            Err(e) => {
                                failure
                                    .lock()
                                    .unwrap_or_else(|e| e.into_inner())
                                    .get_or_insert(e);
                                abort.store(true, Ordering::Relaxed);
                                timelines.values().for_each(Timeline::wake);
                                return;
                            }
                        }
                        timelines[&lane.queue].signal(i as u64 + 1);
                    }
                });
            }
        });
        if let Some(e) = failure.into_inner().unwrap_or_else(|e| e.into_inner()) {
            return Err(e);
        }
        let mut timings = timings.into_inner().unwrap_or_else(|e| e.into_inner());
        timings.sort_by_key(|t| plan.position(t.pass));
        let mut captured = captured.into_inner().unwrap_or_else(|e| e.into_inner());
        captured.sort_by_key(|c| plan.position(c.pass));
        Ok((timings, captured))
    }

    /// Looks up every live pass's definition, binds it and builds its kernel.
    fn prepare<'d>(
        &self,
        defs: &'d dyn Definitions,
        plan: &Plan,
    ) -> Result<HashMap<PassId, Prepared<'d>>, CpuError> {
        let g = &plan.graph;
        let mut out = HashMap::new();
        for &p in &plan.order {
            let pass = &g.passes[p];
            let def = defs
                .definition(&pass.kind)
                .ok_or_else(|| CpuError::NoKernel {
                    pass: pass.name.clone(),
                    kind: pass.kind.clone(),
                })?;
            let bindings = strandgraph_passes::bind::bind(def, g, p)?
                .into_iter()
                .map(|b| (b.name, b.access.resource))
                .collect();
            let kernel = def.cpu_kernel(&pass.params)?;
            out.insert(
                p,
                Prepared {
                    kernel,
                    def,
                    bindings,
                },
            );
        }
        Ok(out)
    }

    fn wait_for(
        &self,
        plan: &Plan,
        p: PassId,
        timelines: &HashMap<Queue, Timeline>,
        abort: &AtomicBool,
    ) -> Result<(), CpuError> {
        for s in plan.sync_points.iter().filter(|s| s.before == p) {
            let waited = timelines[&s.signal_queue]
                .wait(s.value, self.sync_timeout, || abort.load(Ordering::Relaxed));
            match waited {
                Ok(()) => {}
                Err(WaitError::Aborted) => return Ok(()),
                Err(WaitError::TimedOut) => {
                    return Err(CpuError::SyncTimeout {
                        pass: plan.pass_name(p).to_string(),
                        queue: s.signal_queue,
                        value: s.value,
                        seconds: self.sync_timeout.as_secs(),
                    });
                }
            }
        }
        Ok(())
    }

    fn run_pass(
        &self,
        plan: &Plan,
        instance: &Instance,
        p: PassId,
        prep: &Prepared<'_>,
        memory: &Memory,
    ) -> Result<PassTiming, CpuError> {
        let pass = &plan.graph.passes[p];
        let bindings: HashMap<&str, Words<'_>> = prep
            .bindings
            .iter()
            .map(|(name, r)| {
                (
                    name.as_str(),
                    Words::new(memory.words(plan, *r), &memory.out_of_bounds),
                )
            })
            .collect();
        prep.def
            .check_binding_sizes(&|name| bindings.get(name).map_or(0, |w| w.len() as u64))
            .map_err(|message| CpuError::Dispatch {
                pass: pass.name.clone(),
                message,
            })?;
        let dispatch = prep.def.dispatch();
        let most = bindings.values().map(Words::len).max().unwrap_or(0) as u64;
        let groups = match dispatch.direct_groups(&instance.quantities, most) {
            Some(n) => u32::try_from(n).unwrap_or(u32::MAX),
            None => match dispatch {
                Dispatch::Indirect { binding, word } => {
                    let w = bindings.get(binding);
                    let words = w.map_or(0, |w| w.len() as u64);
                    Dispatch::check_indirect(binding, word, words).map_err(|message| {
                        CpuError::Dispatch {
                            pass: pass.name.clone(),
                            message,
                        }
                    })?;
                    w.map_or(0, |w| w.load(word))
                }
                _ => unreachable!("only indirect dispatches have no direct count"),
            },
        };
        let counters = Counters::default();
        let ctx = Ctx {
            bindings,
            quantities: instance.quantities,
            workgroups: groups,
            workgroup_size: prep.def.workgroup_size(),
            subgroup_width: self.subgroup_width,
            instrument: self.instrument,
            counters: &counters,
        };
        let start = Instant::now();
        let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            prep.kernel.prologue(&ctx);
            (0..groups)
                .into_par_iter()
                .for_each(|g| prep.kernel.run_workgroup(g, &ctx));
        }));
        let millis = start.elapsed().as_secs_f64() * 1e3;
        if let Err(panic) = run {
            let message = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            return Err(CpuError::KernelPanic {
                pass: pass.name.clone(),
                message,
            });
        }
        tracing::debug!(pass = %pass.name, groups, millis, "ran");
        Ok(PassTiming {
            pass: p,
            name: pass.name.clone(),
            queue: pass.queue,
            workgroups: groups,
            millis,
            counters: counters.snapshot(),
        })
    }
}

/// A copy of pass `p`'s bindings. Safe to take while another queue runs:
/// the plan orders every pass that touches these resources against `p`,
/// and aliased memory is never shared with a resource live at the same time.
fn capture(plan: &Plan, p: PassId, prep: &Prepared<'_>, memory: &Memory) -> Captured {
    let bindings = prep
        .bindings
        .iter()
        .map(|(name, r)| {
            let words = memory.words(plan, *r);
            (
                name.clone(),
                words.iter().map(|w| w.load(Ordering::Relaxed)).collect(),
            )
        })
        .collect();
    Captured { pass: p, bindings }
}
