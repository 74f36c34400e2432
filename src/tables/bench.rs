//! Markdown tables from `strandgraph bench --out DIR`'s `bench.json`.

use serde_json::Value;
use std::fmt::Write;

/// The cells of one backend, in the file's order.
pub(super) fn cells<'a>(json: &'a Value, backend: &'a str) -> impl Iterator<Item = &'a Value> + 'a {
    json["cells"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(move |c| c["backend"] == backend)
}

pub(super) fn label(cell: &Value) -> String {
    format!(
        "{}: {}",
        cell["pipeline"].as_str().unwrap_or("?"),
        cell["variant"].as_str().unwrap_or("?")
    )
}

fn view_of(cell: &Value) -> String {
    cell["view"].as_str().unwrap_or("?").to_string()
}

/// The (pass, kind) pairs of `cells`, in the order they first appear.
fn passes_of<'a>(cells: impl Iterator<Item = &'a Value>) -> Vec<(String, String)> {
    distinct(
        cells.flat_map(|c| c["passes"].as_array().into_iter().flatten()),
        |p| {
            (
                p["pass"].as_str().unwrap_or("?").to_string(),
                p["kind"].as_str().unwrap_or("?").to_string(),
            )
        },
    )
}

/// Distinct values of `f` over `items`, first occurrence first.
fn distinct<'a, T: PartialEq>(
    items: impl Iterator<Item = &'a Value>,
    f: impl Fn(&Value) -> T,
) -> Vec<T> {
    let mut out = Vec::new();
    for i in items {
        let v = f(i);
        if !out.contains(&v) {
            out.push(v);
        }
    }
    out
}

pub(super) fn devices(json: &Value) -> Result<Vec<(String, String)>, String> {
    let list = json["devices"]
        .as_array()
        .ok_or("no `devices` (not a bench.json)")?;
    Ok(list
        .iter()
        .filter_map(|d| {
            Some((
                d["backend"].as_str()?.to_string(),
                d["device"].as_str()?.to_string(),
            ))
        })
        .collect())
}

/// What the run was, for a table's caption.
pub(super) fn caption(json: &Value, backend: &str, device: &str) -> String {
    format!(
        "{device}, {backend}, {}, {} timed frames after {} warm-up",
        json["size"].as_str().unwrap_or("?"),
        json["frames"],
        json["warmup"]
    )
}

/// A row per label of `rows`, a column per view; each cell `text` of the
/// backend's cell of that row and view ("–" where there is none).
fn grid<'a>(
    md: &mut String,
    cells: impl Fn() -> Box<dyn Iterator<Item = &'a Value> + 'a>,
    rows: &[String],
    views: &[String],
    text: impl Fn(&Value) -> String,
) {
    let _ = writeln!(md, "| variant | {} |", views.join(" | "));
    let _ = writeln!(md, "|---|{}", "---:|".repeat(views.len()));
    for row in rows {
        let _ = write!(md, "| {row} |");
        for view in views {
            let cell = cells().find(|c| label(c) == *row && c["view"] == view.as_str());
            let _ = write!(md, " {} |", cell.map_or("–".into(), &text));
        }
        md.push('\n');
    }
}

/// Per backend: a row per pipeline variant, a column per view; each cell the
/// median frame time with the raster passes' median and their atomics as a
/// fraction of the same run's atomicMin roofline (Lipp's Table 1 shape).
pub fn frame_table(json: &Value) -> Result<String, String> {
    let mut md = String::new();
    for (backend, device) in devices(json)? {
        let views = distinct(cells(json, &backend), view_of);
        let rows = distinct(cells(json, &backend), label);
        let table = |md: &mut String, what: &str, text: &dyn Fn(&Value) -> String| {
            let _ = writeln!(md, "{}; ms: {what}:\n", caption(json, &backend, &device));
            grid(md, || Box::new(cells(json, &backend)), &rows, &views, text);
        };
        table(
            &mut md,
            "median frame (raster median; raster atomics as % of the atomicMin roofline)",
            &cell_text,
        );
        md.push_str(&roofline_line(json, &backend));
        if cells(json, &backend).any(|c| c["frame_bounds"].is_object()) {
            md.push('\n');
            table(
                &mut md,
                "median frame timed only at its bounds (the same frames run again with no timestamp between passes; per-pass timestamps make a queue's passes wait for each other)",
                &|c| match c["frame_bounds"]["median_ms"].as_f64() {
                    Some(ms) => format!("{ms:.3}"),
                    None => "–".into(),
                },
            );
        }
    }
    Ok(md)
}

