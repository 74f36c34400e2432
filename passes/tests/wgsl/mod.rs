//! What the WGSL reflection tests share: every pass's WGSL is composed and
//! validated with naga and checked against the pass contract (docs/architecture.md,
//! "Contracts"), one test file per concern:
//! - `wgsl_bindings.rs`: each kind's shader, entry points and bindings;
//! - `wgsl_params.rs`: each kind's GPU parameter block against its WGSL struct;
//! - `wgsl_shared.rs`: the shared WGSL (`layout.wgsl`'s records, the Lipp
//!   constants) against the Rust side.
//!
//! Shaders share `shaders/common/layout.wgsl` (and the Kulikov helpers in
//! `shaders/kulikov/common.wgsl`) through naga_oil's `#import`: every file
//! with a `#define_import_path` is added to one `Composer` as a composable
//! module, and each pass's file is composed into a naga module from there.

// Each test file compiles this module and uses only part of it.
#![allow(dead_code)]

pub mod reflect;

use naga::Module;
use naga::valid::{Capabilities, ModuleInfo};
use std::path::{Path, PathBuf};
use strandgraph_passes::layout::{FrameData, LightData, ModelData, TriangleData};
use strandgraph_passes::wgsl::{Shaders, validate};

/// What every shader may use: subgroup operations and subgroup barriers
/// (the Kulikov raster's request stacks, the cull's wave-aggregated atomics).
pub const BASE: Capabilities = Capabilities::SUBGROUP.union(Capabilities::SUBGROUP_BARRIER);

pub fn shaders_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders")
}

/// Every composable module under `shaders/`, loaded by the composition the
/// backends use ([`strandgraph_passes::wgsl::Shaders`]).
pub fn composer() -> Shaders {
    Shaders::load(&shaders_dir()).unwrap_or_else(|e| panic!("{e}"))
}

/// Composes and validates one top-level shader with the given capabilities.
pub fn compose(
    composer: &mut Shaders,
    file: &str,
    source: &str,
    caps: Capabilities,
) -> Result<(Module, ModuleInfo), String> {
    let module = composer.module_from_source(file, source)?;
    let info = validate(&module, caps).map_err(|e| format!("{file}: {e}"))?;
    Ok((module, info))
}

/// The shared records and their sizes on the Rust side.
pub fn record_sizes() -> [(&'static str, usize); 6] {
    use strandgraph_passes::kulikov::{ModelLod, tile_alloc::ModelTiles};
    [
        ("FrameData", std::mem::size_of::<FrameData>()),
        ("ModelData", std::mem::size_of::<ModelData>()),
        ("LightData", std::mem::size_of::<LightData>()),
        ("TriangleData", std::mem::size_of::<TriangleData>()),
        ("ModelLod", ModelLod::WORDS * 4),
        ("ModelTiles", ModelTiles::WORDS * 4),
    ]
}
