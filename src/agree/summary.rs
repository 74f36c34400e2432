//! Markdown summaries of `strandgraph agree --json` files, for README: one
//! table per file, a row per output that differs from the CPU's on any
//! backend, and a count of the outputs bit-identical everywhere.

use serde_json::Value;
use std::collections::BTreeMap;
use std::fmt::Write;

/// One file's table, titled `title`. `checks` is the file's JSON (a list of
/// [`super::PassCheck`]).
pub fn markdown(title: &str, checks: &Value) -> Result<String, String> {
    let checks = checks
        .as_array()
        .ok_or("not a list of pass checks (strandgraph agree --json)")?;
    // (pass, output) → backend → (identical %, passed, rule)
    let mut rows: BTreeMap<(usize, String, String, String), BTreeMap<String, Cell>> =
        BTreeMap::new();
    let mut order: Vec<String> = Vec::new();
    let mut backends: Vec<String> = Vec::new();
    for (i, c) in checks.iter().enumerate() {
        let field = |v: &Value, k: &str| {
            v[k].as_str()
                .map(str::to_string)
                .ok_or(format!("check {i}: no `{k}`"))
        };
        let (pass, kind, backend) = (field(c, "pass")?, field(c, "kind")?, field(c, "backend")?);
        if !order.contains(&pass) {
            order.push(pass.clone());
        }
        if !backends.contains(&backend) {
            backends.push(backend.clone());
        }
        let at = order.iter().position(|p| *p == pass).unwrap_or(0);
        for o in c["outputs"]
            .as_array()
            .ok_or(format!("check {i}: no outputs"))?
        {
            let r = &o["outcome"];
            let n = |k: &str| r[k].as_f64().ok_or(format!("check {i}: no `{k}`"));
            let (words, differing) = (n("words")?, n("differing")?);
            let cell = Cell {
                identical: 100.0 * (words - differing) / words.max(1.0),
                passed: n("failing")? <= n("allowed")?,
                rule: rule_text(&o["judgement"]["rule"]),
            };
            rows.entry((at, pass.clone(), kind.clone(), field(o, "binding")?))
                .or_default()
                .insert(backend.clone(), cell);
        }
    }
    let mut md = format!("**{title}**\n\n| pass | kind | output |");
    for b in &backends {
        let _ = write!(md, " {b} identical | {b} rule |");
    }
    md.push_str("\n|---|---|---|");
    md.push_str(&"---:|---|".repeat(backends.len()));
    md.push('\n');
    let mut same = 0;
    for ((_, pass, kind, output), cells) in &rows {
        if cells.values().all(|c| c.identical >= 100.0) {
            same += 1;
            continue;
        }
        let _ = write!(md, "| {pass} | `{kind}` | {output} |");
        for b in &backends {
            match cells.get(b) {
                Some(c) => {
                    let verdict = if c.passed { "ok" } else { "**outside**" };
                    // Rounded down, so one differing word never reads 100.000%.
                    let shown = (c.identical * 1000.0).floor() / 1000.0;
                    let _ = write!(md, " {shown:.3}% | {} {verdict} |", c.rule);
                }
                None => md.push_str(" – | – |"),
            }
        }
        md.push('\n');
    }
    let _ = writeln!(
        md,
        "\n{same} more outputs are bit-identical to the CPU's on {}.",
        backends.join(" and ")
    );
    Ok(md)
}

struct Cell {
    identical: f64,
    passed: bool,
    rule: String,
}

/// `{"F32": {"ulps": 4, "abs": 1e-6}}` → `F32 ≤ 4 ULP`; `"Exact"` → `exact`.
fn rule_text(rule: &Value) -> String {
    if let Some(s) = rule.as_str() {
        return s.to_lowercase();
    }
    let Some((name, v)) = rule.as_object().and_then(|m| m.iter().next()) else {
        return rule.to_string();
    };
    let num = |k: &str| v[k].as_f64().unwrap_or(0.0);
    match name.as_str() {
        "F32" => format!("f32 ≤ {} ULP", num("ulps")),
        "F16" => format!("f16 ≤ {} ULP", num("ulps")),
        "Unorm8" => format!("unorm8 ≤ {}", num("steps")),
        "Unorm16" => format!("unorm16 ≤ {}", num("steps")),
        "Near" => format!("± {}", num("max")),
        other => other.to_lowercase(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_differing_outputs_and_counts_the_rest() {
        let json: Value = serde_json::from_str(
            r#"[{"pass":"raster","kind":"kulikov.raster","backend":"ash","outputs":[
                {"binding":"vis_atlas","judgement":{"rule":"Exact"},
                 "outcome":{"words":1000,"differing":1,"failing":1,"allowed":0}},
                {"binding":"coverage_atlas","judgement":{"rule":{"Near":{"max":8}}},
                 "outcome":{"words":10,"differing":0,"failing":0,"allowed":0}}]}]"#,
        )
        .unwrap();
        let md = markdown("H100", &json).unwrap();
        assert!(
            md.contains("| raster | `kulikov.raster` | vis_atlas | 99.900% | exact **outside** |"),
            "{md}"
        );
        assert!(!md.contains("coverage_atlas"), "{md}");
        assert!(md.contains("1 more outputs"), "{md}");
        assert!(markdown("x", &Value::Null).is_err());
    }
}
