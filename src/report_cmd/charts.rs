//! The report's charts, drawn with `plotters` into SVG strings that the
//! page inlines: time against FLIP with the Pareto frontier, and each
//! row's passes as stacked bars. Colours suit the page's dark background.

use miette::{Result, miette};
use plotters::coord::Shift;
use plotters::element::PathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

const TEXT: RGBColor = RGBColor(0xc9, 0xcc, 0xd1);
const AXIS: RGBColor = RGBColor(0x8b, 0x90, 0x99);
const GRID: RGBColor = RGBColor(0x2c, 0x2f, 0x34);
const FRONTIER: RGBColor = RGBColor(0xf2, 0xb8, 0x4b);
const OTHER: RGBColor = RGBColor(0x55, 0x5a, 0x61);
/// Point colours per pipeline (amber is the frontier's).
const PIPELINES: [RGBColor; 6] = [
    RGBColor(0x5f, 0xa8, 0xe8),
    RGBColor(0x6c, 0xc0, 0x8b),
    RGBColor(0xb3, 0x92, 0xf0),
    RGBColor(0xe8, 0x7f, 0xb0),
    RGBColor(0x4f, 0xc1, 0xc1),
    RGBColor(0xe1, 0x57, 0x59),
];
/// Pass colours (Tableau 10 and two more), distinct on dark grey.
const PASSES: [RGBColor; 12] = [
    RGBColor(0x4e, 0x79, 0xa7),
    RGBColor(0xf2, 0x8e, 0x2b),
    RGBColor(0xe1, 0x57, 0x59),
    RGBColor(0x76, 0xb7, 0xb2),
    RGBColor(0x59, 0xa1, 0x4f),
    RGBColor(0xed, 0xc9, 0x48),
    RGBColor(0xb0, 0x7a, 0xa1),
    RGBColor(0xff, 0x9d, 0xa7),
    RGBColor(0x9c, 0x75, 0x5f),
    RGBColor(0xba, 0xb0, 0xac),
    RGBColor(0xa0, 0xcb, 0xe8),
    RGBColor(0xd3, 0x72, 0x95),
];
/// Passes under this share of every row's sum go into "other passes".
const MINOR: f64 = 0.02;

/// `plotters`' errors as diagnostics naming the chart.
fn drawn<T, E: std::fmt::Display>(what: &str, r: Result<T, E>) -> Result<T> {
    r.map_err(|e| miette!("drawing the {what} chart: {e}"))
}

fn font(size: u32) -> TextStyle<'static> {
    ("sans-serif", size).into_font().color(&TEXT)
}

/// One row on the time-versus-FLIP chart.
pub struct Point {
    pub label: String,
    /// Index into the chart's pipelines (its colour).
    pub pipeline: usize,
    pub ms: f64,
    pub flip: f64,
    pub front: bool,
}

/// `lo..hi` padded by a tenth each side (a point alone gets a span).
fn padded(lo: f64, hi: f64, floor: Option<f64>) -> std::ops::Range<f64> {
    let pad = if hi > lo {
        0.1 * (hi - lo)
    } else {
        0.1 * hi.abs().max(1e-3)
    };
    let lo = floor.map_or(lo - pad, |f| (lo - pad).max(f));
    lo..hi + pad
}

/// Decimals that tell apart the labels of an axis spanning `span`
/// (about five labels; FLIP differences are often in the fourth place).
fn decimals(span: f64) -> usize {
    let d = -(span / 5.0).log10();
    if d.is_finite() {
        d.ceil().clamp(0.0, 8.0) as usize
    } else {
        3
    }
}

type XyChart<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// The axes' ranges: the points' time and FLIP, padded, from zero up.
fn ranges(points: &[Point]) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
    let span = |v: Vec<f64>| {
        let lo = v.iter().copied().fold(f64::MAX, f64::min);
        let hi = v.iter().copied().fold(0.0, f64::max);
        padded(lo, hi, Some(0.0))
    };
    (
        span(points.iter().map(|p| p.ms).collect()),
        span(points.iter().map(|p| p.flip).collect()),
    )
}

