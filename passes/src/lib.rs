//! # strandgraph-passes
//!
//! Pass definitions shared by every backend. This crate implements the
//! graph compiler's [`PassRegistry`]: graph files name pass kinds such as
//! `"kulikov.raster"`, and the compiler rejects kinds not listed here.
//!
//! Each pass kind is declared once ([`PassKind`], listed in [`PASSES`]): its
//! interface, typed parameters, CPU kernel and GPU parameter block, and
//! which section of which paper specifies it.

// Kernels write `!(a > b)` on purpose: it rejects NaN together with the
// failing case, as their WGSL ports do.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod backend;
pub mod bench;
pub mod bind;
pub mod common;
pub mod contract;
pub mod describe;
#[cfg(test)]
mod fill_rule_checks;
pub mod hardware_raster;
pub mod hw_strands;
pub mod kernel;
pub mod kulikov;
pub mod layout;
pub mod lipp;
pub mod loop_counters;
pub mod opaque_mesh;
pub mod params;
pub mod raster_state;
pub mod reference;
pub mod scheuermann;
pub mod shipped;
pub mod sim;
pub mod spirv;
pub mod upload;
pub mod wgsl;

pub use contract::{Binding, CpuKernel, Dispatch, GpuLayout, ParamError, Params, PassDef, Shader};
pub use describe::{GpuBlock, PassKind};
pub use loop_counters::LoopCounters;
pub use params::{Invalid, NoParams, PassParams};
pub use raster_state::RasterState;
use strandgraph_graph::PassRegistry;
use strandgraph_graph::registry::ParamProblem;

/// Every pass kind, one declaration each (name, citation, interface,
/// parameters, kernels): the only list of kinds.
pub static PASSES: &[&dyn PassDef] = &[
    // Shared by every pipeline.
    &common::clear::CLEAR,
    &opaque_mesh::visibility::VISIBILITY,
    &opaque_mesh::depth_resolve::DEPTH_RESOLVE,
    &opaque_mesh::depth_resolve::DEPTH_HIZ,
    &opaque_mesh::opaque::OPAQUE,
    &opaque_mesh::depth_attachment::DEPTH_ATTACHMENT,
    // Kulikov 2025, SIGGRAPH Advances: Indiana Jones strand hair.
    &sim::grid::SPLAT,
    &sim::grid::SPLAT_CHAINS,
    &sim::pbd::PBD,
    &sim::pbd::PBD_CHAINS,
    &sim::follow::FOLLOW,
    &kulikov::lod::LOD,
    &kulikov::skin::SKIN,
    &kulikov::skin::SKIN_MOTION,
    &kulikov::density::DENSITY,
    &kulikov::depth_downsample::DEPTH_DOWNSAMPLE,
    &kulikov::cull::CULL,
    &kulikov::tile_alloc::TILE_ALLOC,
    &kulikov::sort::SORT_SCAN,
    &kulikov::sort::SORT,
    &kulikov::raster::RASTER,
    &kulikov::debug_resolve::DEBUG_RESOLVE,
    &kulikov::shade_sort::SHADE_SORT,
    &kulikov::shade::SHADE,
    &kulikov::compose::COMPOSE,
    &kulikov::skin_shadow::SKIN_SHADOW,
    &kulikov::motion::STORE_HISTORY,
    // Lipp et al., deferred software rasterization of hair meshes.
    &lipp::lod::LOD,
    &lipp::lod::scan::LOD_SCAN,
    &lipp::clear::CLEAR_GBUFFER,
    &lipp::raster::RASTER,
    &lipp::dom::DOM_DEPTH,
    &lipp::dom::DOM_OPACITY,
    &lipp::shade::SHADE,
    &lipp::filter::FILTER,
    // Scheuermann 2004: polygonal hair, the baseline.
    &scheuermann::hair::PRIME_DEPTH,
    &scheuermann::hair::OPAQUE,
    &scheuermann::hair::BACK_FACES,
    &scheuermann::hair::FRONT_FACES,
    &scheuermann::reference_shade::REFERENCE_SHADE,
    // Hardware-rasterized strands: Lipp's Table 1 baseline.
    &hw_strands::assemble::ASSEMBLE,
    &hw_strands::raster::RASTER,
    &hw_strands::mesh::MESH,
    // The ground-truth reference (docs/reference.md).
    &reference::bin::COUNT,
    &reference::scan::SCAN,
    &reference::bin::FILL,
    &reference::resolve::RESOLVE,
    &reference::bin::FILL_STRANDS,
    &lipp::reference::strands::STRANDS,
    &lipp::reference::shade::SHADE,
    // Roofline references for `strandgraph bench` (scenes/graphs/roofline.ron).
    &bench::ATOMIC_MIN32,
    &bench::ATOMIC_MIN64,
    &bench::COPY,
    &bench::RASTER,
];

