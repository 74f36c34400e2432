//! Typed pass parameters: each pass kind declares a `serde` struct of its
//! parameters, and the graph's RON map is deserialised into it.
//!
//! `#[serde(deny_unknown_fields, default)]` makes a misspelt key an error
//! (naming the closest valid key) instead of a silently ignored switch, and
//! [`PassParams::validate`] checks ranges. Every error names the offending
//! key, so the graph compiler can point at it (`PassRegistry::check_params`).
//!
//! [`override_param`] applies the command line's `--param PASS.PARAM=VALUE`
//! to a compiled plan, checked the same way (the fuzz target `param`).

use serde::de::DeserializeOwned;
use strandgraph_graph::unroll::MODEL_INDEX;
use strandgraph_graph::{PassRegistry, Plan, Usage};

/// A parameter value that is unknown, mistyped or out of range.
#[derive(Debug, Clone, PartialEq)]
pub struct Invalid {
    /// The key, or empty when the whole parameter block is wrong.
    pub key: String,
    pub message: String,
}

impl Invalid {
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            message: message.into(),
        }
    }
}

/// A pass kind's parameters.
pub trait PassParams:
    DeserializeOwned + serde::Serialize + Default + Send + Sync + 'static
{
    /// Whether the kind reads `model_index`, which graph/src/unroll.rs adds
    /// to every pass of a per-model block (declare it as
    /// `#[serde(deserialize_with = "crate::params::some")] model_index: Option<u32>`).
    /// Kinds that do not read it may still sit in the block; they never see it.
    const READS_MODEL_INDEX: bool = false;

    /// Range checks the types cannot express.
    fn validate(&self) -> Result<(), Invalid> {
        Ok(())
    }

    /// Entry points besides the kind's [`crate::contract::Shader::entry`]
    /// that [`PassParams::entry`] may choose.
    const VARIANT_ENTRIES: &'static [&'static str] = &[];

    /// The entry point for these parameters; `default` is the kind's. A
    /// kind compiles a switch into an entry point of its own where a branch
    /// would cost every variant: the registers a branch's other side holds
    /// live are the kernel's, whichever side runs.
    fn entry(&self, default: &'static str) -> &'static str {
        default
    }
}

/// No parameters: only an empty map (or none) is accepted.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct NoParams {}

impl PassParams for NoParams {}

/// A kind's parameters at their defaults, as a map from each name to its
/// value: every parameter a graph file may set (the viewer's widgets).
pub fn defaults<P: PassParams>() -> ron::Value {
    let Ok(text) = ron::to_string(&P::default()) else {
        return ron::Value::Unit;
    };
    match ron::from_str(&text) {
        Ok(ron::Value::Map(map)) => ron::Value::Map(map),
        // A struct without fields writes `()`.
        Ok(ron::Value::Unit) => ron::Value::Map(ron::Map::new()),
        _ => ron::Value::Unit,
    }
}

/// Parses the parameters a graph file (or `--param`) wrote: every key must
/// be one the kind declares, `model_index` included.
pub fn check<P: PassParams>(value: &ron::Value) -> Result<P, Invalid> {
    parse_map(value, false)
}

/// Parses the parameters of a compiled pass: as [`check`], but a
/// `model_index` the unrolling added is dropped for kinds that do not read it.
pub fn parse<P: PassParams>(value: &ron::Value) -> Result<P, Invalid> {
    parse_map(value, !P::READS_MODEL_INDEX)
}

fn parse_map<P: PassParams>(value: &ron::Value, drop_model_index: bool) -> Result<P, Invalid> {
    let map = match value {
        ron::Value::Unit => ron::Map::new(),
        ron::Value::Map(m) => m.clone(),
        other => {
            return Err(Invalid::new(
                "",
                format!("expected a map of parameters, found {}", describe(other)),
            ));
        }
    };
    let mut kept = ron::Map::new();
    for (k, v) in map.iter() {
        let ron::Value::String(key) = k else {
            return Err(Invalid::new(
                "",
                format!("parameter names are strings, found {}", describe(k)),
            ));
        };
        if !(drop_model_index && key == MODEL_INDEX) {
            kept.insert(k.clone(), v.clone());
        }
    }
    let parsed = match ron::Value::Map(kept.clone()).into_rust::<P>() {
        Ok(p) => p,
        Err(whole) => return Err(locate::<P>(&kept, &whole)),
    };
    parsed.validate()?;
    Ok(parsed)
}

