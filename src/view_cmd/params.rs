//! Every parameter of a slot's graph as a widget: the pass kind's defaults
//! ([`PassDef::param_defaults`]) overlaid with what the graph file and the
//! overrides set. An edit becomes a `--param PASS.PARAM=VALUE` override and
//! reopens the slot, so it is checked exactly as the command line's is.
//! Switches are check boxes, numbers drag values, named switches
//! (`"Baked"`) combo boxes of the names the kind accepts.

use super::app::Viewer;
use std::collections::BTreeSet;
use strandgraph_graph::base_name;
use strandgraph_passes::params::choices;
use strandgraph_passes::{Definitions, Registry};

/// The parameter widgets of slot `i` (0: A, 1: B).
pub fn show(v: &mut Viewer, i: usize, ui: &mut egui::Ui) {
    let Some(slot) = (if i == 0 { &v.a } else { &v.b }) else {
        return;
    };
    let g = &slot.plan.graph;
    let mut seen = BTreeSet::new();
    let mut edit = None;
    for &p in &slot.plan.order {
        let pass = &g.passes[p];
        let base = base_name(&pass.name).to_string();
        let Some(def) = Registry.definition(&pass.kind) else {
            continue;
        };
        let ron::Value::Map(defaults) = def.param_defaults() else {
            continue;
        };
        if defaults.is_empty() || !seen.insert(base.clone()) {
            continue;
        }
        let header = format!("{base}  ·  {}", pass.kind);
        egui::CollapsingHeader::new(header)
            .id_salt((i, &base))
            .show(ui, |ui| {
                ui.label(egui::RichText::new(def.summary()).small().weak());
                for (key, default) in defaults.iter() {
                    let ron::Value::String(key) = key else {
                        continue;
                    };
                    if key == strandgraph_graph::unroll::MODEL_INDEX {
                        continue;
                    }
                    let current = match &pass.params {
                        ron::Value::Map(m) => m.get(&ron::Value::String(key.clone())),
                        _ => None,
                    };
                    let value = current.unwrap_or(default);
                    let names = matches!(value, ron::Value::String(_))
                        .then(|| choices(def, key))
                        .flatten();
                    if let Some(new) = widget(ui, (i, &base, key), key, value, names) {
                        edit = Some(format!("{base}.{key}={new}"));
                    }
                }
            });
    }
    if let Some(spec) = edit {
        let overrides = with_override(&slot.overrides, spec);
        v.pending.push((i, slot.graph.clone(), overrides));
    }
}

/// `overrides` with `spec` (`PASS.PARAM=VALUE`) in place of any earlier
/// override of the same parameter.
fn with_override(overrides: &[String], spec: String) -> Vec<String> {
    let target = |o: &str| o.split_once('=').map(|(k, _)| k.trim().to_string());
    let mut kept: Vec<String> = overrides
        .iter()
        .filter(|o| target(o) != target(&spec))
        .cloned()
        .collect();
    kept.push(spec);
    kept
}

/// One parameter's widget; the new value in RON when the user changed it.
fn widget(
    ui: &mut egui::Ui,
    id: impl std::hash::Hash + std::fmt::Debug,
    key: &str,
    value: &ron::Value,
    choices: Option<Vec<String>>,
) -> Option<String> {
    ui.horizontal(|ui| match value {
        ron::Value::Bool(b) => {
            let mut b = *b;
            ui.checkbox(&mut b, key).changed().then(|| b.to_string())
        }
        ron::Value::Number(n) => {
            ui.label(key);
            if is_float(n) {
                let mut x = n.into_f64();
                let speed = 0.01 * x.abs().max(0.01);
                let changed = ui.add(egui::DragValue::new(&mut x).speed(speed)).changed();
                changed.then(|| format!("{x:?}"))
            } else {
                let mut x = n.into_f64() as i64;
                let changed = ui.add(egui::DragValue::new(&mut x).speed(0.2)).changed();
                changed.then(|| x.to_string())
            }
        }
        ron::Value::String(s) => {
            ui.label(key);
            let names = choices.unwrap_or_default();
            let mut picked = None;
            egui::ComboBox::from_id_salt(id)
                .selected_text(s.as_str())
                .show_ui(ui, |ui| {
                    for name in &names {
                        if ui.selectable_label(name == s, name.as_str()).clicked() && name != s {
                            picked = Some(format!("{name:?}"));
                        }
                    }
                });
            picked
        }
        other => {
            ui.label(format!(
                "{key}: {}",
                ron::to_string(other).unwrap_or_default()
            ));
            None
        }
    })
    .inner
}

fn is_float(n: &ron::Number) -> bool {
    matches!(n, ron::Number::F32(_) | ron::Number::F64(_))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_edit_replaces_the_override_of_its_parameter_only() {
        let start = vec![
            "raster.loop_flattening=false".to_string(),
            "shade.exposure=1.0".to_string(),
            "raster.loop_flattening_x=1".to_string(),
        ];
        let after = with_override(&start, "raster.loop_flattening=true".into());
        assert_eq!(
            after,
            [
                "shade.exposure=1.0",
                "raster.loop_flattening_x=1",
                "raster.loop_flattening=true"
            ]
        );
    }
}
