//! The report page: one self-contained HTML file (inline CSS, script and
//! SVG; pictures by relative path) that opens from disk with no server.

use super::charts;
use super::data::{Bench, Cell, CropNote, Reference, Section, sections};
use super::figures::{self, fronts};
use miette::Result;
use std::fmt::Write as _;

const CSS: &str = include_str!("page.css");
const JS: &str = include_str!("page.js");
/// Runs first, so errors of anything after it are recorded for the check.
const ERRORS_JS: &str = r#"window.reportErrors = [];
window.addEventListener("error", (e) => window.reportErrors.push(e.message || ("failed to load " + ((e.target && (e.target.src || e.target.href)) || "?"))), true);
window.addEventListener("unhandledrejection", (e) => window.reportErrors.push(String(e.reason)));
(() => { const ce = console.error; console.error = (...a) => { window.reportErrors.push(a.join(" ")); ce.apply(console, a); }; })();"#;

/// What the page holds, for its self-check.
#[derive(Default)]
pub(super) struct Counts {
    pub images: usize,
    pub charts: usize,
}

pub fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            _ => o.push(c),
        }
    }
    o
}

/// Milliseconds to two decimals (one past 100).
fn ms(x: f64) -> String {
    if x >= 100.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.2}")
    }
}

/// Mean FLIP to five decimals: rows of one pipeline often differ in
/// the fourth.
fn flip(x: f64) -> String {
    format!("{x:.5}")
}

/// The whole page for `b`; `source` names the bench.json it came from.
pub fn page(b: &Bench, source: &str) -> Result<String> {
    let secs = sections(b);
    let mut counts = Counts::default();
    let mut body = String::new();
    for s in &secs {
        body.push_str(&section(s, &mut counts)?);
    }
    let mut o = String::new();
    let _ = write!(
        o,
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <meta name=\"color-scheme\" content=\"dark\">\
         <title>strandgraph report: {}</title>\n<script>{ERRORS_JS}</script>\n<style>{CSS}</style></head>\n\
         <body data-expect-images=\"{}\" data-expect-charts=\"{}\">\n",
        esc(&b.size),
        counts.images,
        counts.charts
    );
    o.push_str(&header(b, &secs, source));
    let _ = write!(o, "<main>{body}</main>\n{}", footer(b));
    let _ = write!(o, "<script>{JS}</script>\n</body></html>\n");
    Ok(o)
}

fn header(b: &Bench, secs: &[Section<'_>], source: &str) -> String {
    let mut o = String::from(
        "<header class=\"top\"><h1>strandgraph report <span>time against quality</span></h1>",
    );
    let mut took = b
        .elapsed_s
        .map_or(String::new(), |t| format!(" · bench took {t:.0} s"));
    if let Some(q) = b.jpeg_quality {
        let _ = write!(
            took,
            " · pictures as JPEG of quality {q} (FLIP is of the lossless frames)"
        );
    }
    if b.partial {
        took.push_str(" · <strong>partial run</strong>: the bench stopped before its last row");
    }
    let _ = write!(
        o,
        "<p class=\"meta\">{} · {} timed frame{} after {} warm-up{took} · from <a href=\"{src}\">{src}</a></p>",
        esc(&b.size),
        b.frames,
        if b.frames == 1 { "" } else { "s" },
        b.warmup,
        src = esc(source)
    );
    o.push_str("<table class=\"devices\">");
    for d in &b.devices {
        let _ = write!(
            o,
            "<tr><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&d.backend),
            esc(&d.device),
            esc(&d.clock)
        );
    }
    o.push_str("</table><nav class=\"toc\">");
    for s in secs {
        let _ = write!(
            o,
            "<a href=\"#{}\">{} · {}</a>",
            s.id(),
            esc(s.view),
            esc(s.backend)
        );
    }
    o.push_str(
        "</nav><p class=\"howto\">Click a row or a picture to show it large; click the large picture \
         (or press space) to flip between the row and its pipeline's reference; hover a picture for \
         its FLIP error map (magma: black is no error, yellow the largest). FLIP is the mean over the \
         last timed frame against the row's reference (pipelines may share one), both through ACES at \
         0 EV; ◆ marks the rows on their own reference's time-versus-FLIP Pareto frontier.</p></header>\n",
    );
    o
}

fn footer(b: &Bench) -> String {
    let mut o = String::from("<footer>");
    if !b.notes.is_empty() {
        o.push_str("Notes of the run:<ul>");
        for n in &b.notes {
            let _ = write!(o, "<li>{}</li>", esc(n));
        }
        o.push_str("</ul>");
    }
    o.push_str("Made by <code>strandgraph report</code>; every picture is a file under <code>pictures/</code> next to this page.</footer>\n");
    o
}

/// Pipelines of the section's cells, in order (their colour index).
fn pipelines<'a>(s: &Section<'a>) -> Vec<&'a str> {
    let mut out: Vec<&str> = Vec::new();
    for c in &s.cells {
        if !out.contains(&c.pipeline.as_str()) {
            out.push(c.pipeline.as_str());
        }
    }
    out
}

