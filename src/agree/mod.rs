//! Per-pass agreement: every pass of a graph run alone on the CPU simulator
//! and on the GPU backends with the same inputs, every output compared.
//!
//! Whole-frame image diffs say *that* backends disagree, not *where*. Here
//! the CPU simulator runs the frame once and keeps every pass's bindings as
//! they were just before it ran ([`strandgraph_cpu::CpuBackend::capture`]);
//! then each pass is [isolated](isolate) into a one-pass plan, given those
//! words on every backend, and its outputs are compared under a [`Rule`]:
//! integers bit-exact, floats within a stated ULP bound, and the few
//! exceptions listed in [`rules`] with the reason the CPU and GPU must differ.

pub mod compare;
pub mod isolate;
pub mod rules;
pub mod summary;

use crate::frame::Prepared;
use crate::runner::{self, Backend, OpenOptions};
use compare::{Outcome, compare};
use miette::{IntoDiagnostic, Result};
use serde::Serialize;
use strandgraph_cpu::{Captured, CpuBackend};
use strandgraph_graph::Plan;
use strandgraph_passes::Registry;
use strandgraph_passes::upload::Upload;

/// One output of one pass on one GPU backend, against the CPU.
#[derive(Debug, Clone, Serialize)]
pub struct OutputCheck {
    pub binding: String,
    pub judgement: rules::Judgement,
    pub outcome: Outcome,
}

/// One pass on one GPU backend.
#[derive(Debug, Clone, Serialize)]
pub struct PassCheck {
    pub pass: String,
    pub kind: String,
    pub backend: &'static str,
    pub outputs: Vec<OutputCheck>,
    /// Why the backend could not run the pass (a feature the device lacks,
    /// named by the backend); such a check has no outputs and has not passed.
    pub not_run: Option<String>,
}

impl PassCheck {
    pub fn passed(&self) -> bool {
        self.not_run.is_none() && self.outputs.iter().all(|o| o.outcome.passed())
    }
}

/// Runs `p`'s frame on the CPU simulator, keeping every pass's inputs.
pub fn capture(p: &Prepared) -> Result<Vec<Captured>> {
    // Each pass runs alone on the GPU from the CPU's words, and no API
    // copies words into or out of a multisampled image.
    let g = &p.plan.graph;
    if let Some(r) = g.resources.iter().find(|r| r.decl.samples() > 1) {
        return Err(miette::miette!(
            "graph `{}` declares `{}` with {} samples, which a pass cannot be seeded with or read back from; check it at one sample (--param {}.samples=1, and the passes' own MSAA settings to match)",
            g.name,
            r.name,
            r.decl.samples(),
            r.name
        ));
    }
    let backend = CpuBackend {
        capture: true,
        ..CpuBackend::default()
    };
    let mut session = backend
        .open(&Registry, &p.plan, &p.instance)
        .into_diagnostic()?;
    session.run(&p.upload).into_diagnostic()?;
    Ok(std::mem::take(&mut session.captured))
}

/// Checks every captured pass of `plan` on each of `gpus` (passes whose name
/// contains `only`, when given).
pub fn check_all(
    plan: &Plan,
    upload: &Upload,
    captured: &[Captured],
    gpus: &[Backend],
    only: Option<&str>,
    dump: Option<&std::path::Path>,
) -> Result<Vec<PassCheck>> {
    let mut checks = Vec::new();
    for c in captured {
        let name = plan.pass_name(c.pass);
        if only.is_some_and(|o| !name.contains(o)) {
            continue;
        }
        checks.extend(check_pass(plan, upload, c, gpus, dump)?);
    }
    Ok(checks)
}