/// Per backend and reference: a row per variant measured against it, a
/// column per view; each cell the mean FLIP, the coverage error where
/// measured, and the frame median.
pub fn flip_table(json: &Value) -> Result<String, String> {
    let mut md = String::new();
    for (backend, device) in devices(json)? {
        let measured = || cells(json, &backend).filter(|c| c["flip"].is_number());
        let references = distinct(measured(), |c| {
            c["flip_reference"].as_str().unwrap_or("?").to_string()
        });
        let views = distinct(cells(json, &backend), view_of);
        for reference in &references {
            let with = || {
                measured().filter(move |c| c["flip_reference"].as_str().unwrap_or("?") == reference)
            };
            let rows = distinct(with(), label);
            let _ = writeln!(
                md,
                "{}; mean FLIP against `{reference}` (ACES, 0 EV; 0 is identical) / coverage error (mean \\|α − α<sub>ref</sub>\\| over the pixels with hair in either), then the median frame in ms:\n",
                caption(json, &backend, &device)
            );
            grid(
                &mut md,
                || Box::new(with()),
                &rows,
                &views,
                |c| {
                    let text =
                        |key: &str| crate::compare::flip_text(c[key].as_f64().unwrap_or(f64::NAN));
                    let coverage = if c["coverage_error"].is_number() {
                        format!(" / {}", text("coverage_error"))
                    } else {
                        String::new()
                    };
                    format!(
                        "{}{coverage} ({:.2})",
                        text("flip"),
                        c["frame"]["median_ms"].as_f64().unwrap_or(f64::NAN)
                    )
                },
            );
            md.push('\n');
        }
    }
    if md.is_empty() {
        return Err("no cell has a `flip` (a bench run before the reference)".into());
    }
    Ok(md)
}

fn cell_text(c: &Value) -> String {
    if c.get("skipped").is_some() {
        return "skipped".into();
    }
    let ms = |k: &str| c[k]["median_ms"].as_f64().unwrap_or(f64::NAN);
    match c["fraction_of_ceiling"].as_f64() {
        Some(f) => format!(
            "{:.2} ({:.2}; {:.0}%)",
            ms("frame"),
            ms("raster"),
            100.0 * f
        ),
        None => format!("{:.2} ({:.2})", ms("frame"), ms("raster")),
    }
}

fn roofline_line(json: &Value, backend: &str) -> String {
    let Some(r) = json["roofline"]
        .as_array()
        .and_then(|l| l.iter().find(|r| r["backend"] == backend))
    else {
        return String::new();
    };
    let g = |k: &str, f: &str| {
        r[k][f].as_f64().map_or("–".into(), |x| {
            if x >= 1e9 {
                format!("{:.1} G", x / 1e9)
            } else {
                format!("{:.0} M", x / 1e6)
            }
        })
    };
    let mut line = format!(
        "\nRoofline of the same run: {} atomicMin/s 32-bit, {} atomicMin/s 64-bit (random addresses), {}B/s copy",
        g("atomic_min32", "ops_per_s"),
        g("atomic_min64", "ops_per_s"),
        g("copy", "bytes_moved_per_s")
    );
    // Runs before the graphics roofline existed have none.
    if r["triangles"]["per_s"].is_number() {
        line.push_str(&format!(
            "; through the hardware rasterizer {} triangles/s (2x2-pixel pairs) and {} shaded fragments/s (full-screen layers)",
            g("triangles", "per_s"),
            g("fragments", "per_s")
        ));
    }
    line + ".\n\n"
}

