//! Synthetic graphs for property tests and the compile benchmark.
//!
//! A [`Spec`] describes a random DAG: each pass reads outputs of earlier
//! passes and writes one new transient. [`Spec::to_ron`] renders it as a real
//! graph file, so tests and benches exercise the parser and locator too.

use crate::schema::Queue;
use std::fmt::Write;

#[derive(Debug, Clone)]
pub struct SynthPass {
    pub queue: Queue,
    /// Indices of earlier passes whose output this pass reads.
    pub reads: Vec<usize>,
    /// Also update the shared atomic counter (exercises atomic serialisation).
    pub atomic: bool,
    /// Size of this pass's output, in elements of 16 bytes per segment / 1024.
    pub size: u64,
}

#[derive(Debug, Clone)]
pub struct Spec {
    pub passes: Vec<SynthPass>,
    /// Passes whose outputs are graph outputs (imported).
    pub outputs: Vec<usize>,
}

impl Spec {
    /// A deterministic pseudo-random spec (an LCG, so the crate needs no RNG).
    pub fn random(n: usize, seed: u64) -> Spec {
        let mut s = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut next = move |m: u64| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 33) % m.max(1)
        };
        let passes = (0..n)
            .map(|i| {
                let reads = if i == 0 {
                    vec![]
                } else {
                    let k = 1 + next(3) as usize;
                    // Mostly recent producers, like a real frame.
                    let mut r: Vec<usize> = (0..k)
                        .map(|_| i - 1 - next(i.min(8) as u64) as usize)
                        .collect();
                    r.sort_unstable();
                    r.dedup();
                    r
                };
                SynthPass {
                    queue: if next(3) == 0 {
                        Queue::AsyncCompute
                    } else {
                        Queue::Graphics
                    },
                    reads,
                    atomic: next(10) == 0,
                    size: 1 + next(64),
                }
            })
            .collect();
        let outputs = (n.saturating_sub(3)..n).collect();
        Spec { passes, outputs }
    }

    /// The spec as graph text. Outputs are imported buffers; everything else is transient.
    pub fn to_ron(&self) -> String {
        let mut s = String::from("Graph(\n  name: \"synthetic\",\n  resources: [\n");
        let _ = writeln!(s, "    Buffer(name: \"counter\", size: Bytes(4)),");
        for (i, p) in self.passes.iter().enumerate() {
            let lifetime = if self.outputs.contains(&i) {
                "Imported"
            } else {
                "Transient"
            };
            let _ = writeln!(
                s,
                "    Buffer(name: \"r{i}\", size: PerElement(Segments, {}), lifetime: {lifetime}),",
                p.size
            );
        }
        s.push_str("  ],\n  passes: [\n");
        let _ = writeln!(
            s,
            "    Pass(name: \"clear\", kind: \"common.clear\", writes: [\"counter\"]),"
        );
        for (i, p) in self.passes.iter().enumerate() {
            let reads: Vec<String> = p.reads.iter().map(|r| format!("\"r{r}\"")).collect();
            let atomics = if p.atomic { "\"counter\"" } else { "" };
            let _ = writeln!(
                s,
                "    Pass(name: \"p{i}\", kind: \"synthetic\", queue: {:?}, reads: [{}], writes: [\"r{i}\"], atomics: [{atomics}]),",
                p.queue,
                reads.join(", ")
            );
        }
        let outs: Vec<String> = self.outputs.iter().map(|o| format!("\"r{o}\"")).collect();
        let _ = write!(s, "  ],\n  outputs: [{}],\n)\n", outs.join(", "));
        s
    }

    /// Pass-kind names the synthetic graphs use.
    pub fn kinds() -> crate::registry::KindList {
        crate::registry::KindList::new(["common.clear", "synthetic"])
    }
}