/// Finds the key a failed deserialisation is about: serde's errors carry no
/// path, so each key is tried alone (the struct is `#[serde(default)]`, so
/// one valid key on its own always parses).
fn locate<P: PassParams>(map: &ron::Map, whole: &ron::Error) -> Invalid {
    for (k, v) in map.iter() {
        let ron::Value::String(key) = k else { continue };
        let mut one = ron::Map::new();
        one.insert(k.clone(), v.clone());
        if let Err(e) = ron::Value::Map(one).into_rust::<P>() {
            return Invalid::new(key.clone(), message(key, &e));
        }
    }
    Invalid::new("", lower_first(&whole.to_string()))
}

fn message(key: &str, e: &ron::Error) -> String {
    match e {
        ron::Error::NoSuchStructField { expected, .. } => {
            let mut m = String::from("unknown");
            match closest(key, expected) {
                Some(s) => m.push_str(&format!(", did you mean `{s}`?")),
                None if expected.is_empty() => m.push_str(" (the pass takes no parameters)"),
                None => m.push_str(&format!(" (parameters: {})", expected.join(", "))),
            }
            m
        }
        ron::Error::InvalidValueForType { expected, found } => {
            format!("expected {expected}, found {found}")
        }
        other => lower_first(&other.to_string()),
    }
}

/// The valid key most like `wanted`, when it is close enough to be a typo.
pub fn closest<'a>(wanted: &str, valid: &[&'a str]) -> Option<&'a str> {
    valid
        .iter()
        .map(|k| (strsim::jaro_winkler(k, wanted), *k))
        .filter(|(score, _)| *score > 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, k)| k)
}

fn describe(v: &ron::Value) -> &'static str {
    match v {
        ron::Value::Bool(_) => "a boolean",
        ron::Value::Char(_) => "a char",
        ron::Value::Map(_) => "a map",
        ron::Value::Number(_) => "a number",
        ron::Value::Option(_) => "an option",
        ron::Value::String(_) => "a string",
        ron::Value::Bytes(_) => "bytes",
        ron::Value::Seq(_) => "a list",
        ron::Value::Unit => "()",
    }
}

fn lower_first(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_lowercase().chain(c).collect(),
        None => String::new(),
    }
}

/// An `Option` parameter written as its value: `Some(v)` as `v` (the
/// counterpart of [`some`]), so that defaults and widgets show a plain value.
pub fn plain<S, T>(v: &Option<T>, s: S) -> Result<S::Ok, S::Error>
where
    S: serde::Serializer,
    T: serde::Serialize,
{
    match v {
        Some(v) => v.serialize(s),
        None => s.serialize_none(),
    }
}

/// `model_index` as `Option<u32>`: ron's `Value` has no options of its own,
/// so a present number means `Some`.
pub fn some<'de, D, T>(d: D) -> Result<Option<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: serde::Deserialize<'de>,
{
    T::deserialize(d).map(Some)
}

/// `value` within `range`, or an error naming `key`.
pub fn in_range<T>(key: &str, value: T, range: std::ops::RangeInclusive<T>) -> Result<(), Invalid>
where
    T: PartialOrd + std::fmt::Display,
{
    if range.contains(&value) {
        Ok(())
    } else {
        Err(Invalid::new(
            key,
            format!("{value} is outside {}..={}", range.start(), range.end()),
        ))
    }
}

/// A finite number `>= 0`, or an error naming `key`.
pub fn non_negative(key: &str, value: f32) -> Result<(), Invalid> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(Invalid::new(
            key,
            format!("expected a finite number >= 0, got {value}"),
        ))
    }
}

/// How a [`string_enum!`] refuses a name: the valid names, then the one
/// found. [`choices`] reads the names back out of it.
pub fn one_of(names: &[&str], found: &str) -> String {
    format!(
        "expected one of \"{}\", found \"{found}\"",
        names.join("\", \"")
    )
}