/// One variant's per-pass medians on the file's first backend, a column
/// per view (only `only`'s views when it names any).
pub fn pass_table(json: &Value, variant: &str, only: &[String]) -> Result<String, String> {
    let mut md = String::new();
    if let Some((backend, device)) = devices(json)?.into_iter().next() {
        let mine: Vec<&Value> = cells(json, &backend)
            .filter(|c| label(c) == variant && c.get("skipped").is_none())
            .filter(|c| only.is_empty() || only.contains(&view_of(c)))
            .collect();
        if mine.is_empty() {
            return Err(format!(
                "no measured cell of `{variant}` on {backend} in {only:?}"
            ));
        }
        let views = distinct(mine.iter().copied(), view_of);
        let passes = passes_of(mine.iter().copied());
        let _ = writeln!(
            md,
            "{variant}, {}; ms, median per pass:\n",
            caption(json, &backend, &device)
        );
        let _ = writeln!(md, "| pass | kind | {} |", views.join(" | "));
        let _ = writeln!(md, "|---|---|{}", "---:|".repeat(views.len()));
        for (pass, kind) in &passes {
            let _ = write!(md, "| {pass} | `{kind}` |");
            for c in &mine {
                let ms = c["passes"]
                    .as_array()
                    .and_then(|l| l.iter().find(|p| p["pass"] == pass.as_str()))
                    .and_then(|p| p["median_ms"].as_f64());
                let _ = write!(md, " {} |", ms.map_or("–".into(), |m| format!("{m:.3}")));
            }
            md.push('\n');
        }
    }
    if md.is_empty() {
        return Err(format!("no measured cell of `{variant}`"));
    }
    Ok(md)
}

