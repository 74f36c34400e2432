//! The pass contract: what every pass kind defines once, for every backend.
//!
//! A pass kind has an interface (named bindings that match the resource names
//! its graph declares), parameters read from the graph's RON, a dispatch
//! rule, a WGSL entry point for the GPU backends and a CPU kernel written per
//! workgroup for the CPU simulator.

use crate::kernel::Ctx;
use crate::raster_state::RasterState;
use strandgraph_graph::Quantities;
use strandgraph_graph::schema::{AccessMode, Quantity};

/// One resource a pass binds, by the name graph files give it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Binding {
    pub name: &'static str,
    pub mode: AccessMode,
    /// Words the pass reads or writes at fixed places of the resource
    /// (say, arguments past an indirect dispatch's); 0: none. A graph whose
    /// resource is smaller is an error ([`Binding::check_size`]), not an
    /// access past its end, which neither Vulkan nor WGSL's clamping would
    /// report.
    pub min_words: u32,
}

impl Binding {
    pub const fn read(name: &'static str) -> Self {
        Self {
            name,
            mode: AccessMode::Read,
            min_words: 0,
        }
    }
    pub const fn write(name: &'static str) -> Self {
        Self {
            name,
            mode: AccessMode::Write,
            min_words: 0,
        }
    }
    pub const fn atomic(name: &'static str) -> Self {
        Self {
            name,
            mode: AccessMode::Atomic,
            min_words: 0,
        }
    }
    /// This binding with at least `words` words.
    pub const fn at_least(self, words: u32) -> Self {
        Self {
            min_words: words,
            ..self
        }
    }
    /// An error unless the bound resource's `words` hold [`Self::min_words`].
    pub fn check_size(&self, words: u64) -> Result<(), String> {
        if words >= u64::from(self.min_words) {
            return Ok(());
        }
        Err(format!(
            "the pass uses words 0..{} of `{}`, which holds {words}: give it at least {} bytes",
            self.min_words,
            self.name,
            4 * u64::from(self.min_words)
        ))
    }
}

/// How many workgroups a dispatch launches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dispatch {
    /// A fixed count.
    Fixed(u32),
    /// One workgroup per `per_group` elements of a scene quantity.
    PerElement { quantity: Quantity, per_group: u32 },
    /// The count is the u32 of `binding` at word `word`, written by an earlier pass.
    Indirect { binding: &'static str, word: usize },
    /// One workgroup per `words_per_group` 32-bit words of the largest
    /// written binding, at most [`MAX_COVER_GROUPS`]: past that the
    /// kernel's workgroups stride over the rest ([`Dispatch::cover_groups`]).
    CoverWrites { words_per_group: u32 },
}

/// The most workgroups a [`Dispatch::CoverWrites`] launches: the 65,535 per
/// dimension Vulkan guarantees (and wgpu allows).
pub const MAX_COVER_GROUPS: u64 = 65_535;

impl Dispatch {
    /// The workgroups of a direct dispatch, the same on every backend;
    /// `None` for [`Dispatch::Indirect`], whose count an earlier pass wrote.
    /// `largest_words` is the size of the pass's largest bound buffer (what
    /// [`Dispatch::CoverWrites`] covers).
    pub fn direct_groups(&self, q: &Quantities, largest_words: u64) -> Option<u64> {
        match *self {
            Dispatch::Fixed(n) => Some(u64::from(n)),
            Dispatch::PerElement {
                quantity,
                per_group,
            } => Some(q.count(quantity).div_ceil(u64::from(per_group.max(1)))),
            Dispatch::Indirect { .. } => None,
            Dispatch::CoverWrites { words_per_group } => {
                Some(Self::cover_groups(largest_words, words_per_group))
            }
        }
    }