/// Runs one captured pass alone on the CPU and on each of `gpus`, and
/// compares every output. With `dump`, the words of every output that
/// fails are written there as `PASS.OUTPUT.BACKEND.u32` (little endian).
pub fn check_pass(
    plan: &Plan,
    upload: &Upload,
    captured: &Captured,
    gpus: &[Backend],
    dump: Option<&std::path::Path>,
) -> Result<Vec<PassCheck>> {
    let pass = &plan.graph.passes[captured.pass];
    let alone = isolate::isolate(plan, captured.pass)?;
    let instance = alone.plan.instantiate(&upload.quantities)?;
    let inputs = Upload {
        resources: captured.bindings.iter().cloned().collect(),
        quantities: upload.quantities,
        ..Upload::default()
    };
    let outputs: Vec<&isolate::Port> = alone.ports.iter().filter(|p| p.mode.writes()).collect();
    let run = |backend: Backend| -> Result<Vec<Vec<u32>>> {
        let mut session = runner::open(backend, &alone.plan, &instance, OpenOptions::default())?;
        session.run(&inputs)?;
        outputs
            .iter()
            .map(|port| {
                session.read(&port.name)?.ok_or_else(|| {
                    miette::miette!("{}: output `{}` has no memory", backend.name(), port.name)
                })
            })
            .collect()
    };
    let cpu = run(Backend::Cpu)?;
    let mut checks = Vec::new();
    for &backend in gpus {
        let gpu = match run(backend) {
            Ok(words) => words,
            Err(e) if e.downcast_ref::<runner::Unsupported>().is_some() => {
                checks.push(PassCheck {
                    pass: pass.name.clone(),
                    kind: pass.kind.clone(),
                    backend: backend.name(),
                    outputs: Vec::new(),
                    not_run: Some(e.to_string()),
                });
                continue;
            }
            Err(e) => {
                return Err(e.wrap_err(format!(
                    "pass `{}` alone on {}; its graph:\n{}",
                    pass.name,
                    backend.name(),
                    alone.text
                )));
            }
        };
        let mut checks_here = Vec::new();
        for (port, (c, g)) in outputs.iter().zip(cpu.iter().zip(&gpu)) {
            let judgement = rules::rule(&pass.kind, &port.name, &port.decl, backend);
            let mut outcome = compare(c, g, judgement.rule);
            outcome.allowed = (judgement.outliers * outcome.words as f64) as usize;
            if let (Some(dir), false) = (dump, outcome.passed()) {
                for (who, words) in [("cpu", c), (backend.name(), g)] {
                    let file = dir.join(format!("{}.{}.{who}.u32", pass.name, port.name));
                    std::fs::write(&file, bytemuck_words(words)).into_diagnostic()?;
                }
            }
            checks_here.push(OutputCheck {
                binding: port.name.clone(),
                judgement,
                outcome,
            });
        }
        checks.push(PassCheck {
            pass: pass.name.clone(),
            kind: pass.kind.clone(),
            backend: backend.name(),
            outputs: checks_here,
            not_run: None,
        });
    }
    Ok(checks)
}

fn bytemuck_words(words: &[u32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// A table for people: one line per pass, backend and output.
pub fn table(checks: &[PassCheck]) -> String {
    use std::fmt::Write;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "  {:<18} {:<26} {:<5} {:<18} {:>10} {:>9} {:>9} {:>8} {:>10} {:>10}  rule",
        "pass",
        "kind",
        "on",
        "output",
        "words",
        "equal %",
        "failing",
        "allowed",
        "max int",
        "max ulps"
    );
    for c in checks {
        if let Some(why) = &c.not_run {
            let _ = writeln!(
                o,
                "  {:<18} {:<26} {:<5} NOT RUN: {why}",
                c.pass, c.kind, c.backend
            );
        }
        for out in &c.outputs {
            let r = &out.outcome;
            let equal = 100.0 * (r.words - r.differing) as f64 / r.words.max(1) as f64;
            let _ = writeln!(
                o,
                "  {:<18} {:<26} {:<5} {:<18} {:>10} {:>9.4} {:>9} {:>8} {:>10} {:>10} {} {:?}",
                c.pass,
                c.kind,
                c.backend,
                out.binding,
                r.words,
                equal,
                r.failing,
                r.allowed,
                r.max_int,
                if r.max_f32_ulps == u64::MAX {
                    "nan".to_string()
                } else {
                    r.max_f32_ulps.to_string()
                },
                if r.passed() { "ok  " } else { "FAIL" },
                out.judgement.rule,
            );
        }
    }
    o
}