/// Per-pass medians of one variant and view in two runs side by side, with
/// the change: what an optimisation bought, pass by pass.
pub fn delta_table(
    before: &Value,
    after: &Value,
    variant: &str,
    view: &str,
) -> Result<String, String> {
    let cell = |json: &Value, which: &str| -> Result<(String, Value), String> {
        let (backend, device) = devices(json)?
            .into_iter()
            .next()
            .ok_or(format!("{which}: no device"))?;
        let c = cells(json, &backend)
            .find(|c| label(c) == variant && c["view"] == view && c.get("skipped").is_none())
            .ok_or(format!(
                "{which}: no measured cell of `{variant}` at `{view}`"
            ))?;
        Ok((format!("{device}, {backend}"), c.clone()))
    };
    let ((dev_a, a), (dev_b, b)) = (cell(before, "before")?, cell(after, "after")?);
    if dev_a != dev_b {
        return Err(format!(
            "before ran on {dev_a}, after on {dev_b}: not comparable"
        ));
    }
    let median = |c: &Value, pass: &str| {
        c["passes"]
            .as_array()
            .and_then(|l| l.iter().find(|p| p["pass"] == pass))
            .and_then(|p| p["median_ms"].as_f64())
    };
    // One row a pass: a pass whose kind changed names both.
    let mut passes: Vec<(String, String)> = Vec::new();
    for (p, k) in passes_of([&a, &b].into_iter()) {
        match passes.iter_mut().find(|(q, _)| *q == p) {
            Some((_, kinds)) => *kinds = format!("{kinds} → `{k}`"),
            None => passes.push((p, format!("`{k}`"))),
        }
    }
    let ms = |v: Option<f64>| v.map_or("–".into(), |m| format!("{m:.3}"));
    let mut md = format!(
        "{variant}, {view}, {dev_a}; ms, median per pass:\n\n| pass | kind | before | after | change |\n|---|---|---:|---:|---:|\n"
    );
    let frame = |c: &Value| c["frame"]["median_ms"].as_f64();
    let bounds = |c: &Value| c["frame_bounds"]["median_ms"].as_f64();
    let timed_at_bounds = [&a, &b].iter().any(|c| bounds(c).is_some());
    for (pass, kind, x, y) in passes
        .iter()
        .map(|(p, k)| (p.as_str(), k.clone(), median(&a, p), median(&b, p)))
        .chain([("**frame**", String::new(), frame(&a), frame(&b))])
        .chain(timed_at_bounds.then(|| {
            let label = "**frame, timed at its bounds**";
            (label, String::new(), bounds(&a), bounds(&b))
        }))
    {
        let change = match (x, y) {
            (Some(x), Some(y)) if x > 0.0 => format!("{:+.0}%", 100.0 * (y - x) / x),
            _ => "–".into(),
        };
        let _ = writeln!(md, "| {pass} | {kind} | {} | {} | {change} |", ms(x), ms(y));
    }
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Value {
        serde_json::from_str(
            r#"{"size":"1920x1080","frames":10,"warmup":2,
            "devices":[{"backend":"ash","device":"GPU"}],
            "roofline":[{"backend":"ash","atomic_min32":{"ops_per_s":5.0e10},
                         "atomic_min64":{"ops_per_s":6.0e10},"copy":{"bytes_moved_per_s":1.0e12}}],
            "cells":[
              {"backend":"ash","pipeline":"K","variant":"all","view":"close",
               "frame":{"median_ms":2.5},"raster":{"median_ms":1.25},"fraction_of_ceiling":0.4,
               "passes":[{"pass":"raster","kind":"k.raster","median_ms":1.25}]},
              {"backend":"ash","pipeline":"L","variant":"all","view":"close","skipped":"no meshes"}]}"#,
        )
        .unwrap()
    }

    #[test]
    fn frame_table_has_a_row_per_variant_and_the_roofline() {
        let md = frame_table(&sample()).unwrap();
        assert!(md.contains("| K: all | 2.50 (1.25; 40%) |"), "{md}");
        assert!(md.contains("| L: all | skipped |"), "{md}");
        assert!(md.contains("50.0 G atomicMin/s 32-bit"), "{md}");
        assert!(frame_table(&Value::Null).is_err());
    }

    #[test]
    fn delta_table_shows_both_runs_and_the_change() {
        let mut after = sample();
        after["cells"][0]["passes"][0]["median_ms"] = serde_json::json!(0.625);
        after["cells"][0]["frame"]["median_ms"] = serde_json::json!(1.875);
        let md = delta_table(&sample(), &after, "K: all", "close").unwrap();
        assert!(
            md.contains("| raster | `k.raster` | 1.250 | 0.625 | -50% |"),
            "{md}"
        );
        assert!(
            md.contains("| **frame** |  | 2.500 | 1.875 | -25% |"),
            "{md}"
        );
        let mut other = after.clone();
        other["devices"][0]["device"] = serde_json::json!("another GPU");
        assert!(delta_table(&sample(), &other, "K: all", "close").is_err());
        // A pass whose kind changed is one row naming both kinds.
        after["cells"][0]["passes"][0]["kind"] = serde_json::json!("k.raster2");
        let md = delta_table(&sample(), &after, "K: all", "close").unwrap();
        assert!(
            md.contains("| raster | `k.raster` → `k.raster2` | 1.250 | 0.625 | -50% |"),
            "{md}"
        );
        assert_eq!(md.matches("| raster |").count(), 1, "{md}");
    }

    #[test]
    fn frames_timed_at_their_bounds_get_a_table_and_a_delta_row() {
        let before = sample();
        let mut after = sample();
        assert!(
            !frame_table(&after)
                .unwrap()
                .contains("timed only at its bounds")
        );
        after["cells"][0]["frame_bounds"] = serde_json::json!({"median_ms": 2.25});
        let md = frame_table(&after).unwrap();
        assert!(md.contains("timed only at its bounds"), "{md}");
        assert!(md.contains("2.250"), "{md}");
        let label = label(&after["cells"][0]);
        let view = after["cells"][0]["view"].as_str().unwrap().to_string();
        let delta = delta_table(&before, &after, &label, &view).unwrap();
        assert!(
            delta.contains("| **frame, timed at its bounds** |  | – | 2.250 | – |"),
            "{delta}"
        );
    }

    #[test]
    fn pass_table_lists_one_variants_passes() {
        let md = pass_table(&sample(), "K: all", &[]).unwrap();
        assert!(md.contains("| raster | `k.raster` | 1.250 |"), "{md}");
        assert!(pass_table(&sample(), "L: all", &[]).is_err());
        // Named views only; a view with no cell is an error, not an empty table.
        let close = pass_table(&sample(), "K: all", &["close".to_string()]).unwrap();
        assert!(close.contains("| pass | kind | close |"), "{close}");
        assert!(pass_table(&sample(), "K: all", &["far".to_string()]).is_err());
    }
}
