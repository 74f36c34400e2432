//! The bench's results: statistics per cell, the printed table (shaped as
//! Lipp's Table 1), and the CSV and JSON files.

use super::pictures::Saved;
use super::quality;
use super::{Args, Variant};
use miette::{IntoDiagnostic, Result, WrapErr};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use strandgraph::compare::Temporal;
use strandgraph::runner::{Backend, PassTime};

/// Median of `v` (mean of the middle two for an even count); NaN if empty.
pub fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// Median, min and max over frames, in ms.
#[derive(Debug, Clone, Copy)]
pub struct Spread {
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Spread {
    pub fn of(v: &[f64]) -> Spread {
        Spread {
            median: median(v),
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
    fn json(&self) -> Value {
        json!({"median_ms": self.median, "min_ms": self.min, "max_ms": self.max})
    }
}

/// One pass of a measured cell.
#[derive(Debug, Clone)]
pub struct PassStats {
    pub name: String,
    pub kind: String,
    /// Its time over frames.
    pub spread: Spread,
    /// Median begin and end from the frame's first timestamp, where the
    /// backend gives spans (ash): with queues overlapping, these show which
    /// passes a frame waits for.
    pub span: Option<(f64, f64)>,
}

/// One measured cell.
#[derive(Debug, Clone)]
pub struct Stats {
    pub frames: usize,
    pub total: Spread,
    /// The frame timed by timestamps only at its queues' bounds, over as
    /// many frames run again so (ash; `None` where the backend times passes
    /// only): per-pass queries make a queue's passes wait for each other.
    pub bounds: Option<Spread>,
    /// `bench --levels`: the frame's dependency levels, timed (ash).
    pub levels: Vec<super::levels::LevelSpread>,
    /// The raster passes' summed time per frame.
    pub raster: Spread,
    /// Per pass, in plan order.
    pub passes: Vec<PassStats>,
    /// Atomics of the raster passes, from the instrumented CPU run.
    pub raster_atomics: u64,
    /// Every frame's per-pass times (JSON only).
    pub per_frame: Vec<Vec<f64>>,
    /// Mean FLIP against the pipeline's reference: of the last frame, or
    /// averaged over an animated scene's timed frames.
    pub flip: Option<f32>,
    /// Each judged frame's mean FLIP (one for a still scene).
    pub flip_frames: Vec<f32>,
    /// The last frame's coverage error against the reference
    /// (compare::coverage_error).
    pub coverage_error: Option<f32>,
    /// An animated scene's flicker against the reference's.
    pub temporal: Option<Temporal>,
    /// Where `--pictures` saved the last frame, its FLIP map and reference.
    pub pictures: Option<Saved>,
}

impl Stats {
    pub fn new(frames: &[Vec<PassTime>], totals: &[f64], raster: &[&str], atomics: u64) -> Stats {
        let first = frames.first().map_or(&[][..], Vec::as_slice);
        let passes = first
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let v: Vec<f64> = frames
                    .iter()
                    .filter_map(|f| f.get(i).and_then(|t| t.millis))
                    .collect();
                let spans: Vec<(f64, f64)> = frames
                    .iter()
                    .filter_map(|f| f.get(i).and_then(|t| t.span))
                    .collect();
                let begins: Vec<f64> = spans.iter().map(|s| s.0).collect();
                let ends: Vec<f64> = spans.iter().map(|s| s.1).collect();
                PassStats {
                    name: t.name.clone(),
                    kind: t.kind.clone(),
                    spread: Spread::of(&v),
                    span: (!spans.is_empty()).then(|| (median(&begins), median(&ends))),
                }
            })
            .collect();
        let raster_ms: Vec<f64> = frames
            .iter()
            .map(|f| {
                f.iter()
                    .filter(|t| raster.contains(&strandgraph_graph::base_name(&t.name)))
                    .filter_map(|t| t.millis)
                    .sum()
            })
            .collect();
        Stats {
            frames: frames.len(),
            total: Spread::of(totals),
            bounds: None,
            levels: Vec::new(),
            raster: Spread::of(&raster_ms),
            passes,
            raster_atomics: atomics,
            per_frame: frames
                .iter()
                .map(|f| f.iter().map(|t| t.millis.unwrap_or(f64::NAN)).collect())
                .collect(),
            flip: None,
            flip_frames: Vec::new(),
            coverage_error: None,
            temporal: None,
            pictures: None,
        }
    }

    /// Takes the quality measures of `j`.
    pub fn judged(&mut self, j: &quality::Judged) {
        self.flip = Some(j.flip());
        self.flip_frames = j.flip_frames.clone();
        self.coverage_error = j.coverage_error;
        self.temporal = j.temporal;
    }

    /// Raster atomics per second.
    fn atomic_rate(&self) -> f64 {
        self.raster_atomics as f64 / (self.raster.median * 1e-3)
    }
}

#[derive(Debug, Clone)]
pub enum Cell {
    Measured(Box<Stats>),
    Skipped(String),
}

/// The roofline of one backend: (operations or bytes, median ms).
#[derive(Debug, Clone, Copy)]
pub struct Ceilings {
    pub atomic_min32: (u64, f64),
    pub atomic_min64: (u64, f64),
    /// Bytes copied (each read once and written once).
    pub copy: (u64, f64),
    /// Triangles and shaded fragments through the hardware rasterizer.
    pub triangles: (u64, f64),
    pub fragments: (u64, f64),
}

impl Ceilings {
    /// Operations per second of the roofline pass `name`.
    fn rate(&self, name: &str) -> Option<f64> {
        let (n, ms) = match name {
            "atomic_min32" => self.atomic_min32,
            "atomic_min64" => self.atomic_min64,
            "triangles" => self.triangles,
            "fragments" => self.fragments,
            _ => return None,
        };
        Some(n as f64 / (ms * 1e-3))
    }
}

pub struct Report {
    pub views: Vec<String>,
    scenes: Vec<PathBuf>,
    size: String,
    frames: usize,
    warmup: usize,
    subgroup: u32,
    devices: Vec<(Backend, String, Vec<String>)>,
    ceilings: Vec<(Backend, Ceilings)>,
    cells: Vec<(Backend, Variant, usize, Cell)>,
    notes: Vec<String>,
    pub elapsed_s: f64,
    /// While the bench runs, `--out` is rewritten after every row with
    /// what is measured so far ("partial": true in the JSON), so a run cut
    /// short (a device's time limit) keeps its finished rows.
    pub partial: bool,
}

/// A row's `pipeline: variant` label.
fn row_label(v: &Variant) -> String {
    format!("{}: {}", v.pipeline, v.name)
}

/// The widest row label, so the tables' columns line up.
fn label_width() -> usize {
    super::VARIANTS
        .iter()
        .map(|v| row_label(v).len())
        .max()
        .unwrap_or(0)
}

/// `close` from `scenes/distances/close.ron`.
fn view_name(p: &Path) -> String {
    p.file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_string()
}

fn rate(x: f64) -> String {
    if !x.is_finite() {
        "-".into()
    } else if x >= 1e9 {
        format!("{:.2} G", x / 1e9)
    } else {
        format!("{:.1} M", x / 1e6)
    }
}

impl Report {
    pub fn new(args: &Args, scenes: &[PathBuf]) -> Report {
        Report {
            views: scenes.iter().map(|s| view_name(s)).collect(),
            scenes: scenes.to_vec(),
            size: args
                .size
                .clone()
                .unwrap_or_else(|| "scene resolution".into()),
            frames: args.frames,
            warmup: args.warmup,
            subgroup: args.subgroup,
            devices: Vec::new(),
            ceilings: Vec::new(),
            cells: Vec::new(),
            notes: Vec::new(),
            elapsed_s: 0.0,
            partial: false,
        }
    }
    /// A line printed under the table (and kept in the JSON).
    pub fn note(&mut self, line: String) {
        self.notes.push(line);
    }
    /// Records the device of `b` (once; later calls are ignored).
    pub fn device(&mut self, b: Backend, name: &str, notes: &[String]) {
        if !self.has_device(b) {
            self.devices.push((b, name.to_string(), notes.to_vec()));
        }
    }
    pub fn has_device(&self, b: Backend) -> bool {
        self.devices.iter().any(|(x, ..)| *x == b)
    }
    pub fn ceilings(&mut self, b: Backend, c: Ceilings) {
        self.ceilings.push((b, c));
    }
    pub fn cell(&mut self, b: Backend, v: &Variant, view: usize, cell: Cell) {
        self.cells.push((b, *v, view, cell));
    }

