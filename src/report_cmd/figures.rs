//! A section's charts as page elements: time against FLIP with one
//! Pareto frontier per reference, and each pipeline's pass bars.

use super::charts::{self, Bar, Frontier, Point};
use super::data::{Cell, Reference, Section, frontier};
use super::html::{Counts, esc, inline_svg};
use miette::Result;
use std::fmt::Write as _;

/// Where `c`'s reference is in `refs`.
fn reference_of(refs: &[Reference<'_>], c: &Cell) -> Option<usize> {
    let key = c.judged_by()?;
    refs.iter().position(|r| r.key == key)
}

/// Each cell's place on its own reference's frontier (`None`: no time or
/// FLIP to place it by): rows are only compared with rows judged against
/// the same reference.
pub fn fronts(s: &Section<'_>, refs: &[Reference<'_>]) -> Vec<Option<bool>> {
    let placed: Vec<(usize, Option<usize>, (f64, f64))> = s
        .cells
        .iter()
        .enumerate()
        .filter_map(|(i, c)| Some((i, reference_of(refs, c), (c.ms()?, c.flip?))))
        .collect();
    let mut out = vec![None; s.cells.len()];
    for r in (0..refs.len()).map(Some).chain([None]) {
        let group: Vec<&(usize, Option<usize>, (f64, f64))> =
            placed.iter().filter(|p| p.1 == r).collect();
        let pts: Vec<(f64, f64)> = group.iter().map(|p| p.2).collect();
        for (p, f) in group.iter().zip(frontier(&pts)) {
            out[p.0] = Some(f);
        }
    }
    out
}

/// The references that have points on the chart, as frontiers, and each
/// reference's index among them.
fn frontiers(
    refs: &[Reference<'_>],
    pipes: &[&str],
    has_points: impl Fn(usize) -> bool,
) -> (Vec<Frontier>, Vec<Option<usize>>) {
    let mut out = Vec::new();
    let mut index = vec![None; refs.len()];
    for (r, reference) in refs.iter().enumerate().filter(|(r, _)| has_points(*r)) {
        index[r] = Some(out.len());
        let first = reference.pipelines.first().copied().unwrap_or_default();
        out.push(Frontier {
            name: reference.name().to_string(),
            colour: pipes.iter().position(|p| *p == first).unwrap_or(0),
        });
    }
    (out, index)
}

/// The time-versus-FLIP chart, or why there is none.
pub fn pareto(
    s: &Section<'_>,
    pipes: &[&str],
    refs: &[Reference<'_>],
    fronts: &[Option<bool>],
    counts: &mut Counts,
) -> Result<String> {
    let placed: Vec<(&Cell, usize, bool)> = s
        .cells
        .iter()
        .zip(fronts)
        .filter_map(|(c, f)| Some((*c, reference_of(refs, c)?, (*f)?)))
        .collect();
    if placed.is_empty() {
        return Ok(
            "<p class=\"nochart\">No row here has a reference, so there is no FLIP to chart: \
                   the table gives their times.</p>"
                .into(),
        );
    }
    let (lines, index) = frontiers(refs, pipes, |r| placed.iter().any(|p| p.1 == r));
    let points: Vec<Point> = placed
        .iter()
        .filter_map(|&(c, r, front)| {
            Some(Point {
                label: c.variant.clone(),
                pipeline: pipes.iter().position(|p| *p == c.pipeline)?,
                reference: index[r]?,
                ms: c.ms()?,
                flip: c.flip?,
                front,
            })
        })
        .collect();
    let with: Vec<(&str, usize)> = pipes
        .iter()
        .enumerate()
        .filter(|(i, _)| points.iter().any(|p| p.pipeline == *i))
        .map(|(i, p)| (*p, i))
        .collect();
    let svg = charts::pareto(&points, &with, &lines)?;
    counts.charts += 1;
    let judged: Vec<String> = refs
        .iter()
        .enumerate()
        .filter(|(r, _)| index[*r].is_some())
        .map(|(_, r)| r.label())
        .collect();
    Ok(format!(
        "<figure class=\"chart\" data-chart=\"pareto\">{}<figcaption>Median frame time (log scale) against \
         mean FLIP, each row against its pipeline's reference: {}. One Pareto frontier per reference, in \
         the colour of its first pipeline: a ringed row is one that no other row judged against the same \
         reference is both faster and closer to (FLIPs against different references do not compare).\
         </figcaption></figure>",
        inline_svg(&svg),
        esc(&judged.join("; "))
    ))
}

/// The measured rows of `pipeline` that have passes, as bars.
fn pipeline_bars(s: &Section<'_>, pipeline: &str) -> Vec<Bar> {
    s.cells
        .iter()
        .filter(|c| c.pipeline == pipeline && c.measured() && !c.passes.is_empty())
        .map(|c| Bar {
            label: c.variant.clone(),
            passes: c
                .passes
                .iter()
                .map(|p| (p.pass.clone(), p.median_ms.unwrap_or(0.0)))
                .collect(),
            frame_ms: c.ms(),
        })
        .collect()
}

/// Per-pass stacked bars, one chart per pipeline, each on its own axis.
pub fn bars(s: &Section<'_>, pipes: &[&str], counts: &mut Counts) -> Result<String> {
    let mut o = String::new();
    for (i, pipeline) in pipes.iter().enumerate() {
        let bars = pipeline_bars(s, pipeline);
        if bars.is_empty() {
            continue;
        }
        let svg = charts::pass_bars(&bars)?;
        counts.charts += 1;
        let _ = write!(
            o,
            "<figure class=\"chart\" data-chart=\"passes\"><figcaption class=\"title\">\
             <span class=\"dot\" style=\"background:{}\"></span>{}</figcaption>{}</figure>",
            charts::pipeline_css(i),
            esc(pipeline),
            inline_svg(&svg)
        );
    }
    if o.is_empty() {
        return Ok(o);
    }
    Ok(format!(
        "<div class=\"passes\">{o}</div><p class=\"chart-note\">Where each row's time goes, one chart per \
         pipeline on its own scale: its passes' median times stacked in plan order (passes under 1% of every \
         row's sum, or past the twelfth, are \"other passes\"); the white tick is the median frame time, shorter than the \
         sum where queues overlap (ash).</p>"
    ))
}

#[cfg(test)]
mod tests {
    use super::super::data::{Bench, sections};
    use super::*;

    #[test]
    fn rows_meet_only_rows_of_their_own_reference() {
        let cell = |pipeline: &str, graph: &str, ms: f64, flip: f64| {
            format!(
                r#"{{"backend":"ash","pipeline":"{pipeline}","variant":"v","view":"far","flip":{flip},
                "flip_reference":"{graph}.ron","frame":{{"median_ms":{ms},"min_ms":{ms},"max_ms":{ms}}}}}"#
            )
        };
        let json = format!(
            r#"{{"size":"s","frames":1,"warmup":0,"cells":[{},{},{},{}]}}"#,
            // Kulikov's row beats Lipp's on both, but against another reference.
            cell("Kulikov", "kulikov_reference", 1.0, 0.01),
            cell("Lipp", "lipp_reference", 2.0, 0.04),
            cell("HW mesh", "lipp_reference", 300.0, 0.04),
            cell("Scheuermann", "none", 5.0, 0.5)
        );
        let b: Bench = serde_json::from_str(&json).unwrap();
        let secs = sections(&b);
        let refs = secs[0].references();
        assert_eq!(refs.len(), 3);
        let fronts = fronts(&secs[0], &refs);
        assert_eq!(fronts, [Some(true), Some(true), Some(false), Some(true)]);
    }
}