    /// An indirect dispatch reads three words of `binding` from `word` on:
    /// an error unless its `words` hold them (a graph's buffer too small
    /// for the pass that dispatches from it, which Vulkan would not catch).
    pub fn check_indirect(binding: &str, word: usize, words: u64) -> Result<(), String> {
        if word as u64 + 3 <= words {
            return Ok(());
        }
        Err(format!(
            "the indirect dispatch reads words {word}..{} of `{binding}`, which holds {words}: give it at least {} bytes",
            word + 3,
            4 * (word + 3)
        ))
    }

    /// The workgroups that cover `words` at `words_per_group` each, capped
    /// at [`MAX_COVER_GROUPS`]; a kernel dispatched so strides by the
    /// dispatched count (a 2.7 GB buffer needs 164,022 groups of 4,096
    /// words).
    pub fn cover_groups(words: u64, words_per_group: u32) -> u64 {
        words
            .div_ceil(u64::from(words_per_group.max(1)))
            .min(MAX_COVER_GROUPS)
    }
}

/// WGSL entry points in `shaders/`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shader {
    /// Path under `shaders/`.
    pub file: &'static str,
    /// The compute entry point, or the vertex entry point of a raster pass.
    pub entry: &'static str,
    /// The fragment entry point of a raster pass (one with colour or depth attachments).
    pub fragment: Option<&'static str>,
}

impl Shader {
    /// A compute entry point.
    pub const fn compute(file: &'static str, entry: &'static str) -> Self {
        Self {
            file,
            entry,
            fragment: None,
        }
    }
}

/// A pass parameter that is unknown, mistyped or out of range; `param` is
/// the key, or empty when the whole parameter block is wrong.
#[derive(Debug, Clone, thiserror::Error)]
#[error("pass kind `{kind}`: {}{message}", if param.is_empty() { String::new() } else { format!("parameter `{param}`: ") })]
pub struct ParamError {
    pub kind: &'static str,
    pub param: String,
    pub message: String,
}

/// Field names and byte offsets of a GPU parameter block, and its size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GpuLayout {
    pub fields: &'static [(&'static str, usize)],
    pub size: usize,
}

/// What backends, the compiler and tests ask of a pass kind. Pass kinds
/// implement it through their declaration ([`crate::describe::PassKind`]);
/// tests may implement it by hand.
pub trait PassDef: Send + Sync {
    fn kind(&self) -> &'static str;
    /// One line on what the pass does.
    fn summary(&self) -> &'static str {
        ""
    }
    /// Where the algorithm comes from (paper and section).
    fn source(&self) -> &'static str {
        ""
    }
    /// The bindings, or `None` when the pass binds whatever the graph gives it
    /// (`common.clear` clears every resource it writes).
    fn bindings(&self) -> Option<&'static [Binding]>;
    /// An error unless each declared binding's resource holds the words it
    /// needs ([`Binding::check_size`]); `words(name)` is what the backend
    /// bound to `name`, 0 if nothing. Every backend calls it when it plans
    /// the pass.
    fn check_binding_sizes(&self, words: &dyn Fn(&str) -> u64) -> Result<(), String> {
        self.bindings()
            .unwrap_or(&[])
            .iter()
            .try_for_each(|b| b.check_size(words(b.name)))
    }
    fn workgroup_size(&self) -> u32;
    fn dispatch(&self) -> Dispatch;
    fn shader(&self) -> Shader;
    /// The entry point these parameters run: [`Shader::entry`], or one of
    /// [`PassDef::entries`] where the kind compiles a switch into entry
    /// points of its own ([`crate::params::PassParams::entry`]).
    fn entry(&self, params: &ron::Value) -> Result<&'static str, ParamError> {
        let _ = params;
        Ok(self.shader().entry)
    }
    /// Every entry point [`PassDef::entry`] may return, the default first.
    fn entries(&self) -> Vec<&'static str> {
        vec![self.shader().entry]
    }
    /// Checks parameters as a graph file or `--param` wrote them: unknown
    /// keys (including `model_index`, which only the per-model block sets),
    /// types and ranges. The error names the key.
    fn check_params(&self, params: &ron::Value) -> Result<(), ParamError> {
        let _ = params;
        Ok(())
    }
    /// Every parameter the kind takes, at its default, as a map from name
    /// to value ([`crate::params::defaults`]); `Unit` when it has no typed
    /// parameters.
    fn param_defaults(&self) -> ron::Value {
        ron::Value::Unit
    }
    /// Reads the graph's parameters and returns the CPU kernel configured by them.
    fn cpu_kernel(&self, params: &ron::Value) -> Result<Box<dyn CpuKernel>, ParamError>;
    /// The WGSL parameter block (binding 0) as 32-bit words: the pass's
    /// `#[repr(C)]` GPU block ([`crate::describe::GpuBlock`]) built from its
    /// parameters and the scene counts, as bytes. [`PassDef::gpu_layout`]
    /// gives its fields (`passes/tests/wgsl_params.rs` checks them with naga).
    ///
    /// For a pass whose `bindings()` is `None` (`common.clear`), the GPU
    /// backends dispatch once per written resource and put that resource's
    /// size in 32-bit words into the last word.
    ///
    /// The default refuses, naming the kind: a GPU backend cannot run the pass.
    fn gpu_params(&self, params: &ron::Value, q: &Quantities) -> Result<Vec<u32>, ParamError> {
        let _ = (params, q);
        Err(ParamError {
            kind: self.kind(),
            param: "params".into(),
            message: "the pass has no GPU parameter block yet (PassDef::gpu_params)".into(),
        })
    }
    /// Field names, offsets and size of the GPU parameter block.
    fn gpu_layout(&self) -> Option<GpuLayout> {
        None
    }
    /// The draw state of a raster pass (`shader().fragment` is `Some`);
    /// `None` for compute passes.
    fn raster(
        &self,
        params: &ron::Value,
        q: &Quantities,
    ) -> Result<Option<RasterState>, ParamError> {
        let _ = (params, q);
        Ok(None)
    }
}