/// Time (x) against mean FLIP (y), coloured by pipeline, the frontier as
/// an amber staircase with rings, every point labelled; the legend names
/// `pipelines` (name and colour index).
pub fn pareto(points: &[Point], pipelines: &[(&str, usize)]) -> Result<String> {
    let what = "time-versus-FLIP";
    let (w, h) = (720u32, 440u32);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        let (xr, yr) = ranges(points);
        let (dx, dy) = (decimals(xr.end - xr.start), decimals(yr.end - yr.start));
        let mut chart = drawn(
            what,
            ChartBuilder::on(&root)
                .margin(14)
                .margin_top(36)
                .margin_right(24)
                .x_label_area_size(44)
                .y_label_area_size(72)
                .build_cartesian_2d(xr, yr),
        )?;
        drawn(
            what,
            chart
                .configure_mesh()
                .axis_style(AXIS)
                .bold_line_style(GRID)
                .light_line_style(TRANSPARENT)
                .label_style(font(13))
                .axis_desc_style(font(14))
                .x_desc("frame time, ms (median)")
                .y_desc("mean FLIP (lower is better)")
                .x_label_formatter(&|x| format!("{x:.dx$}"))
                .y_label_formatter(&|y| format!("{y:.dy$}"))
                .draw(),
        )?;
        let at = draw_points(&mut chart, points)?;
        labels(&root, points, &at, (w, h))?;
        legend(&root, pipelines)?;
        drawn(what, root.present())?;
    }
    Ok(svg)
}

/// The frontier's points joined as a staircase (the boundary of what its
/// rows dominate), by time.
fn stairs(points: &[Point]) -> Vec<(f64, f64)> {
    let mut front: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.front)
        .map(|p| (p.ms, p.flip))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    front
        .iter()
        .enumerate()
        .flat_map(|(i, &(t, e))| {
            let prev = i.checked_sub(1).map(|j| (t, front[j].1));
            prev.into_iter().chain([(t, e)])
        })
        .collect()
}

/// The staircase, the frontier's rings and every point; where the points
/// landed, in pixels.
fn draw_points(chart: &mut XyChart<'_, '_>, points: &[Point]) -> Result<Vec<(i32, i32)>> {
    let what = "time-versus-FLIP";
    let line = LineSeries::new(stairs(points), FRONTIER.mix(0.7).stroke_width(2));
    drawn(what, chart.draw_series(line))?;
    let rings = points
        .iter()
        .filter(|p| p.front)
        .map(|p| Circle::new((p.ms, p.flip), 8, FRONTIER.stroke_width(2)));
    drawn(what, chart.draw_series(rings))?;
    let dots = points.iter().map(|p| {
        let c = PIPELINES[p.pipeline % PIPELINES.len()];
        Circle::new((p.ms, p.flip), 5, c.filled())
    });
    drawn(what, chart.draw_series(dots))?;
    Ok(points
        .iter()
        .map(|p| chart.backend_coord(&(p.ms, p.flip)))
        .collect())
}

/// Approximate width in pixels of `text` at `size` (no font metrics in
/// an SVG backend without a font library; sans-serif averages ~0.56 em).
fn text_width(text: &str, size: u32) -> i32 {
    (text.chars().count() as f64 * 0.56 * f64::from(size)).ceil() as i32
}

