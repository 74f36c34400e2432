//! Binding each pass, filling its parameter block and composing its shader.

use super::*;

/// Looks up every live pass's definition, binds it, fills its parameter block
/// and composes its shader; `loop_counters` says whether its module gets
/// naga's loop counters.
pub(crate) fn prepare<'d>(
    defs: &'d dyn Definitions,
    plan: &Plan,
    instance: &Instance,
    shaders: &mut Shaders,
    loop_counters: LoopCounters,
) -> Result<Vec<Prepared<'d>>, WgpuError> {
    let g = &plan.graph;
    let mut out = Vec::new();
    for &p in &plan.order {
        let pass = &g.passes[p];
        let def = defs
            .definition(&pass.kind)
            .ok_or_else(|| WgpuError::NoDefinition {
                pass: pass.name.clone(),
                kind: pass.kind.clone(),
            })?;
        let chosen: Vec<(String, usize, Usage)> = strandgraph_passes::bind::bind(def, g, p)?
            .into_iter()
            .map(|b| (b.name, b.access.resource, b.access.usage))
            .collect();
        let attachments = chosen
            .iter()
            .enumerate()
            .filter(|(_, (_, _, u))| matches!(u, Usage::Color | Usage::Depth))
            .map(|(i, (_, _, u))| (i, *u))
            .collect();
        let bindings = chosen
            .into_iter()
            .map(|(n, r, _)| (n, g.physical(r)))
            .collect();
        let raster = def.raster(&pass.params, &instance.quantities)?;
        if def.shader().fragment.is_some() != raster.is_some() {
            return Err(WgpuError::Pass {
                pass: pass.name.clone(),
                message: format!(
                    "`{}` has a fragment entry but no draw state (PassDef::raster), or the reverse",
                    def.kind()
                ),
            });
        }
        let params = def.gpu_params(&pass.params, &instance.quantities)?;
        let entry = def.entry(&pass.params)?;
        let file = def.shader().file;
        let composed = shaders
            .compose(file)
            .map_err(|e| WgpuError::Shader(format!("pass `{}`: {e}", pass.name)))?;
        out.push(Prepared {
            p,
            def,
            bindings,
            attachments,
            params,
            entry,
            composed,
            raster,
            loop_bounding: loop_counters.for_pass(g.passes[p].loop_bounding),
        });
    }
    Ok(out)
}
