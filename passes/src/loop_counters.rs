//! Which passes' shaders the GPU backends compile with naga's loop counters.
//!
//! naga bounds every loop unless told not to (`force_loop_bounding`; wgpu
//! sets it for every module it does not create trusted): a 64-bit counter
//! that breaks out when it runs out, so that a driver cannot treat an
//! endless loop as unreachable. Our loops end by construction, and the
//! counters keep NVIDIA's compiler from unrolling short loops; but some
//! kernels unroll into more registers than they save, and their graphs keep
//! the counters per pass (`loop_bounding: true`). docs/architecture.md,
//! "Shaders", has the measurements.

use std::fmt;
use std::str::FromStr;

/// Where the counters go; the GPU backends' setting, the CLI's
/// `--loop-counters`, and a bench row's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LoopCounters {
    /// In the passes whose graph says `loop_bounding: true`.
    #[default]
    Graph,
    /// In every pass: naga's and wgpu's own default.
    Every,
    /// In no pass, whatever the graph says.
    None,
}

impl LoopCounters {
    /// The names `FromStr` takes.
    pub const NAMES: [&'static str; 3] = ["graph", "every", "none"];

    /// Whether a pass whose graph says `kept` gets the counters.
    pub fn for_pass(self, kept: bool) -> bool {
        match self {
            LoopCounters::Graph => kept,
            LoopCounters::Every => true,
            LoopCounters::None => false,
        }
    }
}

impl FromStr for LoopCounters {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "graph" => Ok(LoopCounters::Graph),
            "every" => Ok(LoopCounters::Every),
            "none" => Ok(LoopCounters::None),
            _ => Err(format!(
                "`{s}` is not a loop-counter setting (one of {})",
                Self::NAMES.join(", ")
            )),
        }
    }
}

impl fmt::Display for LoopCounters {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LoopCounters::Graph => "graph",
            LoopCounters::Every => "every",
            LoopCounters::None => "none",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_setting_reads_back_its_name_and_decides_per_pass() {
        for name in LoopCounters::NAMES {
            let c: LoopCounters = name.parse().unwrap();
            assert_eq!(c.to_string(), name);
        }
        let err = "all".parse::<LoopCounters>().unwrap_err();
        assert!(
            err.contains("`all`") && err.contains("graph, every, none"),
            "{err}"
        );
        use LoopCounters::*;
        let table = [
            (Graph, [false, true]),
            (Every, [true, true]),
            (None, [false, false]),
        ];
        for (c, want) in table {
            assert_eq!([c.for_pass(false), c.for_pass(true)], want, "{c}");
        }
    }
}