/// Where each label goes: beside its point, right or left, moved up or
/// down past points and labels already placed (rows of nearly equal time
/// and FLIP would print over each other). `(x, y, moved)`: the label's
/// left end and middle, and whether it left its point's side.
fn place_labels(widths: &[i32], at: &[(i32, i32)], w: i32, h: i32) -> Vec<(i32, i32, bool)> {
    let overlaps = |r: (i32, i32, i32, i32), q: &(i32, i32, i32, i32)| {
        r.0 < q.2 && q.0 < r.2 && r.1 < q.3 && q.1 < r.3
    };
    let mut taken: Vec<(i32, i32, i32, i32)> = at
        .iter()
        .map(|&(x, y)| (x - 6, y - 6, x + 6, y + 6))
        .collect();
    let mut out = Vec::with_capacity(at.len());
    for (&tw, &(px, py)) in widths.iter().zip(at) {
        // Right, left, then centred over or under the point (off 0 only).
        let sides = [px + 10, px - 10 - tw, px - tw / 2];
        let candidates = [0, -16, 16, -32, 32, -48, 48, -64, 64, -80, 80]
            .into_iter()
            .flat_map(|dy| sides.map(|x| (x, py - 8 + dy, dy != 0)))
            .filter(|&(x, _, moved)| moved || x != px - tw / 2);
        let fits = |&(x, y, _): &(i32, i32, bool)| {
            let r = (x, y - 8, x + tw, y + 8);
            x >= 0 && x + tw <= w && r.1 >= 0 && r.3 <= h && !taken.iter().any(|q| overlaps(r, q))
        };
        let spot = candidates
            .into_iter()
            .find(fits)
            .unwrap_or((sides[0], py - 8, false));
        taken.push((spot.0, spot.1 - 8, spot.0 + tw, spot.1 + 8));
        out.push(spot);
    }
    out
}

/// Each point's label, with a leader line where it had to move.
fn labels(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    points: &[Point],
    at: &[(i32, i32)],
    (w, h): (u32, u32),
) -> Result<()> {
    let size = 12;
    let widths: Vec<i32> = points.iter().map(|p| text_width(&p.label, size)).collect();
    let spots = place_labels(&widths, at, w as i32, h as i32);
    for ((p, &(px, py)), ((x, y, moved), tw)) in
        points.iter().zip(at).zip(spots.into_iter().zip(widths))
    {
        if moved {
            // To the label's near end, or its near edge when centred.
            let end = match (x > px, x + tw < px) {
                (true, _) => (x - 2, y),
                (_, true) => (x + tw + 2, y),
                _ if y < py => (px, y + 7),
                _ => (px, y - 7),
            };
            let line = PathElement::new(vec![(px, py), end], AXIS.mix(0.6));
            drawn("time-versus-FLIP", root.draw(&line))?;
        }
        let style = font(size).pos(Pos::new(HPos::Left, VPos::Center));
        drawn(
            "time-versus-FLIP",
            root.draw(&Text::new(p.label.clone(), (x, y), style)),
        )?;
    }
    Ok(())
}

/// The pipelines' colours and the frontier, in a line above the plot
/// (inside it, they would cover points).
fn legend(root: &DrawingArea<SVGBackend<'_>, Shift>, pipelines: &[(&str, usize)]) -> Result<()> {
    let entries = pipelines
        .iter()
        .map(|&(name, i)| (name.to_string(), PIPELINES[i % PIPELINES.len()]))
        .chain([("Pareto frontier".to_string(), FRONTIER)]);
    let mut x = 90;
    for (name, colour) in entries {
        let dot = Circle::new((x, 16), 5, colour.filled());
        drawn("time-versus-FLIP", root.draw(&dot))?;
        let style = font(12).pos(Pos::new(HPos::Left, VPos::Center));
        let width = text_width(&name, 12);
        drawn(
            "time-versus-FLIP",
            root.draw(&Text::new(name, (x + 10, 16), style)),
        )?;
        x += width + 34;
    }
    Ok(())
}

/// One row's bar: its label, its passes' median ms in plan order, and its
/// median frame time (ticked on the bar; on ash queues overlap, so the
/// frame can be shorter than the passes' sum).
pub struct Bar {
    pub label: String,
    pub passes: Vec<(String, f64)>,
    pub frame_ms: Option<f64>,
}

