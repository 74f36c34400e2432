//! Time (a logarithmic x: the rows span two orders of magnitude) against
//! mean FLIP (y), coloured by pipeline, with one Pareto frontier per
//! reference: FLIPs against different references do not compare.

use super::labels::draw_labels;
use super::{AXIS, GRID, Swatch, decimals, drawn, font, legend, legend_height, pipeline_colour};
use miette::Result;
use plotters::coord::combinators::WithKeyPoints;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::ops::Range;

const WHAT: &str = "time-versus-FLIP";

/// One row on the chart.
pub struct Point {
    pub label: String,
    /// Index into the chart's pipelines (its colour).
    pub pipeline: usize,
    /// Index into the chart's frontiers: the reference it is judged by.
    pub reference: usize,
    pub ms: f64,
    pub flip: f64,
    /// On its reference's frontier.
    pub front: bool,
}

/// One reference's frontier: its name and its colour (a pipeline index).
pub struct Frontier {
    pub name: String,
    pub colour: usize,
}

type LogX = WithKeyPoints<LogCoord<f64>>;
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<LogX, RangedCoordf64>>;

/// The times' range, widened in ratio so points clear the edges.
fn log_span(ms: &[f64]) -> Range<f64> {
    let lo = ms.iter().copied().fold(f64::MAX, f64::min).max(1e-6);
    let hi = ms.iter().copied().fold(lo, f64::max);
    let pad = (hi / lo).powf(0.06).max(1.15);
    lo / pad..hi * pad
}

/// Values `m · 10^k` for the mantissas `ms` inside `r`.
fn decade_ticks(r: &Range<f64>, ms: &[f64]) -> Vec<f64> {
    let (a, b) = (r.start.log10().floor() as i32, r.end.log10().ceil() as i32);
    (a..=b)
        .flat_map(|k| ms.iter().map(move |m| m * 10f64.powi(k)))
        .filter(|v| r.contains(v))
        .collect()
}

/// Ticks of a linear axis over `r`, about five (a range too narrow for
/// decade ticks).
fn linear_ticks(r: &Range<f64>) -> Vec<f64> {
    let raw = (r.end - r.start) / 5.0;
    let unit = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * unit)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * unit);
    let first = (r.start / step).ceil() as i64;
    (first..)
        .map(|i| i as f64 * step)
        .take_while(|v| *v <= r.end)
        .collect()
}

/// The time axis' ticks: 1, 2, 5, 10, 20, 50 … where that gives four to
/// twelve, else powers of ten over many decades, else denser mantissas,
/// else linear steps.
fn log_ticks(r: &Range<f64>) -> Vec<f64> {
    let ticks = decade_ticks(r, &[1.0, 2.0, 5.0]);
    if (4..=12).contains(&ticks.len()) {
        return ticks;
    }
    let sets: [&[f64]; 3] = [
        &[1.0],
        &[1.0, 2.0, 3.0, 5.0],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
    ];
    sets.into_iter()
        .map(|ms| decade_ticks(r, ms))
        .find(|t| t.len() >= 4)
        .unwrap_or_else(|| linear_ticks(r))
}

/// A tick's label: as few decimals as it needs (1, 2.5, 0.2).
fn tick_label(v: f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The FLIP axis: from zero up (or a little under the lowest), padded,
/// more above (room for the labels of the worst rows).
fn flip_span(flip: &[f64]) -> Range<f64> {
    let lo = flip.iter().copied().fold(f64::MAX, f64::min);
    let hi = flip.iter().copied().fold(0.0, f64::max);
    let pad = if hi > lo {
        0.1 * (hi - lo)
    } else {
        0.1 * hi.abs().max(1e-3)
    };
    (lo - pad).max(0.0)..hi + 2.0 * pad
}

/// The legend: pipelines by colour, then each reference's frontier.
fn entries(pipelines: &[(&str, usize)], frontiers: &[Frontier]) -> Vec<(String, Swatch)> {
    let dots = pipelines
        .iter()
        .map(|&(name, i)| (name.to_string(), Swatch::Dot(pipeline_colour(i))));
    let lines = frontiers.iter().map(|f| {
        let name = format!("frontier against {}", f.name);
        (name, Swatch::Line(frontier_colour(f)))
    });
    dots.chain(lines).collect()
}

fn frontier_colour(f: &Frontier) -> RGBColor {
    pipeline_colour(f.colour)
}

/// The chart; `pipelines` are the legend's names and colour indices.
pub fn pareto(
    points: &[Point],
    pipelines: &[(&str, usize)],
    frontiers: &[Frontier],
) -> Result<String> {
    let (w, plot_h) = (720u32, 440u32);
    let entries = entries(pipelines, frontiers);
    let h = plot_h + legend_height(&entries, w);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        let (plot, under) = root.split_vertically(plot_h);
        let mut chart = axes(&plot, points)?;
        let at = draw_points(&mut chart, points, frontiers)?;
        let texts: Vec<&str> = points.iter().map(|p| p.label.as_str()).collect();
        // Right of the FLIP axis, above the time axis; the margin above
        // the plot is free.
        let (xs, ys) = chart.plotting_area().get_pixel_range();
        draw_labels(&plot, &texts, &at, (xs.start + 4, 0, w as i32, ys.end))?;
        legend(&under, &entries, WHAT)?;
        drawn(WHAT, root.present())?;
    }
    Ok(svg)
}

