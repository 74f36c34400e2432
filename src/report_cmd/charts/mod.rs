//! The report's charts, drawn with `plotters` into SVG strings that the
//! page inlines: time against FLIP with one Pareto frontier per reference
//! (pareto.rs), and each pipeline's rows' passes as stacked bars
//! (bars.rs). Colours suit the page's dark background.

mod bars;
mod labels;
mod pareto;

pub use bars::{Bar, pass_bars};
pub use pareto::{Frontier, Point, pareto};

use miette::{Result, miette};
use plotters::coord::Shift;
use plotters::element::PathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

const TEXT: RGBColor = RGBColor(0xc9, 0xcc, 0xd1);
const AXIS: RGBColor = RGBColor(0x8b, 0x90, 0x99);
const GRID: RGBColor = RGBColor(0x2c, 0x2f, 0x34);
const OTHER: RGBColor = RGBColor(0x55, 0x5a, 0x61);
/// Point colours per pipeline; a reference's frontier takes the colour of
/// its first pipeline.
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

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// `plotters`' errors as diagnostics naming the chart.
fn drawn<T, E: std::fmt::Display>(what: &str, r: Result<T, E>) -> Result<T> {
    r.map_err(|e| miette!("drawing the {what} chart: {e}"))
}

fn font(size: u32) -> TextStyle<'static> {
    ("sans-serif", size).into_font().color(&TEXT)
}

/// Pipeline `i`'s colour.
fn pipeline_colour(i: usize) -> RGBColor {
    PIPELINES[i % PIPELINES.len()]
}

/// Pipeline `i`'s point colour as CSS, for the table's dots.
pub fn pipeline_css(i: usize) -> String {
    let RGBColor(r, g, b) = pipeline_colour(i);
    format!("#{r:02x}{g:02x}{b:02x}")
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

/// Approximate width in pixels of `text` at `size` (no font metrics in
/// an SVG backend without a font library; sans-serif averages ~0.56 em).
fn text_width(text: &str, size: u32) -> i32 {
    (text.chars().count() as f64 * 0.56 * f64::from(size)).ceil() as i32
}

/// What a legend entry shows before its name.
#[derive(Clone, Copy)]
enum Swatch {
    Dot(RGBColor),
    Square(RGBColor),
    /// A frontier: a line with a ring on it.
    Line(RGBColor),
}

const LEGEND_SIZE: u32 = 12;
const LEGEND_LINE: i32 = 20;

/// Where each entry of a legend goes when its entries flow in lines
/// `width` wide: the swatch's centre, with the height it all takes.
fn legend_layout(names: &[&str], width: i32) -> (Vec<(i32, i32)>, u32) {
    let (mut x, mut y) = (12, LEGEND_LINE / 2 + 4);
    let mut out = Vec::with_capacity(names.len());
    for name in names {
        let w = 16 + text_width(name, LEGEND_SIZE) + 22;
        if x > 12 && x + w > width {
            (x, y) = (12, y + LEGEND_LINE);
        }
        out.push((x, y));
        x += w;
    }
    (out, (y + LEGEND_LINE / 2 + 4) as u32)
}

/// The legend's height for `entries` flowing `width` wide.
fn legend_height(entries: &[(String, Swatch)], width: u32) -> u32 {
    let names: Vec<&str> = entries.iter().map(|e| e.0.as_str()).collect();
    legend_layout(&names, width as i32).1
}

/// The entries drawn in lines across `area` (outside any plot, so they
/// cover no point or label).
fn legend(area: &Area<'_>, entries: &[(String, Swatch)], what: &str) -> Result<()> {
    let names: Vec<&str> = entries.iter().map(|e| e.0.as_str()).collect();
    let (at, _) = legend_layout(&names, area.dim_in_pixel().0 as i32);
    for ((name, swatch), (x, y)) in entries.iter().zip(at) {
        match *swatch {
            Swatch::Dot(c) => drawn(what, area.draw(&Circle::new((x, y), 5, c.filled())))?,
            Swatch::Square(c) => {
                let square = Rectangle::new([(x - 6, y - 6), (x + 6, y + 6)], c.filled());
                drawn(what, area.draw(&square))?
            }
            Swatch::Line(c) => {
                let line = PathElement::new(vec![(x - 8, y), (x + 8, y)], c.stroke_width(2));
                drawn(what, area.draw(&line))?;
                drawn(what, area.draw(&Circle::new((x, y), 5, c.stroke_width(2))))?
            }
        }
        let style = font(LEGEND_SIZE).pos(Pos::new(HPos::Left, VPos::Center));
        drawn(
            what,
            area.draw(&Text::new(name.clone(), (x + 12, y), style)),
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_follow_the_span() {
        assert_eq!(decimals(0.0001), 5);
        assert_eq!(decimals(2.0), 1);
        assert_eq!(decimals(900.0), 0);
    }

    #[test]
    fn a_legend_wraps_to_its_width() {
        let names = ["Kulikov", "Lipp", "HW strands", "frontier · lipp_reference"];
        let (at, h) = legend_layout(&names, 200);
        assert!(at.iter().all(|&(x, _)| x < 200), "{at:?}");
        assert!(at.last().unwrap().1 > at[0].1, "{at:?}");
        assert_eq!(h as i32, at.last().unwrap().1 + LEGEND_LINE / 2 + 4);
        let (one, _) = legend_layout(&names, 2000);
        assert!(one.iter().all(|p| p.1 == one[0].1), "{one:?}");
    }
}