/// The names a string-valued parameter `key` of `def` accepts (a
/// [`string_enum!`]), found by offering it a name no switch has; `None`
/// for a parameter that takes any string or no string.
pub fn choices(def: &dyn crate::PassDef, key: &str) -> Option<Vec<String>> {
    const PROBE: &str = "\u{1}";
    let mut map = ron::Map::new();
    map.insert(
        ron::Value::String(key.into()),
        ron::Value::String(PROBE.into()),
    );
    let message = def.check_params(&ron::Value::Map(map)).err()?.message;
    let start = message.find("expected one of \"")? + "expected one of \"".len();
    let end = message.find(&format!("\", found \"{PROBE}\""))?;
    let names = message.get(start..end)?;
    Some(names.split("\", \"").map(str::to_string).collect())
}

/// A string-valued switch (`"self_shadow": "Baked"`): ron's `Value` keeps no
/// enum variants, so the variants are matched by name, and a wrong one lists
/// the valid names.
#[macro_export]
macro_rules! string_enum {
    ($(#[$m:meta])* $vis:vis enum $name:ident { $($(#[$vm:meta])* $variant:ident),+ $(,)? }) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        $vis enum $name { $($(#[$vm])* $variant),+ }

        impl $name {
            pub const NAMES: &'static [&'static str] = &[$(stringify!($variant)),+];
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(match self { $(Self::$variant => stringify!($variant)),+ })
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let s = <String as serde::Deserialize>::deserialize(d)?;
                match s.as_str() {
                    $(stringify!($variant) => Ok(Self::$variant),)+
                    _ => Err(serde::de::Error::custom(
                        $crate::params::one_of(Self::NAMES, &s),
                    )),
                }
            }
        }
    };
}

/// Applies `PASS.PARAM=VALUE` (VALUE in RON: `false`, `64`, `"Baked"`) to a
/// compiled plan: how ablations run without editing the graph file
/// (`--param`). `raster.x=…` sets every per-model copy (`raster[0]`,
/// `raster[1]`, …), `raster[1].x=…` one; `IMAGE.samples=N` sets an
/// attachment's sample count. Checked as the graph compiler checks the
/// file's parameters (unknown key with the closest valid one, type, range);
/// the error starts `--param SPEC:`.
pub fn override_param(plan: &mut Plan, spec: &str) -> Result<(), String> {
    let bad =
        || format!("--param {spec}: expected PASS.PARAM=VALUE, e.g. raster.loop_flattening=false");
    let (target, value) = spec.split_once('=').ok_or_else(bad)?;
    if let Some(image) = target.trim().strip_suffix(".samples")
        && plan.graph.resource_id(image).is_some()
    {
        return override_samples(plan, spec, image, value);
    }
    let (pass, param) = target.split_once('.').ok_or_else(bad)?;
    let value: ron::Value = ron::from_str(value.trim())
        .map_err(|e| format!("--param {spec}: value is not RON: {e}"))?;
    let pass = pass.trim();
    let targets: Vec<usize> = (0..plan.graph.passes.len())
        .filter(|&p| {
            let name = &plan.graph.passes[p].name;
            name == pass || strandgraph_graph::base_name(name) == pass
        })
        .collect();
    if targets.is_empty() {
        return Err(format!(
            "--param {spec}: graph `{}` has no pass `{pass}`",
            plan.graph.name
        ));
    }
    // Every copy's new parameters are checked before any is written, so a
    // failed override leaves the plan as it was.
    let mut written = Vec::with_capacity(targets.len());
    for p in targets {
        let pass = &plan.graph.passes[p];
        let mut params = match &pass.params {
            ron::Value::Map(m) => m.clone(),
            _ => ron::Map::new(),
        };
        params.insert(ron::Value::String(param.trim().to_string()), value.clone());
        check_override(&pass.name, &pass.kind, &params, param.trim())
            .map_err(|e| format!("--param {spec}: {e}"))?;
        written.push((p, params));
    }
    for (p, params) in written {
        plan.graph.passes[p].params = ron::Value::Map(params);
    }
    Ok(())
}

