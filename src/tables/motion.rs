//! `bench-motion FILE.json`: what simulation and motion cost and do, per
//! backend, a line per measured cell: the simulation passes' summed median
//! (every pass of a `sim.*` kind: the velocity grid's splat, the solver,
//! Lipp's write-back), the frame median, the mean FLIP against the
//! reference (over the timed frames of an animated scene), the flicker and
//! the reference's own frame-to-frame change it is measured against
//! (src/compare.rs: `Temporal`).

use super::bench::{caption, cells, devices, label};
use serde_json::Value;
use std::fmt::Write;

/// Summed median of the passes whose kind starts with `sim.`; `None` when
/// the cell has none.
fn simulation_ms(cell: &Value) -> Option<f64> {
    let sims: Vec<f64> = cell["passes"]
        .as_array()?
        .iter()
        .filter(|p| p["kind"].as_str().is_some_and(|k| k.starts_with("sim.")))
        .filter_map(|p| p["median_ms"].as_f64())
        .collect();
    (!sims.is_empty()).then(|| sims.iter().sum())
}

fn number(v: Option<f64>, text: impl Fn(f64) -> String) -> String {
    v.map_or("–".into(), text)
}

pub fn table(json: &Value) -> Result<String, String> {
    let mut md = String::new();
    for (backend, device) in devices(json)? {
        let measured: Vec<&Value> = cells(json, &backend)
            .filter(|c| c["frame"]["median_ms"].is_number())
            .collect();
        if measured.is_empty() {
            continue;
        }
        let _ = writeln!(md, "{}; ms, medians:\n", caption(json, &backend, &device));
        md.push_str(
            "| scene | variant | simulation ms | frame ms | FLIP | flicker | reference motion |\n",
        );
        md.push_str("|---|---|---:|---:|---:|---:|---:|\n");
        for c in measured {
            let flip = |key: &str| number(c[key].as_f64(), crate::compare::flip_text);
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} |",
                c["view"].as_str().unwrap_or("?"),
                label(c),
                number(simulation_ms(c), |v| format!("{v:.3}")),
                number(c["frame"]["median_ms"].as_f64(), |v| format!("{v:.2}")),
                flip("flip"),
                flip("flicker"),
                flip("reference_motion"),
            );
        }
        md.push('\n');
    }
    if md.is_empty() {
        return Err("no measured cell".into());
    }
    Ok(md)
}

#[cfg(test)]
mod tests {
    #[test]
    fn sums_the_simulation_passes() {
        let json: serde_json::Value = serde_json::from_str(
            r#"{"devices":[{"backend":"ash","device":"GPU"}],"size":"1280x720","frames":10,"warmup":2,
            "cells":[{"backend":"ash","pipeline":"Kulikov","variant":"v","view":"animated",
            "frame":{"median_ms":1.5},"flip":0.1,"flicker":0.004,"reference_motion":0.005,
            "passes":[{"pass":"splat","kind":"sim.splat","median_ms":0.01},
                      {"pass":"simulate","kind":"sim.pbd","median_ms":0.125},
                      {"pass":"raster","kind":"kulikov.raster","median_ms":0.5}]}]}"#,
        )
        .unwrap();
        let md = super::table(&json).unwrap();
        assert!(
            md.contains("| animated | Kulikov: v | 0.135 | 1.50 | 0.100 | 0.00400 | 0.00500 |"),
            "{md}"
        );
    }
}