    fn ceiling(&self, b: Backend, v: &Variant) -> Option<f64> {
        self.ceilings
            .iter()
            .find(|(x, _)| *x == b)
            .and_then(|(_, c)| c.rate(v.ceiling))
    }

    fn device_name(&self, b: Backend) -> &str {
        self.devices
            .iter()
            .find(|(x, ..)| *x == b)
            .map_or("?", |(_, d, _)| d.as_str())
    }

    /// The cell of row `v` on backend `b` at view `s`.
    fn cell_at(&self, b: Backend, v: &Variant, s: usize) -> Option<&Cell> {
        self.cells
            .iter()
            .find(|(x, y, view, _)| {
                *x == b && y.name == v.name && y.pipeline == v.pipeline && *view == s
            })
            .map(|c| &c.3)
    }

    /// A table's header line: the label column, then the views `w` wide.
    fn header(&self, o: &mut String, w: usize) {
        let _ = write!(
            o,
            "  {:<5} {:<lw$}",
            "",
            "pipeline: variant",
            lw = label_width()
        );
        for v in &self.views {
            let _ = write!(o, " {v:>w$}");
        }
        let _ = writeln!(o);
    }

    /// Mean FLIP per row and view, for the rows whose pipeline has a
    /// reference; empty when none has.
    fn quality_table(&self, rows: &[(Backend, Variant)]) -> String {
        let with: Vec<&(Backend, Variant)> = rows
            .iter()
            .filter(|(_, v)| quality::reference_graph(v.pipeline).is_some())
            .collect();
        if with.is_empty() {
            return String::new();
        }
        let mut o = self.metric_table(
            &with,
            "Quality: mean FLIP of the last frame (of an animated scene: of every timed frame) against the pipeline's reference (0 is identical; ACES, 0 EV)",
            |st| st.flip,
        );
        if rows
            .iter()
            .any(|(b, v)| (0..self.views.len()).any(|s| self.temporal_at(*b, v, s).is_some()))
        {
            o += &self.metric_table(
                &with,
                "Flicker: mean |frame-to-frame luma change - the reference's| (animated scenes; 0 changes as the reference does)",
                |st| st.temporal.map(|t| t.flicker),
            );
        }
        o += &self.metric_table(
            &with,
            "Coverage error: mean |alpha - reference alpha| over the pixels with hair in either",
            |st| st.coverage_error,
        );
        o
    }