/// `IMAGE.samples=N`: an attachment's sample count (how a bench row runs
/// one graph at MSAA 1, 4 and 8), checked as the graph compiler checks it.
fn override_samples(plan: &mut Plan, spec: &str, image: &str, value: &str) -> Result<(), String> {
    use strandgraph_graph::schema::ResourceDecl;
    let n: u32 = value
        .trim()
        .parse()
        .map_err(|_| format!("--param {spec}: samples must be 1, 2, 4 or 8"))?;
    let g = &mut plan.graph;
    let r = g.physical(g.resource_id(image).expect("checked by the caller"));
    // The image and its versions (`a -> a.final`) share one declaration.
    let versions: Vec<usize> = (0..g.resources.len())
        .filter(|&v| v == r || g.resources[v].version_of == Some(r))
        .collect();
    let buffer = || format!("--param {spec}: `{image}` is a buffer, not an image");
    // The new declaration is checked before it is written anywhere, so a
    // failed override leaves the plan as it was.
    let mut decl = g.resources[r].decl.clone();
    let ResourceDecl::Image { samples, .. } = &mut decl else {
        return Err(buffer());
    };
    *samples = n;
    if let Some(why) = strandgraph_graph::resolve::samples_problem(&decl) {
        return Err(format!("--param {spec}: image `{image}` {why}"));
    }
    let attachment_only = g
        .passes
        .iter()
        .flat_map(|p| &p.accesses)
        .all(|a| g.physical(a.resource) != r || matches!(a.usage, Usage::Color | Usage::Depth));
    if n > 1 && !attachment_only {
        return Err(format!(
            "--param {spec}: a pass uses `{image}` as more than an attachment, so it cannot be multisampled"
        ));
    }
    if versions
        .iter()
        .any(|&v| !matches!(g.resources[v].decl, ResourceDecl::Image { .. }))
    {
        return Err(buffer());
    }
    for v in versions {
        if let ResourceDecl::Image { samples, .. } = &mut g.resources[v].decl {
            *samples = n;
        }
    }
    Ok(())
}

