//! Binding each pass, filling its parameter block and composing its shader:
//! everything about a pass that needs no device.

use crate::device::Needs;
use crate::error::AshError;
use strandgraph_graph::resolve::PassId;
use strandgraph_graph::schema::{AccessMode, Usage};
use strandgraph_graph::{Instance, Plan};
use strandgraph_passes::wgsl::{CAPABILITIES, Composed, Shaders};
use strandgraph_passes::{Definitions, PassDef, RasterState};

/// A pass ready to build a pipeline for.
pub(crate) struct Prepared<'d> {
    pub p: PassId,
    pub def: &'d dyn PassDef,
    /// Binding name, physical resource id and usage, in `bindings()` order.
    pub bindings: Vec<(String, usize, Usage)>,
    pub params: Vec<u32>,
    /// The compute (or vertex) entry point these parameters run (`PassDef::entry`).
    pub entry: &'static str,
    pub composed: Composed,
    /// The draw state of a raster pass (`PassDef::raster`).
    pub raster: Option<RasterState>,
}

impl Prepared<'_> {
    pub fn is_raster(&self) -> bool {
        self.def.shader().fragment.is_some()
    }
}

/// Looks up every live pass's definition, binds it, fills its parameter block
/// and composes its shader; collects what the device must support.
pub(crate) fn prepare<'d>(
    defs: &'d dyn Definitions,
    plan: &Plan,
    instance: &Instance,
    shaders: &mut Shaders,
) -> Result<(Vec<Prepared<'d>>, Needs), AshError> {
    let g = &plan.graph;
    let mut out = Vec::new();
    let mut needs = Needs::default();
    for &p in &plan.order {
        let pass = &g.passes[p];
        let def = defs
            .definition(&pass.kind)
            .ok_or_else(|| AshError::NoDefinition {
                pass: pass.name.clone(),
                kind: pass.kind.clone(),
            })?;
        let bindings = strandgraph_passes::bind::bind(def, g, p)?
            .into_iter()
            .map(|b| (b.name, g.physical(b.access.resource), b.access.usage))
            .collect();
        let params = def.gpu_params(&pass.params, &instance.quantities)?;
        let entry = def.entry(&pass.params)?;
        let file = def.shader().file;
        let composed = shaders
            .compose(file)
            .map_err(|e| AshError::Shader(format!("pass `{}`: {e}", pass.name)))?;
        for cap in CAPABILITIES {
            if composed.needs.contains(cap) {
                needs
                    .caps
                    .push((cap, pass.name.clone(), format!("{file} uses {cap:?}")));
            }
        }
        let raster = def.raster(&pass.params, &instance.quantities)?;
        if def.shader().fragment.is_some() && raster.is_none() {
            return Err(AshError::Pass {
                pass: pass.name.clone(),
                message: format!(
                    "kind `{}` has a fragment entry but declares no raster state (PassDef::raster)",
                    def.kind()
                ),
            });
        }
        let prep = Prepared {
            p,
            def,
            bindings,
            params,
            entry,
            composed,
            raster,
        };
        if prep.is_raster() && needs.raster.is_none() {
            needs.raster = Some(pass.name.clone());
        }
        let stores = pass
            .accesses
            .iter()
            .any(|a| a.usage == Usage::Storage && a.mode != AccessMode::Read);
        if prep.is_raster() && stores && needs.fragment_stores.is_none() {
            needs.fragment_stores = Some(pass.name.clone());
        }
        out.push(prep);
    }
    Ok((out, needs))
}
