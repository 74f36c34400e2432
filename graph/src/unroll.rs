//! Unrolling the per-model block ([`Repeat::PerModel`]) for a scene's model
//! count, before dependency analysis.
//!
//! The graph is data flow, so running the same passes again needs fresh names
//! for what each run makes; unrolling gives them:
//! - a **local** transient (written only inside the block, used nowhere
//!   else) gets one copy per model: model 0 keeps the name, model k > 0 gets
//!   `name[k]`. The copies' lifetimes do not overlap, so the memory plan
//!   aliases them into one allocation;
//! - an **in-place write** `a -> b` inside the block chains: model 0 consumes
//!   `a`, model k consumes what model k − 1 made, and the last model makes
//!   `b`. Inside the block, `a` means "this model's input" and `b` "this
//!   model's result". This is how a groom sees the depth and colour of the
//!   grooms before it (Lipp §3.5: "preserving the depth buffer between groom
//!   passes");
//! - resources the block only reads are shared.
//!
//! Anything else the block writes (an imported or history resource, or a
//! transient that passes outside the block use) would have one writer per
//! model and no order between them: that is an error naming the pass.
//!
//! Each copy is named `pass[k]` (the plain name when the scene has one model)
//! and gets the param `model_index: k`.

use crate::error::{ErrorKind, GraphError, GraphErrors};
use crate::resolve::{Graph, Pass, ResourceId};
use crate::schema::{AccessMode, LifetimeClass, Repeat};
use std::collections::{BTreeMap, HashMap};

/// The param each copy of a repeated pass receives.
pub const MODEL_INDEX: &str = "model_index";

/// A pass name without the `[k]` an unrolled copy carries.
pub fn base_name(name: &str) -> &str {
    match name.strip_suffix(']').and_then(|s| s.rsplit_once('[')) {
        Some((base, k)) if !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()) => base,
        _ => name,
    }
}

/// Replaces the per-model block by `models` copies (at least one: a scene
/// without hair still runs the block once, for model 0).
pub fn unroll(mut g: Graph, models: u32) -> Result<Graph, GraphErrors> {
    let block: Vec<usize> = (0..g.passes.len())
        .filter(|&p| g.passes[p].repeat == Repeat::PerModel)
        .collect();
    let (Some(&first), Some(&last)) = (block.first(), block.last()) else {
        return Ok(g);
    };
    let mut errors = Vec::new();
    if let Some(gap) = (first..=last).find(|p| !block.contains(p)) {
        errors.push(
            GraphError::new(
                ErrorKind::BadAccess,
                &g.source,
                g.passes[gap].span,
                format!(
                    "pass `{}` sits between passes repeated per model; a graph has one per-model block of consecutive passes",
                    g.passes[gap].name
                ),
            )
            .label(g.passes[first].span, "the block starts here"),
        );
    }
    let roles = classify(&g, first, last, &mut errors);
    for &p in &block {
        let params_ok = match &g.passes[p].params {
            ron::Value::Map(m) => !m
                .iter()
                .any(|(k, _)| *k == ron::Value::String(MODEL_INDEX.into())),
            _ => false,
        };
        if !params_ok {
            errors.push(GraphError::new(
                ErrorKind::BadAccess,
                &g.source,
                g.passes[p].span,
                format!(
                    "pass `{}` is repeated per model, so its params must be a map without `{MODEL_INDEX}` (the repeat sets it)",
                    g.passes[p].name
                ),
            ));
        }
    }
    if !errors.is_empty() {
        return Err(GraphErrors(errors));
    }

    let n = models.max(1);
    // Per model, what each resource the block touches stands for.
    let mut maps: Vec<HashMap<ResourceId, ResourceId>> = vec![HashMap::new(); n as usize];
    for (&r, role) in &roles {
        match *role {
            Role::Local => {
                for (k, map) in maps.iter_mut().enumerate().skip(1) {
                    let copy = g.resources[r].clone();
                    map.insert(r, g.resources.len());
                    g.resources.push(crate::resolve::Resource {
                        name: format!("{}[{k}]", copy.name),
                        copy_of: Some(r),
                        ..copy
                    });
                }
            }
            Role::Chain { consumed } => {
                // Model k < n − 1 makes `b[k]`; the last model makes `b` itself.
                let made: Vec<ResourceId> = (0..n)
                    .map(|k| {
                        if k + 1 == n {
                            return r;
                        }
                        let copy = g.resources[r].clone();
                        g.resources.push(crate::resolve::Resource {
                            name: format!("{}[{k}]", copy.name),
                            ..copy
                        });
                        g.resources.len() - 1
                    })
                    .collect();
                for (k, map) in maps.iter_mut().enumerate() {
                    map.insert(r, made[k]);
                    if k > 0 {
                        map.insert(consumed, made[k - 1]);
                    }
                }
            }
        }
    }

    let mut passes: Vec<Pass> = g.passes.drain(..first).collect();
    let tail: Vec<Pass> = g.passes.drain(last + 1 - first..).collect();
    let template: Vec<Pass> = std::mem::take(&mut g.passes);
    for (k, map) in maps.iter().enumerate() {
        for t in &template {
            let mut p = t.clone();
            if n > 1 {
                p.name = format!("{}[{k}]", t.name);
            }
            p.model_index = Some(k as u32);
            if let ron::Value::Map(m) = &mut p.params {
                m.insert(
                    ron::Value::String(MODEL_INDEX.into()),
                    ron::Value::Number((k as u64).into()),
                );
            }
            let remap = |r: ResourceId| map.get(&r).copied().unwrap_or(r);
            for a in &mut p.accesses {
                a.resource = remap(a.resource);
            }
            for (r, _) in &mut p.bind_as {
                *r = remap(*r);
            }
            passes.push(p);
        }
    }
    passes.extend(tail);
    g.passes = passes;
    Ok(g)
}