/// Checks a pass's parameters after an override as the graph compiler
/// checks the file's (unknown key with the closest valid one, type, range).
/// `model_index`, which unrolling adds to per-model passes, is the block's
/// to set, not the command line's.
fn check_override(pass: &str, kind: &str, params: &ron::Map, param: &str) -> Result<(), String> {
    if param == MODEL_INDEX {
        return Err(format!(
            "pass `{pass}`: `{param}` is set by the per-model block"
        ));
    }
    let mut written = params.clone();
    written.remove(&ron::Value::String(MODEL_INDEX.into()));
    crate::Registry
        .check_params(kind, &ron::Value::Map(written))
        .map_err(|p| {
            let key = if p.key.is_empty() {
                "params".into()
            } else {
                format!("parameter `{}`", p.key)
            };
            format!("pass `{pass}` ({kind}): {key}: {}", p.message)
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every string-valued parameter of every kind lists its names, its
    /// default among them, and each name is accepted.
    #[test]
    fn every_string_switch_lists_names_it_accepts() {
        let mut switches = 0;
        for def in crate::PASSES {
            let ron::Value::Map(map) = def.param_defaults() else {
                continue;
            };
            for (key, value) in map.iter() {
                let (ron::Value::String(key), ron::Value::String(default)) = (key, value) else {
                    continue;
                };
                let names =
                    choices(*def, key).unwrap_or_else(|| panic!("{}.{key}: no names", def.kind()));
                assert!(names.contains(default), "{}.{key}: {names:?}", def.kind());
                for name in &names {
                    let mut one = ron::Map::new();
                    one.insert(
                        ron::Value::String(key.clone()),
                        ron::Value::String(name.clone()),
                    );
                    def.check_params(&ron::Value::Map(one))
                        .unwrap_or_else(|e| panic!("{}.{key}={name}: {e}", def.kind()));
                }
                switches += 1;
            }
        }
        assert!(switches >= 3, "only {switches} string switches found");
    }

    /// Every kind's defaults are a map a graph file could write back: each
    /// name is one the kind accepts, each value one it parses (what the
    /// viewer's widgets start from).
    #[test]
    fn every_kinds_defaults_are_parameters_it_accepts() {
        for def in crate::PASSES {
            let defaults = def.param_defaults();
            let ron::Value::Map(map) = &defaults else {
                panic!("{}: defaults are not a map: {defaults:?}", def.kind());
            };
            let mut written = map.clone();
            written.remove(&ron::Value::String(MODEL_INDEX.into()));
            def.check_params(&ron::Value::Map(written))
                .unwrap_or_else(|e| panic!("{}: {e}", def.kind()));
        }
    }

    string_enum! {
        enum Mode { Fast, Exact }
    }

    #[derive(Debug, PartialEq, serde::Deserialize, serde::Serialize)]
    #[serde(deny_unknown_fields, default)]
    struct Example {
        flag: bool,
        count: u32,
        scale: f32,
        mode: Mode,
    }

    impl Default for Example {
        fn default() -> Self {
            Self {
                flag: true,
                count: 4,
                scale: 1.0,
                mode: Mode::Fast,
            }
        }
    }

    impl PassParams for Example {
        fn validate(&self) -> Result<(), Invalid> {
            in_range("count", self.count, 1..=8)
        }
    }

    fn v(s: &str) -> ron::Value {
        ron::from_str(s).unwrap()
    }

    #[test]
    fn defaults_and_values() {
        assert_eq!(check::<Example>(&ron::Value::Unit), Ok(Example::default()));
        let p: Example = check(&v(r#"{"flag": false, "scale": 2, "mode": "Exact"}"#)).unwrap();
        assert_eq!(
            (p.flag, p.count, p.scale, p.mode),
            (false, 4, 2.0, Mode::Exact)
        );
    }

    #[test]
    fn errors_name_the_key() {
        let e = check::<Example>(&v(r#"{"count": 2, "flga": true}"#)).unwrap_err();
        assert_eq!(e.key, "flga");
        assert!(e.message.contains("did you mean `flag`"), "{}", e.message);
        let e = check::<Example>(&v(r#"{"scael": 2}"#)).unwrap_err();
        assert_eq!(e.key, "scael");
        assert!(e.message.contains("did you mean `scale`"), "{}", e.message);
        let e = check::<Example>(&v(r#"{"flag": 1}"#)).unwrap_err();
        assert_eq!(e.key, "flag");
        assert!(e.message.contains("boolean"), "{}", e.message);
        let e = check::<Example>(&v(r#"{"count": 9}"#)).unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.message.as_str()),
            ("count", "9 is outside 1..=8")
        );
        let e = check::<Example>(&v(r#"{"mode": "Slow"}"#)).unwrap_err();
        assert!(e.message.contains("\"Fast\", \"Exact\""), "{}", e.message);
        let e = check::<Example>(&v("[1, 2]")).unwrap_err();
        assert_eq!(e.key, "");
    }

    /// Found by the `param` fuzz target: `strand_depth.samples=3` was refused
    /// after the sample count had been written, leaving the plan with a
    /// 3-sample image; a per-model override could likewise set some copies
    /// before another's check failed. A failed override now changes nothing.
    #[test]
    fn a_failed_override_leaves_the_plan_as_it_was() {
        let text = include_str!("../../scenes/graphs/hw_mesh.ron");
        let mut plan =
            strandgraph_graph::compile_str("hw_mesh.ron", text, &crate::Registry, 2).unwrap();
        let snapshot = |plan: &Plan| {
            let g = &plan.graph;
            let params: Vec<_> = g.passes.iter().map(|p| p.params.clone()).collect();
            (params, format!("{:?}", g.resources))
        };
        let before = snapshot(&plan);
        for spec in [
            "strand_depth.samples=3",
            "strand_depth.samples=x",
            "filter.msaa=3",
            "filter.model_index=1",
            "filter[1].nope=1",
            "nope.x=1",
            "filter.msaa",
            "filter.msaa=(",
        ] {
            let e = override_param(&mut plan, spec).unwrap_err();
            assert!(e.starts_with(&format!("--param {spec}: ")), "{e}");
            assert!(snapshot(&plan) == before, "{spec} changed the plan: {e}");
        }
        override_param(&mut plan, "strand_depth.samples=8").unwrap();
        override_param(&mut plan, "filter.msaa=8").unwrap();
        assert!(snapshot(&plan) != before);
    }

    #[test]
    fn model_index_is_dropped_only_for_kinds_that_ignore_it() {
        let m = v(r#"{"model_index": 1}"#);
        assert!(parse::<Example>(&m).is_ok());
        assert_eq!(check::<Example>(&m).unwrap_err().key, "model_index");
    }
}
