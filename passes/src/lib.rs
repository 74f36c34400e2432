//! # strandgraph-passes
//!
//! Pass definitions shared by every backend. This crate implements the
//! graph compiler's [`PassRegistry`]: graph files name pass kinds such as
//! `"kulikov.raster"`, and the compiler rejects kinds not listed here.
//!
//! Each entry says which pipeline it belongs to and which section of which
//! paper specifies it, so `strandgraph graph` can show where a pass comes from.

// Kernels write `!(a > b)` on purpose: it rejects NaN together with the
// failing case, as their WGSL ports do.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod backend;
pub mod bench;
pub mod bind;
mod catalogue;
pub mod common;
pub mod contract;
pub mod draw;
pub mod kulikov;
pub mod layout;
pub mod lipp;
pub mod scene;
pub mod sim;
pub mod spirv;
pub mod upload;
pub mod wgsl;

pub use catalogue::{KINDS, PassKind};
pub use contract::{Binding, CpuKernel, Dispatch, ParamError, Params, PassDef, Shader};
pub use draw::RasterState;
use strandgraph_graph::PassRegistry;

/// Pass kinds that have kernels so far. A kind listed in [`KINDS`] but not
/// here compiles in graphs; backends refuse to run it and say so.
static DEFINITIONS: &[&dyn PassDef] = &[
    &common::clear::Clear,
    &scene::depth_prepass::DepthPrepass,
    &scene::opaque::Opaque,
    &kulikov::lod::Lod,
    &kulikov::skin::Skin,
    &kulikov::hiz::DepthDownsample,
    &kulikov::cull::Cull,
    &kulikov::tiles::TileAlloc,
    &kulikov::sort::SortScan,
    &kulikov::sort::Sort,
    &kulikov::raster::Raster,
    &kulikov::debug_resolve::DebugResolve,
    &kulikov::density::Density,
    &kulikov::skin_shadow::SkinShadow,
    &kulikov::shade_sort::ShadeSort,
    &kulikov::shade::Shade,
    &kulikov::compose::Compose,
    &kulikov::history::Motion,
    &kulikov::history::StoreHistory,
    &kulikov::pixel_motion::PixelMotion,
    &lipp::lod::Lod,
    &lipp::raster::Raster,
    &lipp::dom::DomDepth,
    &lipp::dom::DomOpacity,
    &lipp::shade::Shade,
    &lipp::filter::Filter,
    &bench::ATOMIC_MIN32,
    &bench::ATOMIC_MIN64,
    &bench::Copy,
];

/// The built-in pass kinds.
#[derive(Debug, Clone, Copy, Default)]
pub struct Registry;

impl Registry {
    pub fn get(&self, kind: &str) -> Option<&'static PassKind> {
        KINDS.iter().find(|k| k.name == kind)
    }
}

/// Where backends look up pass definitions; tests supply their own.
pub trait Definitions: Sync {
    /// The definition (interface, dispatch, kernels) of `kind`, if it has one yet.
    fn definition(&self, kind: &str) -> Option<&dyn PassDef>;
}

impl Definitions for Registry {
    fn definition(&self, kind: &str) -> Option<&dyn PassDef> {
        DEFINITIONS.iter().copied().find(|d| d.kind() == kind)
    }
}

impl PassRegistry for Registry {
    fn contains(&self, kind: &str) -> bool {
        self.get(kind).is_some()
    }
    fn kinds(&self) -> Vec<&str> {
        KINDS.iter().map(|k| k.name).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_namespaced() {
        let mut names: Vec<&str> = KINDS.iter().map(|k| k.name).collect();
        names.sort_unstable();
        let before = names.len();
        names.dedup();
        assert_eq!(before, names.len(), "duplicate pass kind");
        for k in KINDS {
            assert!(k.name.contains('.'), "{} has no pipeline prefix", k.name);
            assert!(
                !k.source.is_empty() && !k.summary.is_empty(),
                "{} is undocumented",
                k.name
            );
        }
    }

    #[test]
    fn every_definition_is_in_the_catalogue() {
        for d in DEFINITIONS {
            assert!(
                Registry.get(d.kind()).is_some(),
                "{} is defined but not catalogued",
                d.kind()
            );
            let wgsl = concat!(env!("CARGO_MANIFEST_DIR"), "/../shaders/");
            let path = std::path::Path::new(wgsl).join(d.shader().file);
            let text = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(
                text.contains(&format!("fn {}(", d.shader().entry)),
                "{} lacks entry point",
                path.display()
            );
        }
    }

    #[test]
    fn shipped_graphs_use_only_registered_kinds() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/graphs");
        let mut seen = 0;
        for entry in std::fs::read_dir(dir).expect("scenes/graphs exists") {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "ron") {
                // One model, and three: every per-model block unrolls cleanly.
                for models in [1, 3] {
                    strandgraph_graph::compile_file(&path, &Registry, models)
                        .unwrap_or_else(|e| panic!("{e}"));
                }
                seen += 1;
            }
        }
        assert!(
            seen >= 2,
            "expected the kulikov and lipp graphs, found {seen}"
        );
    }
}