/// The chart's axes: log time with 1-2-5 ticks, linear FLIP.
fn axes<'a, 'b>(plot: &'a super::Area<'b>, points: &[Point]) -> Result<Chart<'a, 'b>> {
    let ms: Vec<f64> = points.iter().map(|p| p.ms).collect();
    let flip: Vec<f64> = points.iter().map(|p| p.flip).collect();
    let (xr, yr) = (log_span(&ms), flip_span(&flip));
    let ticks = log_ticks(&xr);
    let dy = decimals(yr.end - yr.start);
    let mut chart = drawn(
        WHAT,
        ChartBuilder::on(plot)
            .margin(14)
            .margin_right(24)
            .x_label_area_size(44)
            .y_label_area_size(72)
            .build_cartesian_2d(xr.log_scale().with_key_points(ticks), yr),
    )?;
    drawn(
        WHAT,
        chart
            .configure_mesh()
            .axis_style(AXIS)
            .bold_line_style(GRID)
            .light_line_style(TRANSPARENT)
            .label_style(font(13))
            .axis_desc_style(font(14))
            .x_desc("frame time, ms (median; log scale)")
            .y_desc("mean FLIP (lower is better)")
            .x_label_formatter(&|x| tick_label(*x))
            .y_label_formatter(&|y| format!("{y:.dy$}"))
            .draw(),
    )?;
    Ok(chart)
}

/// Reference `r`'s frontier points joined as a staircase (the boundary of
/// what its rows dominate), by time.
fn stairs(points: &[Point], r: usize) -> Vec<(f64, f64)> {
    let mut front: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.front && p.reference == r)
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

/// Each reference's staircase and rings, then every point; where the
/// points landed, in pixels.
fn draw_points(
    chart: &mut Chart<'_, '_>,
    points: &[Point],
    frontiers: &[Frontier],
) -> Result<Vec<(i32, i32)>> {
    for (r, f) in frontiers.iter().enumerate() {
        let c = frontier_colour(f);
        let line = LineSeries::new(stairs(points, r), c.mix(0.8).stroke_width(2));
        drawn(WHAT, chart.draw_series(line))?;
        let rings = points
            .iter()
            .filter(|p| p.front && p.reference == r)
            .map(|p| Circle::new((p.ms, p.flip), 8, c.stroke_width(2)));
        drawn(WHAT, chart.draw_series(rings))?;
    }
    let dots = points
        .iter()
        .map(|p| Circle::new((p.ms, p.flip), 5, pipeline_colour(p.pipeline).filled()));
    drawn(WHAT, chart.draw_series(dots))?;
    Ok(points
        .iter()
        .map(|p| chart.backend_coord(&(p.ms, p.flip)))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_h100_span_gets_one_two_five_ticks() {
        let r = log_span(&[2.4, 333.0]);
        let labels: Vec<String> = log_ticks(&r).into_iter().map(tick_label).collect();
        assert_eq!(labels, ["2", "5", "10", "20", "50", "100", "200"]);
    }

    #[test]
    fn narrow_and_wide_spans_still_get_ticks() {
        let narrow = log_ticks(&log_span(&[2.40, 2.44]));
        assert!(narrow.len() >= 3, "{narrow:?}");
        let wide = log_ticks(&(0.01..5000.0));
        assert_eq!(wide.len(), 6, "{wide:?}");
        assert_eq!(tick_label(0.30000000000000004), "0.3");
        assert_eq!(tick_label(20.0), "20");
    }

    #[test]
    fn each_reference_has_its_own_staircase() {
        let p = |reference, ms, flip| Point {
            label: String::new(),
            pipeline: reference,
            reference,
            ms,
            flip,
            front: true,
        };
        let pts = [p(0, 1.0, 0.3), p(0, 2.0, 0.1), p(1, 5.0, 0.2)];
        assert_eq!(stairs(&pts, 0), [(1.0, 0.3), (2.0, 0.3), (2.0, 0.1)]);
        assert_eq!(stairs(&pts, 1), [(5.0, 0.2)]);
    }
}