/// `true`/`false` as a WGSL `u32` switch.
pub fn flag(b: bool) -> u32 {
    u32::from(b)
}

/// A scene count as a WGSL `u32` (saturating; no scene comes near 2^32).
pub fn count(n: u64) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

/// A kernel for the CPU simulator, run once per workgroup, workgroups in parallel.
///
/// Kernels see memory only through `ctx` (atomic words, as on a GPU) and use
/// `ctx`'s subgroup emulation and counters, so results that are
/// order-independent on a GPU are order-independent here too.
pub trait CpuKernel: Send + Sync {
    /// Runs once before the workgroups, like a render pass's load op
    /// (clearing attachments). Most kernels need nothing here.
    fn prologue(&self, _ctx: &Ctx<'_>) {}
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>);
}

/// Reads parameters out of a pass's RON map, with defaults, for pass
/// definitions written by hand (tests). Pass kinds declare typed,
/// checked parameters instead ([`crate::params::PassParams`]): this reader
/// ignores keys nobody asks for.
pub struct Params<'a> {
    kind: &'static str,
    map: Option<&'a ron::Map>,
}

impl<'a> Params<'a> {
    pub fn new(kind: &'static str, value: &'a ron::Value) -> Result<Self, ParamError> {
        match value {
            ron::Value::Map(m) => Ok(Self { kind, map: Some(m) }),
            ron::Value::Unit => Ok(Self { kind, map: None }),
            _ => Err(ParamError {
                kind,
                param: "params".into(),
                message: "expected a map".into(),
            }),
        }
    }