    /// The temporal measures of a cell, if it has them.
    fn temporal_at(&self, b: Backend, v: &Variant, s: usize) -> Option<Temporal> {
        match self.cell_at(b, v, s) {
            Some(Cell::Measured(st)) => st.temporal,
            _ => None,
        }
    }

    /// One line per row of `metric` at every view (three significant digits).
    fn metric_table(
        &self,
        rows: &[&(Backend, Variant)],
        title: &str,
        metric: impl Fn(&Stats) -> Option<f32>,
    ) -> String {
        let mut o = String::new();
        let w = 12;
        let _ = writeln!(o, "\n{title}");
        self.header(&mut o, w);
        for (b, v) in rows {
            let _ = write!(
                o,
                "  {:<5} {:<lw$}",
                b.name(),
                row_label(v),
                lw = label_width()
            );
            for s in 0..self.views.len() {
                let value = match self.cell_at(*b, v, s) {
                    Some(Cell::Measured(st)) => metric(st),
                    _ => None,
                };
                let text = value.map_or("-".into(), |f| {
                    strandgraph::compare::flip_text(f64::from(f))
                });
                let _ = write!(o, " {text:>w$}");
            }
            let _ = writeln!(o);
        }
        o
    }

    /// The text table.
    pub fn table(&self) -> String {
        let mut o = String::new();
        let _ = writeln!(
            o,
            "\nstrandgraph bench: {} at {}, {} timed frames after {} warm-up",
            self.views.join(", "),
            self.size,
            self.frames,
            self.warmup
        );
        for (b, d, _) in &self.devices {
            let _ = writeln!(o, "  {:<5} {d}  [{}]", b.name(), b.clock().describe());
        }
        let _ = writeln!(
            o,
            "\nRoofline (scenes/graphs/roofline.ron, same device and run; median of {} frames)",
            self.frames
        );
        let _ = writeln!(
            o,
            "  {:<5} {:>24} {:>24} {:>22} {:>22} {:>22}",
            "", "32-bit atomicMin", "64-bit atomicMin", "copy", "hw triangles", "hw fragments"
        );
        for (b, c) in &self.ceilings {
            let atom = |(n, ms): (u64, f64)| {
                format!("{}atom/s ({ms:.3} ms)", rate(n as f64 / (ms * 1e-3)))
            };
            let (bytes, ms) = c.copy;
            let copy = format!("{}B/s ({ms:.3} ms)", rate(2.0 * bytes as f64 / (ms * 1e-3)));
            let per_s =
                |(n, ms): (u64, f64)| format!("{}/s ({ms:.3} ms)", rate(n as f64 / (ms * 1e-3)));
            let _ = writeln!(
                o,
                "  {:<5} {:>24} {:>24} {:>22} {:>22} {:>22}",
                b.name(),
                atom(c.atomic_min32),
                atom(c.atomic_min64),
                copy,
                per_s(c.triangles),
                per_s(c.fragments)
            );
        }
        let w = 34;
        let _ = writeln!(
            o,
            "\nFrame time, ms: median [min-max] over frames (raster pass median; raster atomics/s as % of the roofline atomicMin rate)"
        );
        self.header(&mut o, w);
        let mut rows: Vec<(Backend, Variant)> = Vec::new();
        for (b, v, ..) in &self.cells {
            if !rows
                .iter()
                .any(|(x, y)| x == b && y.name == v.name && y.pipeline == v.pipeline)
            {
                rows.push((*b, *v));
            }
        }
        let mut skipped = Vec::new();
        for (b, v) in &rows {
            let _ = write!(
                o,
                "  {:<5} {:<lw$}",
                b.name(),
                row_label(v),
                lw = label_width()
            );
            for s in 0..self.views.len() {
                let text = match self.cell_at(*b, v, s) {
                    Some(Cell::Measured(st)) => {
                        let pct = self.ceiling(*b, v).map_or("-".into(), |c| {
                            format!("{:.0}%", 100.0 * st.atomic_rate() / c)
                        });
                        format!(
                            "{:.2} [{:.2}-{:.2}] ({:.2}; {pct})",
                            st.total.median, st.total.min, st.total.max, st.raster.median
                        )
                    }
                    Some(Cell::Skipped(why)) => {
                        if !skipped.contains(why) {
                            skipped.push(why.clone());
                        }
                        "skipped".into()
                    }
                    None => "-".into(),
                };
                let _ = write!(o, " {text:>w$}");
            }
            let _ = writeln!(o);
        }
        for why in skipped {
            let _ = writeln!(o, "  skipped: {why}");
        }
        if self
            .cells
            .iter()
            .any(|c| matches!(&c.3, Cell::Measured(st) if st.bounds.is_some()))
        {
            let all: Vec<&(Backend, Variant)> = rows.iter().collect();
            o += &self.metric_table(
                &all,
                "Frame time, ms, timed only at the frame's bounds: median over frames run again with no query between passes (ash; per-pass queries make a queue's passes wait for each other)",
                |st| st.bounds.map(|b| b.median as f32),
            );
        }
        o.push_str(&self.quality_table(&rows));
        for note in &self.notes {
            let _ = writeln!(o, "  {note}");
        }
        let _ = writeln!(
            o,
            "  The atomicMin roofline is random-address; raster atomics hit nearby texels, so a raster can exceed 100% of it."
        );
        let _ = writeln!(
            o,
            "  CPU frame time is the frame's wall clock (its queues run concurrently on threads); GPU frame time is first begin to last end of the per-pass GPU timestamps on ash (its queues overlap), their sum on wgpu (one queue).\n  Raster atomics are counted by an instrumented CPU run of the same configuration (subgroup width {}); GPU rows use that count.\n  Every row's per-pass medians are in bench.csv / bench.json (--out). Bench took {:.0} s.",
            self.subgroup, self.elapsed_s
        );
        o.push_str(&self.pass_tables());
        o
    }

