//! Matching a graph pass's accesses to its kind's bindings, the same way on
//! every backend: by resource name, in the order the definition lists them.
//! A pass reading a version of a resource (`clip_positions.skinned`) binds
//! it under the resource's name (`clip_positions`), and a per-model copy
//! (`gbuffer[1]`) under the name of what it copies (`gbuffer`). An access
//! written `"shadow_lod as bundle_lod"` binds under the name after `as`.

use crate::contract::PassDef;
use strandgraph_graph::resolve::{Access, Graph, PassId};

/// A binding the graph gave: the name the kernel asks for and the access behind it.
#[derive(Debug, Clone)]
pub struct Bound {
    pub name: String,
    pub access: Access,
}

/// A binding the definition declares that the graph pass does not provide.
#[derive(Debug, Clone, thiserror::Error)]
#[error("pass `{pass}`: kind `{kind}` binds `{binding}`, which the graph does not give it")]
pub struct MissingBinding {
    pub pass: String,
    pub kind: String,
    pub binding: String,
}

/// The bindings of pass `p`, in the definition's order. A definition without
/// a fixed interface (`common.clear`) binds every resource the pass writes.
pub fn bind(def: &dyn PassDef, g: &Graph, p: PassId) -> Result<Vec<Bound>, MissingBinding> {
    let pass = &g.passes[p];
    let named = |a: &Access| Bound {
        name: g.resources[a.resource].name.clone(),
        access: *a,
    };
    match def.bindings() {
        None => Ok(pass
            .accesses
            .iter()
            .filter(|a| a.mode.writes())
            .map(named)
            .collect()),
        Some(wanted) => wanted
            .iter()
            .map(|b| {
                // A version (`a -> a.next`) binds under its resource's name,
                // so kernels need not know how the graph versions a resource.
                let root = |a: &&Access| {
                    let r = &g.resources[g.physical(a.resource)];
                    let r = r.copy_of.map_or(r, |c| &g.resources[c]);
                    r.name == b.name
                };
                let aliased = |a: &&Access| {
                    pass.bind_as
                        .iter()
                        .any(|(r, name)| *r == a.resource && name == b.name)
                };
                let plain = |a: &&Access| !pass.bind_as.iter().any(|(r, _)| *r == a.resource);
                pass.accesses
                    .iter()
                    .find(aliased)
                    .or_else(|| {
                        pass.accesses
                            .iter()
                            .filter(plain)
                            .find(|a| g.resources[a.resource].name == b.name)
                    })
                    .or_else(|| pass.accesses.iter().filter(plain).find(root))
                    .map(|a| Bound {
                        name: b.name.to_string(),
                        access: *a,
                    })
                    .ok_or_else(|| MissingBinding {
                        pass: pass.name.clone(),
                        kind: pass.kind.clone(),
                        binding: b.name.to_string(),
                    })
            })
            .collect(),
    }
}