fn section(s: &Section<'_>, counts: &mut Counts) -> Result<String> {
    let mut o = String::new();
    let device = s
        .device
        .map_or(String::new(), |d| format!(" — {}", esc(&d.device)));
    let _ = write!(
        o,
        "<section class=\"view\" id=\"{}\"><h2>{}<span class=\"where\">{}{device}</span></h2>\
         <p class=\"scene\">{}</p>",
        s.id(),
        esc(s.view),
        esc(s.backend),
        esc(s.scene)
    );
    let pipes = pipelines(s);
    let refs = s.references();
    let fronts = fronts(s, &refs);
    o.push_str("<div class=\"grid\"><div>");
    o.push_str(&viewer(s, counts));
    o.push_str("</div><div>");
    o.push_str(&figures::pareto(s, &pipes, &refs, &fronts, counts)?);
    o.push_str("</div></div>");
    o.push_str(&table(s, &pipes, &fronts));
    o.push_str(&thumbs(s, &refs, counts));
    o.push_str(&figures::bars(s, &pipes, counts)?);
    o.push_str("</section>\n");
    Ok(o)
}

/// The large picture: the first row with a reference, else the first
/// measured row; the script swaps what it shows.
fn viewer(s: &Section<'_>, counts: &mut Counts) -> String {
    let shown = |c: &Cell| c.measured() && c.picture.is_some();
    let first = s
        .cells
        .iter()
        .position(|c| shown(c) && c.reference_picture.is_some())
        .or_else(|| s.cells.iter().position(|c| shown(c)));
    let Some(i) = first else {
        return "<p class=\"nochart\">Every row was skipped here.</p>".into();
    };
    let pic = esc(s.cells[i].picture.as_deref().unwrap_or_default());
    counts.images += 1;
    let (class, link) = match s.crop {
        Some(_) => (" crop", "open"),
        None => ("", "full size"),
    };
    format!(
        "<div class=\"viewer{class}\" data-row=\"{i}\"><div class=\"frame\" title=\"click to flip between the row and its reference\">\
         <img class=\"big\" src=\"{pic}\" alt=\"selected picture\"></div><div class=\"bar\"><span class=\"what\"></span>\
         <button data-mode=\"row\">row</button><button data-mode=\"ref\">reference</button>\
         <button data-mode=\"map\">FLIP map</button><a class=\"full\" href=\"{pic}\">{link}</a></div></div>{}",
        s.crop.map_or(String::new(), crop_note)
    )
}

/// What a cropped view's pictures are, said next to its viewer.
fn crop_note(c: &CropNote) -> String {
    format!(
        "<p class=\"crop-note\">1:1 crop {}x{} at ({}, {}) of the {}x{} frame; \
         FLIP is over the whole frame, coverage error over its pixels with hair.</p>",
        c.width, c.height, c.x, c.y, c.frame_width, c.frame_height
    )
}

/// plotters' SVG as an inline element (its XML prologue, if any, dropped).
pub(super) fn inline_svg(svg: &str) -> &str {
    svg.find("<svg").map_or(svg, |i| &svg[i..])
}