    /// Per-pass medians of every row that runs a graph as shipped (no
    /// overrides: each pipeline as published), on the first backend, one
    /// column per view.
    fn pass_tables(&self) -> String {
        let json = self.json();
        let mut shipped: Vec<String> = Vec::new();
        for (_, v, ..) in &self.cells {
            let label = format!("{}: {}", v.pipeline, v.name);
            if v.overrides.is_empty() && !shipped.contains(&label) {
                shipped.push(label);
            }
        }
        let mut o = String::new();
        for label in shipped {
            // A pipeline whose every cell was skipped has no passes to show.
            if let Ok(md) = strandgraph::tables::bench::pass_table(&json, &label, &[]) {
                let _ = write!(o, "\n{md}");
            }
        }
        o
    }

    fn csv(&self) -> String {
        let mut o = String::from(
            "backend,device,pipeline,variant,view,pass,kind,frames,median_ms,min_ms,max_ms,raster_atomics,raster_atomics_per_s,fraction_of_ceiling\n",
        );
        let q = |s: &str| format!("\"{}\"", s.replace('"', "\"\""));
        for (b, v, s, cell) in &self.cells {
            let Cell::Measured(st) = cell else { continue };
            let frac = self
                .ceiling(*b, v)
                .map_or(String::new(), |c| format!("{:.4}", st.atomic_rate() / c));
            let head = format!(
                "{},{},{},{},{}",
                b.name(),
                q(self.device_name(*b)),
                q(v.pipeline),
                q(v.name),
                self.views[*s]
            );
            let mut line = |pass: &str, kind: &str, sp: &Spread, extra: &str| {
                let _ = writeln!(
                    o,
                    "{head},{},{},{},{:.4},{:.4},{:.4},{extra}",
                    q(pass),
                    q(kind),
                    st.frames,
                    sp.median,
                    sp.min,
                    sp.max
                );
            };
            line("frame", "", &st.total, ",,");
            let raster_extra = format!("{},{:.0},{frac}", st.raster_atomics, st.atomic_rate());
            line("raster (sum)", "", &st.raster, &raster_extra);
            for p in &st.passes {
                line(&p.name, &p.kind, &p.spread, ",,");
            }
        }
        o
    }