impl Bar {
    /// The passes' summed medians.
    fn total(&self) -> f64 {
        self.passes.iter().map(|p| p.1).sum()
    }
}

/// The passes that get their own colour: at most a dozen, by their
/// largest share of any row; the rest are "other passes".
fn major_passes(bars: &[Bar]) -> Vec<String> {
    let mut share: Vec<(String, f64)> = Vec::new();
    for b in bars {
        let sum: f64 = b.passes.iter().map(|p| p.1).sum::<f64>().max(1e-12);
        for (name, ms) in &b.passes {
            match share.iter_mut().find(|(n, _)| n == name) {
                Some(s) => s.1 = s.1.max(ms / sum),
                None => share.push((name.clone(), ms / sum)),
            }
        }
    }
    let mut ranked: Vec<&(String, f64)> = share.iter().filter(|s| s.1 >= MINOR).collect();
    ranked.sort_by(|a, b| b.1.total_cmp(&a.1));
    ranked.truncate(PASSES.len());
    // Legend in plan order (first appearance), not by size.
    share
        .iter()
        .filter(|s| ranked.iter().any(|r| r.0 == s.0))
        .map(|s| s.0.clone())
        .collect()
}

/// Segments of one bar: (colour index or None for "other", start, end).
fn segments(bar: &Bar, major: &[String]) -> Vec<(Option<usize>, f64, f64)> {
    let (mut out, mut x, mut other) = (Vec::new(), 0.0, 0.0);
    for (name, ms) in &bar.passes {
        match major.iter().position(|m| m == name) {
            Some(i) => {
                out.push((Some(i), x, x + ms));
                x += ms;
            }
            None => other += ms,
        }
    }
    out.push((None, x, x + other));
    out
}

/// Horizontal stacked bars, one per row, passes coloured alike across
/// rows, with the legend at the right.
pub fn pass_bars(bars: &[Bar]) -> Result<String> {
    let what = "per-pass";
    let n = bars.len();
    let label_px = bars
        .iter()
        .map(|b| text_width(&b.label, 12))
        .max()
        .unwrap_or(0)
        + 16;
    let legend_px = 200u32;
    let major = major_passes(bars);
    // Tall enough for the bars and for the legend beside them.
    let legend_h = 30 + 20 * (major.len() as u32 + 1);
    let bars_h = 70 + 28 * n.max(1) as u32;
    let (w, h) = (1080u32, bars_h.max(legend_h));
    let max = bars.iter().map(Bar::total).fold(0.0, f64::max).max(1e-6);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        let (plot, side) = root.split_horizontally(w - legend_px);
        // Bars keep their thickness when the legend is the taller.
        let (plot, _) = plot.split_vertically(bars_h);
        let mut chart = drawn(
            what,
            ChartBuilder::on(&plot)
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(label_px as u32)
                // Row i spans y in [n-1-i, n-i]: row 0 on top.
                .build_cartesian_2d(0.0..max * 1.14, 0.0..n.max(1) as f64),
        )?;
        let dx = decimals(max * 1.14);
        drawn(
            what,
            chart
                .configure_mesh()
                .axis_style(AXIS)
                .bold_line_style(GRID)
                .light_line_style(TRANSPARENT)
                .disable_y_mesh()
                // Row labels are drawn beside their bars (draw_bars).
                .y_labels(0)
                .x_label_formatter(&|x| format!("{x:.dx$}"))
                .label_style(font(12))
                .axis_desc_style(font(13))
                .x_desc("ms: sum of the passes' medians (tick: median frame)")
                .draw(),
        )?;
        draw_bars(&root, &mut chart, bars, &major)?;
        bar_legend(&side, &major)?;
        drawn(what, root.present())?;
    }
    Ok(svg)
}