/// The built-in pass kinds.
#[derive(Debug, Clone, Copy, Default)]
pub struct Registry;

impl Registry {
    pub fn get(&self, kind: &str) -> Option<&'static dyn PassDef> {
        PASSES.iter().copied().find(|d| d.kind() == kind)
    }
}

/// Where backends look up pass definitions; tests supply their own.
pub trait Definitions: Sync {
    /// The definition (interface, dispatch, kernels) of `kind`.
    fn definition(&self, kind: &str) -> Option<&dyn PassDef>;
}

impl Definitions for Registry {
    fn definition(&self, kind: &str) -> Option<&dyn PassDef> {
        self.get(kind)
    }
}

impl PassRegistry for Registry {
    fn contains(&self, kind: &str) -> bool {
        self.get(kind).is_some()
    }
    fn kinds(&self) -> Vec<&str> {
        PASSES.iter().map(|d| d.kind()).collect()
    }
    fn check_params(&self, kind: &str, params: &ron::Value) -> Result<(), ParamProblem> {
        let Some(def) = self.get(kind) else {
            return Ok(()); // the compiler reports the unknown kind
        };
        def.check_params(params).map_err(|e| ParamProblem {
            key: e.param,
            message: e.message,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_namespaced() {
        let mut names: Vec<&str> = PASSES.iter().map(|k| k.kind()).collect();
        names.sort_unstable();
        let before = names.len();
        names.dedup();
        assert_eq!(before, names.len(), "duplicate pass kind");
        for k in PASSES {
            assert!(
                k.kind().contains('.'),
                "{} has no pipeline prefix",
                k.kind()
            );
            assert!(
                !k.source().is_empty() && !k.summary().is_empty(),
                "{} is undocumented",
                k.kind()
            );
        }
    }

    #[test]
    fn every_definition_has_its_entry_point() {
        for d in PASSES {
            let wgsl = concat!(env!("CARGO_MANIFEST_DIR"), "/../shaders/");
            let path = std::path::Path::new(wgsl).join(d.shader().file);
            let text = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            for entry in d.entries() {
                assert!(
                    text.contains(&format!("fn {entry}(")),
                    "{} lacks entry point {entry}",
                    path.display()
                );
            }
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

    /// `lipp.filter`'s `centre_diameter` restates `lipp.raster`'s: the width
    /// of the lines whose coverage its hit ratio measures.
    #[test]
    fn shipped_filters_know_the_raster_line_width() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/graphs");
        let mut checked = 0;
        for graph in ["lipp.ron", "lipp_msaa.ron"] {
            let plan = strandgraph_graph::compile_file(
                std::path::Path::new(&format!("{dir}/{graph}")),
                &Registry,
                1,
            )
            .unwrap_or_else(|e| panic!("{e}"));
            let of = |kind: &str| {
                let pass = plan.graph.passes.iter().find(|p| p.kind == kind);
                pass.unwrap_or_else(|| panic!("{graph} has no {kind}"))
                    .params
                    .clone()
            };
            let raster = lipp::raster::RASTER.params(&of("lipp.raster")).unwrap();
            let filter = lipp::filter::FILTER.params(&of("lipp.filter")).unwrap();
            assert_eq!(raster.centre_diameter, filter.centre_diameter, "{graph}");
            checked += 1;
        }
        assert_eq!(checked, 2);
    }
}