    fn json(&self) -> Value {
        let cells: Vec<Value> = self
            .cells
            .iter()
            .map(|(b, v, s, cell)| {
                let mut j = json!({
                    "backend": b.name(),
                    "pipeline": v.pipeline,
                    "variant": v.name,
                    "graph": v.graph,
                    "overrides": v.overrides,
                    "view": self.views[*s],
                    "scene": self.scenes[*s].display().to_string(),
                });
                match cell {
                    Cell::Skipped(why) => j["skipped"] = json!(why),
                    Cell::Measured(st) => {
                        j["frames"] = json!(st.frames);
                        if let Some(f) = st.flip {
                            j["flip"] = json!(f);
                            j["flip_reference"] = json!(quality::reference_graph(v.pipeline));
                        }
                        if st.flip_frames.len() > 1 {
                            j["flip_frames"] = json!(st.flip_frames);
                        }
                        if let Some(e) = st.coverage_error {
                            j["coverage_error"] = json!(e);
                        }
                        if let Some(t) = st.temporal {
                            j["flicker"] = json!(t.flicker);
                            j["reference_motion"] = json!(t.reference_motion);
                        }
                        if let Some(p) = &st.pictures {
                            j["picture"] = json!(p.picture);
                            j["flip_map"] = json!(p.flip_map);
                            j["reference_picture"] = json!(p.reference);
                        }
                        j["frame"] = st.total.json();
                        if let Some(b) = st.bounds {
                            j["frame_bounds"] = b.json();
                        }
                        if !st.levels.is_empty() {
                            j["levels"] = st.levels.iter().map(|l| l.json()).collect();
                        }
                        j["raster"] = st.raster.json();
                        j["raster_passes"] = json!(v.raster);
                        j["raster_atomics"] = json!(st.raster_atomics);
                        j["raster_atomics_source"] = json!("instrumented CPU run");
                        j["raster_atomics_per_s"] = json!(st.atomic_rate());
                        j["ceiling"] = json!(v.ceiling);
                        j["fraction_of_ceiling"] =
                            json!(self.ceiling(*b, v).map(|c| st.atomic_rate() / c));
                        j["passes"] = st
                            .passes
                            .iter()
                            .map(|p| {
                                let mut j = p.spread.json();
                                j["pass"] = json!(p.name);
                                j["kind"] = json!(p.kind);
                                if let Some((begin, end)) = p.span {
                                    j["begin_ms"] = json!(begin);
                                    j["end_ms"] = json!(end);
                                }
                                j
                            })
                            .collect();
                        j["per_frame_ms"] = json!(st.per_frame);
                    }
                }
                j
            })
            .collect();
        json!({
            "size": self.size,
            "frames": self.frames,
            "warmup": self.warmup,
            "cpu_subgroup_width": self.subgroup,
            "devices": self.devices.iter().map(|(b, d, notes)| json!({
                "backend": b.name(), "device": d, "clock": b.clock().describe(), "notes": notes,
            })).collect::<Vec<_>>(),
            "roofline": self.ceilings.iter().map(|(b, c)| json!({
                "backend": b.name(),
                "atomic_min32": {"ops": c.atomic_min32.0, "median_ms": c.atomic_min32.1, "ops_per_s": c.rate("atomic_min32")},
                "atomic_min64": {"ops": c.atomic_min64.0, "median_ms": c.atomic_min64.1, "ops_per_s": c.rate("atomic_min64")},
                "copy": {"bytes": c.copy.0, "median_ms": c.copy.1, "bytes_moved_per_s": 2.0 * c.copy.0 as f64 / (c.copy.1 * 1e-3)},
                "triangles": {"count": c.triangles.0, "median_ms": c.triangles.1, "per_s": c.rate("triangles")},
                "fragments": {"count": c.fragments.0, "median_ms": c.fragments.1, "per_s": c.rate("fragments")},
            })).collect::<Vec<_>>(),
            "cells": cells,
            "notes": self.notes,
            "elapsed_s": self.elapsed_s,
            "partial": self.partial,
        })
    }

    /// Writes bench.txt, bench.csv and bench.json into `dir`.
    pub fn write(&self, dir: &Path) -> Result<()> {
        std::fs::create_dir_all(dir)
            .into_diagnostic()
            .wrap_err_with(|| format!("creating {}", dir.display()))?;
        let json = serde_json::to_string_pretty(&self.json()).into_diagnostic()?;
        for (name, text) in [
            ("bench.txt", self.table()),
            ("bench.csv", self.csv()),
            ("bench.json", json),
        ] {
            let path = dir.join(name);
            std::fs::write(&path, text)
                .into_diagnostic()
                .wrap_err_with(|| format!("writing {}", path.display()))?;
        }
        Ok(())
    }
}
