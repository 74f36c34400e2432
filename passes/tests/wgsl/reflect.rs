//! The group-0 resources an entry point uses, as reflected from a composed
//! module, and whether each is accessed as a binding mode declares.

use naga::valid::ModuleInfo;
use naga::{AddressSpace, ImageClass, Module, StorageAccess, TypeInner};
use std::collections::BTreeMap;
use strandgraph_graph::AccessMode;

/// A resource an entry point uses, as reflected from the module.
#[derive(Debug)]
pub struct Reflected {
    pub name: String,
    pub kind: Kind,
}

/// How a resource is declared in WGSL.
#[derive(Debug, PartialEq)]
pub enum Kind {
    Uniform { is_struct: bool },
    Storage { access: StorageAccess, atomic: bool },
    StorageTexture { access: StorageAccess },
    Texture,
    Sampler,
    Other(String),
}

fn contains_atomic(module: &Module, ty: naga::Handle<naga::Type>) -> bool {
    match &module.types[ty].inner {
        TypeInner::Atomic(_) => true,
        TypeInner::Array { base, .. } | TypeInner::BindingArray { base, .. } => {
            contains_atomic(module, *base)
        }
        TypeInner::Struct { members, .. } => members.iter().any(|m| contains_atomic(module, m.ty)),
        _ => false,
    }
}

/// `name` without naga_oil's module decoration: a binding declared in an
/// imported module (`shaders/kulikov/segments.wgsl`) keeps its WGSL name
/// before the suffix naga_oil appends (`Composer::decorated_name`: the
/// marker below, then the module path in base32).
fn undecorated(name: &str) -> &str {
    name.split_once("X_naga_oil_mod_X")
        .map_or(name, |(plain, _)| plain)
}

/// The group-0 resources the named entry points use, by binding number.
pub fn reflect(
    module: &Module,
    info: &ModuleInfo,
    entries: &[&str],
) -> Result<BTreeMap<u32, Reflected>, String> {
    let mut out = BTreeMap::new();
    for (index, ep) in module.entry_points.iter().enumerate() {
        if !entries.contains(&ep.name.as_str()) {
            continue;
        }
        let uses = info.get_entry_point(index);
        for (handle, var) in module.global_variables.iter() {
            if uses[handle].is_empty() {
                continue;
            }
            let Some(rb) = &var.binding else { continue };
            let name = undecorated(var.name.as_deref().unwrap_or_default()).to_string();
            if rb.group != 0 {
                return Err(format!("`{name}` is in group {}, expected 0", rb.group));
            }
            let inner = &module.types[var.ty].inner;
            let kind = match (var.space, inner) {
                (AddressSpace::Uniform, inner) => Kind::Uniform {
                    is_struct: matches!(inner, TypeInner::Struct { .. }),
                },
                (AddressSpace::Storage { access }, _) => Kind::Storage {
                    access,
                    atomic: contains_atomic(module, var.ty),
                },
                (AddressSpace::Handle, TypeInner::Image { class, .. }) => match class {
                    ImageClass::Storage { access, .. } => Kind::StorageTexture { access: *access },
                    _ => Kind::Texture,
                },
                (AddressSpace::Handle, TypeInner::Sampler { .. }) => Kind::Sampler,
                (space, inner) => Kind::Other(format!("{space:?} {inner:?}")),
            };
            if let Some(prev) = out.get(&rb.binding) {
                let prev: &Reflected = prev;
                if prev.name != name {
                    return Err(format!(
                        "binding {} is both `{}` and `{name}`",
                        rb.binding, prev.name
                    ));
                }
                continue;
            }
            out.insert(rb.binding, Reflected { name, kind });
        }
    }
    Ok(out)
}

/// Whether a resource declared as `kind` is accessed as `mode` says (see
/// `wgsl_bindings.rs`).
pub fn access_matches(mode: AccessMode, kind: &Kind) -> bool {
    let rw = StorageAccess::LOAD | StorageAccess::STORE;
    match (mode, kind) {
        (AccessMode::Read, Kind::Storage { access, .. }) => *access == StorageAccess::LOAD,
        (AccessMode::Read, Kind::StorageTexture { access }) => *access == StorageAccess::LOAD,
        (AccessMode::Read, Kind::Texture | Kind::Uniform { .. }) => true,
        (AccessMode::Write, Kind::Storage { access, .. }) => *access == rw,
        (AccessMode::Write, Kind::StorageTexture { access }) => {
            access.contains(StorageAccess::STORE)
        }
        (AccessMode::Atomic, Kind::Storage { access, atomic }) => *access == rw && *atomic,
        (AccessMode::Atomic, Kind::StorageTexture { access }) => *access == rw,
        _ => false,
    }
}