fn table(s: &Section<'_>, pipes: &[&str], fronts: &[Option<bool>]) -> String {
    let best = |f: fn(&Cell) -> Option<f64>| {
        s.cells
            .iter()
            .filter_map(|c| f(c))
            .fold(f64::INFINITY, f64::min)
    };
    let (best_ms, best_flip) = (best(Cell::ms), best(|c| c.flip));
    // Animated scenes add their flicker (compare::Temporal).
    let temporal = s.cells.iter().any(|c| c.flicker.is_some());
    let best_flicker = best(|c| c.flicker);
    let mut o = format!(
        "<table class=\"rows\"><thead><tr><th>row</th><th>frame ms</th><th>min–max</th>\
         <th>raster ms</th><th>FLIP</th><th>coverage err.</th>{}<th title=\"on the Pareto frontier of the rows judged against the same reference\">◆</th></tr></thead><tbody>",
        if temporal {
            "<th title=\"mean |frame-to-frame luma change − the reference's|\">flicker</th>"
        } else {
            ""
        }
    );
    for (i, c) in s.cells.iter().enumerate() {
        let colour = charts::pipeline_css(pipes.iter().position(|p| *p == c.pipeline).unwrap_or(0));
        let label = format!(
            "<td><span class=\"dot\" style=\"background:{colour}\"></span>{}</td>",
            esc(&c.label())
        );
        if let Some(why) = &c.skipped {
            let _ = write!(
                o,
                "<tr>{label}<td class=\"skip\" colspan=\"{}\">skipped: {}</td></tr>",
                6 + usize::from(temporal),
                esc(why)
            );
            continue;
        }
        let num = |x: Option<f64>, fmt: fn(f64) -> String, best: f64| match x {
            Some(v) if v == best => format!("<td class=\"num best\">{}</td>", fmt(v)),
            Some(v) => format!("<td class=\"num\">{}</td>", fmt(v)),
            None => "<td class=\"na\">—</td>".into(),
        };
        let spread = c.frame.as_ref().and_then(|f| Some((f.min_ms?, f.max_ms?)));
        let raster = c.raster.as_ref().and_then(|r| r.median_ms);
        let _ = write!(
            o,
            "<tr data-row=\"{i}\">{label}{}{}{}{}{}{}<td class=\"front\">{}</td></tr>",
            num(c.ms(), ms, best_ms),
            spread.map_or("<td class=\"na\">—</td>".into(), |(a, b)| format!(
                "<td class=\"num\">{}–{}</td>",
                ms(a),
                ms(b)
            )),
            num(raster, ms, f64::NAN),
            flip_cell(num(c.flip, flip, best_flip), &c.flip_frames),
            num(c.coverage_error, |f| format!("{f:.4}"), f64::NAN),
            if temporal {
                num(c.flicker, flip, best_flicker)
            } else {
                String::new()
            },
            if fronts[i] == Some(true) { "◆" } else { "" }
        );
    }
    o.push_str("</tbody></table>");
    o
}

/// `cell` (a FLIP) with an animated scene's per-frame values on hover.
fn flip_cell(cell: String, frames: &[f64]) -> String {
    if frames.len() < 2 {
        return cell;
    }
    let each: Vec<String> = frames.iter().map(|&f| flip(f)).collect();
    let title = format!(
        " title=\"mean of {} frames: {}\"",
        frames.len(),
        each.join(" ")
    );
    cell.replacen("<td", &format!("<td{title}"), 1)
}

/// Each distinct reference once (pipelines sharing a reference graph
/// share its picture), named by its graph and the pipelines judged
/// against it.
fn reference_thumbs(refs: &[Reference<'_>], counts: &mut Counts) -> String {
    let mut o = String::new();
    for (k, r) in refs.iter().enumerate() {
        let Some(path) = r.picture else {
            continue;
        };
        counts.images += 1;
        let _ = write!(
            o,
            "<figure class=\"thumb reference\" data-row=\"ref{k}\" data-pic=\"{p}\" data-label=\"{label}\">\
             <div class=\"stack\"><img src=\"{p}\" alt=\"reference {label}\"></div>\
             <figcaption><span class=\"name\">reference · {label}</span><span class=\"num\">ground truth</span></figcaption></figure>",
            p = esc(path),
            label = esc(&r.label())
        );
    }
    o
}

/// The references first, then every measured row; each picture with its
/// FLIP map stacked over it (shown on hover).
fn thumbs(s: &Section<'_>, refs: &[Reference<'_>], counts: &mut Counts) -> String {
    let mut o = String::from("<div class=\"thumbs\">");
    o.push_str(&reference_thumbs(refs, counts));
    for (i, c) in s.cells.iter().enumerate() {
        let Some(pic) = c.picture.as_ref().filter(|_| c.measured()) else {
            continue;
        };
        counts.images += 1;
        let label = esc(&c.label());
        let mut attrs = format!(
            "data-row=\"{i}\" data-pic=\"{}\" data-label=\"{label}\"",
            esc(pic)
        );
        let mut map = String::new();
        if let Some((m, r)) = c.map_and_reference() {
            counts.images += 1;
            let _ = write!(attrs, " data-map=\"{}\" data-ref=\"{}\"", esc(m), esc(r));
            map = format!(
                "<img class=\"map\" src=\"{}\" alt=\"FLIP error map of {label}\">",
                esc(m)
            );
        }
        let time = c.ms().map_or(String::new(), |t| format!("{} ms · ", ms(t)));
        let num = c.flip.map_or(format!("{time}no reference"), |f| {
            format!("{time}FLIP {}", flip(f))
        });
        let _ = write!(
            o,
            "<figure class=\"thumb\" {attrs}><div class=\"stack\"><img src=\"{}\" alt=\"{label}\">{map}</div>\
             <figcaption><span class=\"name\" title=\"{label}\">{label}</span><span class=\"num\">{num}</span></figcaption></figure>",
            esc(pic)
        );
    }
    o.push_str("</div>");
    o
}