/// Each row's segments and annotations; row i spans y in [n-1-i, n-i].
fn draw_bars(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    chart: &mut XyChart<'_, '_>,
    bars: &[Bar],
    major: &[String],
) -> Result<()> {
    let n = bars.len();
    for (i, bar) in bars.iter().enumerate() {
        let y = (n - 1 - i) as f64;
        for (colour, a, b) in segments(bar, major) {
            let c = colour.map_or(OTHER, |k| PASSES[k % PASSES.len()]);
            let mut rect = Rectangle::new([(a, y), (b, y + 1.0)], c.filled());
            rect.set_margin(4, 4, 0, 0);
            drawn("per-pass", chart.draw_series(std::iter::once(rect)))?;
        }
        bar_annotations(root, chart, bar, y + 0.5)?;
    }
    Ok(())
}

/// The row's label left of its bar, its sum at the bar's end and a tick
/// at its median frame time, drawn on `root` in pixels (text in a chart's
/// coordinates cannot be offset).
fn bar_annotations(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    chart: &XyChart<'_, '_>,
    bar: &Bar,
    y: f64,
) -> Result<()> {
    let sum = bar.total();
    let (x0, yc) = chart.backend_coord(&(0.0, y));
    let style = font(12).pos(Pos::new(HPos::Right, VPos::Center));
    let label = Text::new(bar.label.clone(), (x0 - 8, yc), style);
    drawn("per-pass", root.draw(&label))?;
    let (x, yc) = chart.backend_coord(&(sum, y));
    let style = font(11).pos(Pos::new(HPos::Left, VPos::Center));
    let text = Text::new(format!("{sum:.2}"), (x + 6, yc), style);
    drawn("per-pass", root.draw(&text))?;
    if let Some(f) = bar.frame_ms {
        let (x, yc) = chart.backend_coord(&(f, y));
        let tick = PathElement::new(vec![(x, yc - 11), (x, yc + 11)], WHITE.stroke_width(2));
        drawn("per-pass", root.draw(&tick))?;
    }
    Ok(())
}

/// Swatches and pass names.
fn bar_legend(side: &DrawingArea<SVGBackend<'_>, Shift>, major: &[String]) -> Result<()> {
    let names = major
        .iter()
        .enumerate()
        .map(|(i, n)| (n.as_str(), PASSES[i % PASSES.len()]))
        .chain([("other passes", OTHER)]);
    for (i, (name, colour)) in names.enumerate() {
        let y = 16 + 20 * i as i32;
        let swatch = Rectangle::new([(4, y - 6), (16, y + 6)], colour.filled());
        drawn("per-pass", side.draw(&swatch))?;
        let style = font(12).pos(Pos::new(HPos::Left, VPos::Center));
        drawn("per-pass", side.draw(&Text::new(name, (22, y), style)))?;
    }
    Ok(())
}

/// Pipeline `i`'s point colour as CSS, for the table's dots.
pub fn pipeline_css(i: usize) -> String {
    let RGBColor(r, g, b) = PIPELINES[i % PIPELINES.len()];
    format!("#{r:02x}{g:02x}{b:02x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_of_coincident_points_do_not_overlap() {
        let at = [(100, 100), (102, 100), (104, 101), (600, 50)];
        let spots = place_labels(&[80, 80, 80, 80], &at, 640, 400);
        for (i, a) in spots.iter().enumerate() {
            for b in &spots[i + 1..] {
                let apart = (a.0 - b.0).abs() >= 80 || (a.1 - b.1).abs() >= 16;
                assert!(apart, "{a:?} and {b:?} overlap");
            }
        }
        // The last point is near the right edge: its label goes left.
        assert!(spots[3].0 + 80 <= 600, "{:?}", spots[3]);
        assert!(!spots[0].2, "the first label stays beside its point");
    }

    #[test]
    fn decimals_follow_the_span() {
        assert_eq!(decimals(0.0001), 5);
        assert_eq!(decimals(2.0), 1);
        assert_eq!(decimals(900.0), 0);
    }
}