    fn get(&self, name: &str) -> Option<&'a ron::Value> {
        self.map?.get(&ron::Value::String(name.to_string()))
    }

    fn error(&self, name: &str, message: impl Into<String>) -> ParamError {
        ParamError {
            kind: self.kind,
            param: name.to_string(),
            message: message.into(),
        }
    }

    pub fn bool(&self, name: &str, default: bool) -> Result<bool, ParamError> {
        match self.get(name) {
            None => Ok(default),
            Some(ron::Value::Bool(b)) => Ok(*b),
            Some(v) => Err(self.error(name, format!("expected true or false, got {v:?}"))),
        }
    }

    pub fn f32(&self, name: &str, default: f32) -> Result<f32, ParamError> {
        match self.get(name) {
            None => Ok(default),
            Some(ron::Value::Number(n)) => Ok(n.into_f64() as f32),
            Some(v) => Err(self.error(name, format!("expected a number, got {v:?}"))),
        }
    }

    pub fn u32(&self, name: &str, default: u32) -> Result<u32, ParamError> {
        match self.get(name) {
            None => Ok(default),
            Some(ron::Value::Number(n)) => {
                let f = n.into_f64();
                if f >= 0.0 && f <= f64::from(u32::MAX) && f.fract() == 0.0 {
                    Ok(f as u32)
                } else {
                    Err(self.error(
                        name,
                        format!("expected a whole number in 0..=4294967295, got {f}"),
                    ))
                }
            }
            Some(v) => Err(self.error(name, format!("expected a number, got {v:?}"))),
        }
    }

    /// The model a pass of the graph's per-model block runs for
    /// (`strandgraph_graph::unroll`); `None` outside the block.
    pub fn model_index(&self) -> Result<Option<u32>, ParamError> {
        let name = strandgraph_graph::unroll::MODEL_INDEX;
        match self.get(name) {
            None => Ok(None),
            Some(_) => self.u32(name, 0).map(Some),
        }
    }

    pub fn string(&self, name: &str, default: &str) -> Result<String, ParamError> {
        match self.get(name) {
            None => Ok(default.to_string()),
            Some(ron::Value::String(s)) => Ok(s.clone()),
            Some(v) => Err(self.error(name, format!("expected a string, got {v:?}"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direct_dispatches_count_their_workgroups() {
        let q = Quantities {
            width: 10,
            height: 10,
            ..Quantities::default()
        };
        let per_pixel = Dispatch::PerElement {
            quantity: Quantity::Pixels,
            per_group: 64,
        };
        assert_eq!(per_pixel.direct_groups(&q, 0), Some(2));
        assert_eq!(Dispatch::Fixed(7).direct_groups(&q, 0), Some(7));
        let cover = Dispatch::CoverWrites {
            words_per_group: 256,
        };
        assert_eq!(cover.direct_groups(&q, 257), Some(2));
        // The crowd reference's records: 671M words, capped; kernels stride.
        assert_eq!(cover.direct_groups(&q, 671_000_000), Some(MAX_COVER_GROUPS));
        let indirect = Dispatch::Indirect {
            binding: "args",
            word: 0,
        };
        assert_eq!(indirect.direct_groups(&q, 1000), None);
        assert!(Binding::read("args").at_least(6).check_size(6).is_ok());
        let e = Binding::read("filter_args")
            .at_least(6)
            .check_size(4)
            .unwrap_err();
        assert!(e.contains("`filter_args`") && e.contains("24 bytes"), "{e}");
        assert!(Binding::read("args").check_size(0).is_ok());
        assert!(Dispatch::check_indirect("args", 8, 11).is_ok());
        let e = Dispatch::check_indirect("raster_args", 8, 8).unwrap_err();
        assert!(
            e.contains("words 8..11 of `raster_args`") && e.contains("44 bytes"),
            "{e}"
        );
    }

    #[test]
    fn typed_params_with_defaults_and_errors() {
        let v: ron::Value =
            ron::from_str(r#"{"a": true, "n": 64, "x": 0.5, "s": "Baked", "bad": -1}"#).unwrap();
        let p = Params::new("test", &v).unwrap();
        assert!(p.bool("a", false).unwrap());
        assert!(p.bool("missing", true).unwrap());
        assert_eq!(p.u32("n", 0).unwrap(), 64);
        assert_eq!(p.f32("x", 0.0).unwrap(), 0.5);
        assert_eq!(p.string("s", "").unwrap(), "Baked");
        let e = p.u32("bad", 0).unwrap_err();
        assert!(e.to_string().contains("`bad`"), "{e}");
        assert!(p.bool("n", false).is_err());
    }
}
