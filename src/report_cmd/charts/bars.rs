//! One pipeline's rows as horizontal stacked bars of their passes, on an
//! axis of its own (a 333 ms row would squeeze a 2 ms pipeline's bars to
//! slivers), with the pass legend below.

use super::{
    AXIS, Area, GRID, OTHER, PASSES, Swatch, decimals, drawn, font, legend, legend_height,
    text_width,
};
use miette::Result;
use plotters::coord::types::RangedCoordf64;
use plotters::element::PathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

const WHAT: &str = "per-pass";
/// Passes under this share of every row's sum go into "other passes"
/// (as do those past the twelfth largest).
const MINOR: f64 = 0.01;

type XyChart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

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
        let sum: f64 = b.total().max(1e-12);
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

/// The legend: the major passes' colours, then "other passes" where a
/// bar has any.
fn entries(bars: &[Bar], major: &[String]) -> Vec<(String, Swatch)> {
    let has_other = bars
        .iter()
        .any(|b| b.passes.iter().any(|p| !major.contains(&p.0)));
    let other = has_other.then(|| ("other passes".to_string(), Swatch::Square(OTHER)));
    major
        .iter()
        .enumerate()
        .map(|(i, n)| (n.clone(), Swatch::Square(PASSES[i % PASSES.len()])))
        .chain(other)
        .collect()
}

/// Horizontal stacked bars, one per row of one pipeline, on a linear
/// axis from zero to its longest row, with the legend below.
pub fn pass_bars(bars: &[Bar]) -> Result<String> {
    let n = bars.len().max(1);
    let w = 640u32;
    let major = major_passes(bars);
    let entries = entries(bars, &major);
    let bars_h = 64 + 26 * n as u32;
    let h = bars_h + legend_height(&entries, w);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        let (plot, under) = root.split_vertically(bars_h);
        let mut chart = axes(&plot, bars)?;
        draw_bars(&root, &mut chart, bars, &major)?;
        legend(&under, &entries, WHAT)?;
        drawn(WHAT, root.present())?;
    }
    Ok(svg)
}

/// Rows down the left (row i spans y in [n-1-i, n-i]: row 0 on top), ms
/// along the bottom.
fn axes<'a, 'b>(plot: &'a Area<'b>, bars: &[Bar]) -> Result<XyChart<'a, 'b>> {
    let n = bars.len().max(1);
    let label_px = bars
        .iter()
        .map(|b| text_width(&b.label, 12))
        .max()
        .unwrap_or(0)
        + 16;
    let longest = |b: &Bar| b.total().max(b.frame_ms.unwrap_or(0.0));
    let max = bars.iter().map(longest).fold(0.0, f64::max).max(1e-6);
    // Room at the right for the longest bar's sum.
    let end = max * 1.16;
    let mut chart = drawn(
        WHAT,
        ChartBuilder::on(plot)
            .margin(10)
            .margin_right(16)
            .x_label_area_size(40)
            .y_label_area_size(label_px as u32)
            .build_cartesian_2d(0.0..end, 0.0..n as f64),
    )?;
    let dx = decimals(end);
    drawn(
        WHAT,
        chart
            .configure_mesh()
            .axis_style(AXIS)
            .bold_line_style(GRID)
            .light_line_style(TRANSPARENT)
            .disable_y_mesh()
            // Row labels are drawn beside their bars (bar_annotations).
            .y_labels(0)
            .x_labels(6)
            .x_label_formatter(&|x| format!("{x:.dx$}"))
            .label_style(font(12))
            .axis_desc_style(font(13))
            .x_desc("ms: sum of the passes' medians (tick: median frame)")
            .draw(),
    )?;
    Ok(chart)
}

/// Each row's segments and annotations; row i spans y in [n-1-i, n-i].
fn draw_bars(
    root: &Area<'_>,
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
            drawn(WHAT, chart.draw_series(std::iter::once(rect)))?;
        }
        bar_annotations(root, chart, bar, y + 0.5)?;
    }
    Ok(())
}

/// The row's label left of its bar, its sum at the bar's end and a tick
/// at its median frame time, drawn on `root` in pixels (text in a chart's
/// coordinates cannot be offset).
fn bar_annotations(root: &Area<'_>, chart: &XyChart<'_, '_>, bar: &Bar, y: f64) -> Result<()> {
    let sum = bar.total();
    let (x0, yc) = chart.backend_coord(&(0.0, y));
    let style = font(12).pos(Pos::new(HPos::Right, VPos::Center));
    let label = Text::new(bar.label.clone(), (x0 - 8, yc), style);
    drawn(WHAT, root.draw(&label))?;
    // Past the bar's end, or its tick where the frame is the longer.
    let (x, yc) = chart.backend_coord(&(sum.max(bar.frame_ms.unwrap_or(0.0)), y));
    let style = font(11).pos(Pos::new(HPos::Left, VPos::Center));
    let text = Text::new(format!("{sum:.2}"), (x + 6, yc), style);
    drawn(WHAT, root.draw(&text))?;
    if let Some(f) = bar.frame_ms {
        let (x, yc) = chart.backend_coord(&(f, y));
        let tick = PathElement::new(vec![(x, yc - 10), (x, yc + 10)], WHITE.stroke_width(2));
        drawn(WHAT, root.draw(&tick))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_passes_go_to_other() {
        let bar = Bar {
            label: "a".into(),
            passes: vec![
                ("raster".into(), 9.0),
                ("tiny".into(), 0.01),
                ("shade".into(), 1.0),
            ],
            frame_ms: Some(9.5),
        };
        let major = major_passes(std::slice::from_ref(&bar));
        assert_eq!(major, ["raster", "shade"]);
        let segs = segments(&bar, &major);
        assert_eq!(segs.last().unwrap().0, None);
        assert!((segs.last().unwrap().2 - bar.total()).abs() < 1e-12);
        assert_eq!(entries(&[bar], &major).len(), 3);
    }
}