/// What a resource written inside the block becomes when unrolled.
#[derive(Debug, Clone, Copy)]
enum Role {
    /// One copy per model.
    Local,
    /// A version made in place from `consumed`, chained model to model.
    Chain { consumed: ResourceId },
}

fn classify(
    g: &Graph,
    first: usize,
    last: usize,
    errors: &mut Vec<GraphError>,
) -> BTreeMap<ResourceId, Role> {
    let inside = |p: usize| (first..=last).contains(&p);
    let used_outside = |r: ResourceId| {
        g.passes
            .iter()
            .enumerate()
            .any(|(p, pass)| !inside(p) && pass.accesses.iter().any(|a| a.resource == r))
            || g.outputs.iter().any(|&(o, _)| o == r)
    };
    let mut roles = BTreeMap::new();
    for p in first..=last {
        let pass = &g.passes[p];
        for a in pass.accesses.iter().filter(|a| a.mode.writes()) {
            let r = a.resource;
            let res = &g.resources[r];
            // The old version an in-place write consumes is read by the same pass.
            let consumed = res.version_of.and_then(|_| {
                pass.accesses.iter().find(|b| {
                    b.mode == AccessMode::Read
                        && b.resource != r
                        && g.physical(b.resource) == g.physical(r)
                })
            });
            if let Some(c) = consumed {
                roles.insert(
                    r,
                    Role::Chain {
                        consumed: c.resource,
                    },
                );
                continue;
            }
            let local = res.version_of.is_none()
                && res.decl.lifetime() == LifetimeClass::Transient
                && !used_outside(r);
            if local {
                roles.entry(r).or_insert(Role::Local);
                continue;
            }
            errors.push(
                GraphError::new(
                    ErrorKind::UnorderedWriters,
                    &g.source,
                    a.span,
                    format!(
                        "pass `{}` is repeated per model and writes `{}`, which {}; every model would write it with nothing ordering them",
                        pass.name,
                        res.name,
                        if res.decl.lifetime() == LifetimeClass::Transient {
                            "passes outside the repeat also use"
                        } else {
                            "is not a transient"
                        }
                    ),
                )
                .label(res.span, "declared here")
                .help(format!(
                    "write it in place (`{0} -> {0}.next`) so each model continues from the last",
                    res.name
                )),
            );
        }
    }
    for (&r, role) in &roles {
        if let Role::Chain { consumed } = *role
            && matches!(roles.get(&consumed), Some(Role::Chain { .. }))
        {
            errors.push(GraphError::new(
                ErrorKind::BadAccess,
                &g.source,
                g.resources[r].span,
                format!(
                    "`{}` is made in place from `{}`, which the per-model block also makes in place; a block carries one version of a resource from model to model",
                    g.resources[r].name, g.resources[consumed].name
                ),
            ));
        }
        if let Role::Chain { consumed } = *role
            && matches!(roles.get(&consumed), Some(Role::Local))
        {
            errors.push(GraphError::new(
                ErrorKind::BadAccess,
                &g.source,
                g.resources[r].span,
                format!(
                    "`{}` is made in place from `{}`, which the per-model block also writes; an in-place write in the block carries a result from one model to the next, so its input must come from before the block",
                    g.resources[r].name, g.resources[consumed].name
                ),
            ));
        }
    }
    roles
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ErrorKind, KindList, Plan, Quantities, compile_str};

    /// Lipp's multi-groom shape: a shared input, a cleared per-model
    /// G-buffer, and an output and depth carried from model to model.
    const GROOMS: &str = r#"Graph(
    name: "grooms",
    resources: [
        Buffer(name: "scene", size: Bytes(64), lifetime: Imported),
        Buffer(name: "depth", size: Bytes(64)),
        Buffer(name: "gbuffer", size: Bytes(4096)),
        Buffer(name: "out", size: Bytes(64), lifetime: Imported),
    ],
    passes: [
        Pass(name: "clear_depth", kind: "common.clear", writes: ["depth"]),
        Pass(name: "clear", kind: "common.clear", repeat: PerModel, writes: ["gbuffer"]),
        Pass(name: "raster", kind: "test.draw", repeat: PerModel,
             reads: ["scene", "depth"], atomics: ["gbuffer"]),
        Pass(name: "filter", kind: "test.produce", repeat: PerModel, params: {"radius": 5},
             reads: ["gbuffer"], writes: ["out -> out.hair", "depth -> depth.hair"]),
        // Listing `out.hair` in reads as well as consuming it in place is one use.
        Pass(name: "post", kind: "test.consume", reads: ["out.hair"], writes: ["out.hair -> out.final"]),
    ],
    outputs: ["out.final"],
)"#;

    fn kinds() -> KindList {
        KindList::new(["common.clear", "test.draw", "test.produce", "test.consume"])
    }

    fn compile(src: &str, models: u32) -> Plan {
        compile_str("grooms.ron", src, &kinds(), models).unwrap_or_else(|e| panic!("{e}"))
    }

    fn pass(plan: &Plan, name: &str) -> usize {
        plan.graph
            .pass_id(name)
            .unwrap_or_else(|| panic!("no pass `{name}`"))
    }

    #[test]
    fn base_names() {
        assert_eq!(base_name("raster[12]"), "raster");
        assert_eq!(base_name("raster"), "raster");
        assert_eq!(base_name("a[b]"), "a[b]");
        assert_eq!(base_name("a[]"), "a[]");
    }

    #[test]
    fn one_model_keeps_names_and_gets_index_zero() {
        let plan = compile(GROOMS, 1);
        let filter = &plan.graph.passes[pass(&plan, "filter")];
        assert_eq!(filter.model_index, Some(0));
        let ron::Value::Map(m) = &filter.params else {
            panic!("params are a map")
        };
        assert_eq!(
            m.get(&ron::Value::String(MODEL_INDEX.into())),
            Some(&ron::Value::Number(0u64.into()))
        );
        assert_eq!(plan.graph.passes.len(), 5);
    }

    #[test]
    fn models_run_in_turn_each_seeing_the_last_ones_result() {
        let plan = compile(GROOMS, 3);
        let g = &plan.graph;
        assert_eq!(g.passes.len(), 2 + 3 * 3);
        let at = |name: &str| plan.position(pass(&plan, name)).unwrap();
        // The carried depth orders model k's raster after model k − 1's filter.
        for k in 1..3 {
            assert!(at(&format!("filter[{}]", k - 1)) < at(&format!("raster[{k}]")));
        }
        assert!(at("filter[2]") < at("post"));
        // Model 1's raster reads what model 0's filter made, not the cleared depth.
        let raster1 = &g.passes[pass(&plan, "raster[1]")];
        let depth_read = raster1
            .accesses
            .iter()
            .find(|a| g.physical(a.resource) == g.resource_id("depth").unwrap())
            .unwrap();
        assert_eq!(g.resources[depth_read.resource].name, "depth.hair[0]");
        // The last model makes the names the rest of the graph reads.
        let filter2 = &g.passes[pass(&plan, "filter[2]")];
        assert!(
            filter2
                .accesses
                .iter()
                .any(|a| a.mode.writes() && g.resources[a.resource].name == "out.hair")
        );
        assert!(
            plan.dependencies
                .iter()
                .any(|d| d.from == pass(&plan, "filter[2]") && d.to == pass(&plan, "post"))
        );
    }

    #[test]
    fn per_model_transients_are_copies_that_share_memory() {
        let plan = compile(GROOMS, 3);
        let g = &plan.graph;
        let copies: Vec<_> = ["gbuffer", "gbuffer[1]", "gbuffer[2]"]
            .iter()
            .map(|n| g.resource_id(n).unwrap_or_else(|| panic!("no `{n}`")))
            .collect();
        assert!(copies.iter().all(|&r| g.resources[r].version_of.is_none()));
        let raster2 = &g.passes[pass(&plan, "raster[2]")];
        assert!(raster2.accesses.iter().any(|a| a.resource == copies[2]));
        let memory = plan.instantiate(&Quantities::example()).unwrap().memory;
        // Three 4 KiB G-buffers live one after another: one allocation's worth.
        assert!(memory.bytes_without_aliasing >= 3 * 4096);
        assert!(
            memory.bytes_with_aliasing < memory.bytes_without_aliasing - 4096,
            "{} vs {}",
            memory.bytes_with_aliasing,
            memory.bytes_without_aliasing
        );
    }

    #[test]
    fn writing_a_shared_resource_per_model_is_an_error() {
        let src = GROOMS.replace(r#""out -> out.hair", "#, "").replace(
            r#"reads: ["out.hair"], writes: ["out.hair -> out.final"]"#,
            r#"reads: ["gbuffer"], writes: ["out"]"#,
        );
        let src = src.replace(r#"outputs: ["out.final"]"#, r#"outputs: ["out"]"#);
        let err = compile_str("bad.ron", &src, &kinds(), 2).unwrap_err();
        let e = err.first();
        assert_eq!(e.kind, ErrorKind::UnorderedWriters, "{err}");
        assert!(
            e.message.contains("clear") && e.message.contains("gbuffer"),
            "{e}"
        );
        assert_eq!(e.line, 11, "points at the access: {e}");
    }

    #[test]
    fn two_in_place_writes_of_one_resource_in_the_block_are_an_error() {
        let src = GROOMS.replace(
            r#"        Pass(name: "post""#,
            r#"        Pass(name: "tone", kind: "test.produce", repeat: PerModel, writes: ["out.hair -> out.toned"]),
        Pass(name: "post""#,
        );
        let err = compile_str("bad.ron", &src, &kinds(), 2).unwrap_err();
        assert!(
            err.0.iter().any(|e| e
                .message
                .contains("`out.toned` is made in place from `out.hair`")),
            "{err}"
        );
    }

    #[test]
    fn the_block_must_be_consecutive() {
        let src = GROOMS.replace(
            r#"Pass(name: "clear", kind: "common.clear", repeat: PerModel"#,
            r#"Pass(name: "clear", kind: "common.clear""#,
        );
        let src = src.replace(
            r#"Pass(name: "clear_depth", kind: "common.clear","#,
            r#"Pass(name: "clear_depth", kind: "common.clear", repeat: PerModel,"#,
        );
        let err = compile_str("bad.ron", &src, &kinds(), 2).unwrap_err();
        assert!(
            err.first().message.contains("`clear` sits between"),
            "{err}"
        );
    }
}
