//! What the report reads: `bench.json` as `strandgraph bench --pictures`
//! writes it (src/bench_cmd/report.rs), grouped into one section per view
//! and backend, with the checks that the pictures it names are there.

use miette::{IntoDiagnostic, Result, WrapErr, miette};
use serde::{Deserialize, Serialize};
use std::path::{Component, Path};

#[derive(Debug, Deserialize)]
pub struct Bench {
    pub size: String,
    pub frames: usize,
    pub warmup: usize,
    #[serde(default)]
    pub devices: Vec<Device>,
    pub cells: Vec<Cell>,
    #[serde(default)]
    pub notes: Vec<String>,
    pub elapsed_s: Option<f64>,
    /// Written by `report --crop`: the views whose pictures are crops.
    #[serde(default)]
    pub crops: Vec<CropNote>,
    /// Written by `report --jpeg`: the pictures' JPEG quality.
    pub jpeg_quality: Option<u8>,
    /// A bench cut short: the rows it finished.
    #[serde(default)]
    pub partial: bool,
}

/// A view whose pictures are the `width`x`height` rectangle at (`x`, `y`)
/// of the bench's frames, which were `frame_width`x`frame_height`.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Serialize)]
pub struct CropNote {
    pub view: String,
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    pub frame_width: u32,
    pub frame_height: u32,
}

#[derive(Debug, Deserialize)]
pub struct Device {
    pub backend: String,
    pub device: String,
    #[serde(default)]
    pub clock: String,
}

/// Median, min and max over frames; `null` in the JSON (an empty or
/// non-finite spread) reads as `None`.
#[derive(Debug, Deserialize)]
pub struct Spread {
    pub median_ms: Option<f64>,
    pub min_ms: Option<f64>,
    pub max_ms: Option<f64>,
}

#[derive(Debug, Deserialize)]
pub struct Pass {
    pub pass: String,
    pub median_ms: Option<f64>,
}

/// One row at one view on one backend: measured, or skipped with why.
#[derive(Debug, Deserialize)]
pub struct Cell {
    pub backend: String,
    pub pipeline: String,
    pub variant: String,
    pub view: String,
    #[serde(default)]
    pub scene: String,
    pub skipped: Option<String>,
    pub frame: Option<Spread>,
    pub raster: Option<Spread>,
    pub flip: Option<f64>,
    /// The reference graph FLIP is measured against
    /// (`scenes/graphs/lipp_reference.ron`); pipelines may share one.
    pub flip_reference: Option<String>,
    /// Mean |alpha − reference alpha| over the pixels with hair in either
    /// (compare::coverage_error).
    pub coverage_error: Option<f64>,
    /// An animated scene's mean FLIP per timed frame (`flip` is their mean).
    #[serde(default)]
    pub flip_frames: Vec<f64>,
    /// An animated scene's flicker against its reference (compare::Temporal).
    pub flicker: Option<f64>,
    #[serde(default)]
    pub passes: Vec<Pass>,
    pub picture: Option<String>,
    pub flip_map: Option<String>,
    pub reference_picture: Option<String>,
}

impl Cell {
    pub fn label(&self) -> String {
        format!("{}: {}", self.pipeline, self.variant)
    }
    pub fn measured(&self) -> bool {
        self.skipped.is_none()
    }
    /// Median frame time in ms, if measured.
    pub fn ms(&self) -> Option<f64> {
        self.frame.as_ref().and_then(|f| f.median_ms)
    }
    /// The picture files of this cell that the page shows: a measured
    /// cell's picture, its reference, and its FLIP map where it has both.
    pub fn shown(&self) -> Vec<&str> {
        if !self.measured() {
            return Vec::new();
        }
        let map = self
            .flip_map
            .as_deref()
            .filter(|_| self.reference_picture.is_some());
        [
            self.picture.as_deref(),
            map,
            self.reference_picture.as_deref(),
        ]
        .into_iter()
        .flatten()
        .collect()
    }
    /// What the cell is judged against: its reference graph, else (a
    /// bench.json from before `flip_reference`) its reference picture.
    pub fn reference_key(&self) -> Option<&str> {
        self.flip_reference
            .as_deref()
            .or(self.reference_picture.as_deref())
    }
    /// The key of the reference a measured cell is judged against (`""`
    /// where it has a FLIP but names none); `None` without a reference.
    pub fn judged_by(&self) -> Option<&str> {
        let judged = self.measured() && (self.flip.is_some() || self.reference_picture.is_some());
        judged.then(|| self.reference_key().unwrap_or(""))
    }
    /// The FLIP map the page shows with the cell's reference.
    pub fn map_and_reference(&self) -> Option<(&str, &str)> {
        Some((
            self.flip_map.as_deref()?,
            self.reference_picture.as_deref()?,
        ))
    }
}

/// The cells of one view on one backend, in the bench's row order.
pub struct Section<'a> {
    pub view: &'a str,
    pub scene: &'a str,
    pub backend: &'a str,
    pub device: Option<&'a Device>,
    pub cells: Vec<&'a Cell>,
    /// Where the view's pictures are a crop of the frame.
    pub crop: Option<&'a CropNote>,
}

impl Section<'_> {
    /// `far-cpu`: the section's anchor.
    pub fn id(&self) -> String {
        let slug = |s: &str| -> String {
            s.chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
                .collect()
        };
        format!("{}-{}", slug(self.view), slug(self.backend))
    }
    /// Each reference the measured rows are judged against, once, in row
    /// order: pipelines sharing a reference graph share its entry.
    pub fn references(&self) -> Vec<Reference<'_>> {
        let mut out: Vec<Reference> = Vec::new();
        for c in &self.cells {
            let Some(key) = c.judged_by() else {
                continue;
            };
            let at = match out.iter().position(|r| r.key == key) {
                Some(i) => i,
                None => {
                    out.push(Reference {
                        key,
                        picture: None,
                        pipelines: Vec::new(),
                    });
                    out.len() - 1
                }
            };
            let r = &mut out[at];
            r.picture = r.picture.or(c.reference_picture.as_deref());
            if !r.pipelines.contains(&c.pipeline.as_str()) {
                r.pipelines.push(c.pipeline.as_str());
            }
        }
        out
    }
}

/// One reference of a section: the graph (or picture) that identifies
/// it, the picture it rendered, and the pipelines judged against it.
pub struct Reference<'a> {
    pub key: &'a str,
    pub picture: Option<&'a str>,
    pub pipelines: Vec<&'a str>,
}

impl Reference<'_> {
    /// The graph's name (`lipp_reference`), or the picture's.
    pub fn name(&self) -> &str {
        if self.key.is_empty() {
            return "reference";
        }
        Path::new(self.key)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or(self.key)
    }
    /// `lipp_reference (Lipp, HW strands, HW mesh)`.
    pub fn label(&self) -> String {
        format!("{} ({})", self.name(), self.pipelines.join(", "))
    }
}

/// Reads and parses `path`.
pub fn load(path: &Path) -> Result<Bench> {
    let text = std::fs::read_to_string(path)
        .into_diagnostic()
        .wrap_err_with(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| {
        miette!(
            "{}: not a bench.json as `strandgraph bench --out` writes it: {e}",
            path.display()
        )
    })
}

/// The views of `b`'s cells, in the order they first appear.
pub fn views(b: &Bench) -> Vec<&str> {
    let mut views: Vec<&str> = Vec::new();
    for c in &b.cells {
        if !views.contains(&c.view.as_str()) {
            views.push(c.view.as_str());
        }
    }
    views
}

/// Views in the order they first appear, each with the backends in the
/// order of `devices` (then of first appearance).
pub fn sections(b: &Bench) -> Vec<Section<'_>> {
    let views = views(b);
    let mut keys: Vec<(&str, &str)> = Vec::new();
    for c in &b.cells {
        let key = (c.view.as_str(), c.backend.as_str());
        if !keys.contains(&key) {
            keys.push(key);
        }
    }
    // A backend without a device line (it never opened) goes last.
    let rank = |backend: &str| {
        b.devices
            .iter()
            .position(|d| d.backend == backend)
            .unwrap_or(usize::MAX)
    };
    // Stable: backends without a device keep their order of appearance.
    keys.sort_by_key(|(v, backend)| (views.iter().position(|x| x == v), rank(backend)));
    keys.into_iter()
        .map(|(view, backend)| {
            let cells: Vec<&Cell> = b
                .cells
                .iter()
                .filter(|c| c.view == view && c.backend == backend)
                .collect();
            Section {
                view,
                scene: cells.first().map_or("", |c| c.scene.as_str()),
                backend,
                device: b.devices.iter().find(|d| d.backend == backend),
                cells,
                crop: b.crops.iter().find(|c| c.view == view),
            }
        })
        .collect()
}

/// A picture path from the JSON, relative and inside its directory (the
/// page links it as is, and `--from` copies it).
fn check_relative(json: &Path, rel: &str) -> Result<()> {
    let inside = Path::new(rel)
        .components()
        .all(|c| matches!(c, Component::Normal(_)));
    if rel.is_empty() || !inside {
        return Err(miette!(
            "{}: picture path {rel:?} is not a relative path inside the bench's directory",
            json.display()
        ));
    }
    Ok(())
}

/// Every measured cell names its picture, and every file named exists
/// next to `json`.
pub fn check_pictures(b: &Bench, json: &Path) -> Result<()> {
    let dir = json.parent().unwrap_or(Path::new("."));
    let measured: Vec<&Cell> = b.cells.iter().filter(|c| c.measured()).collect();
    if measured.is_empty() {
        return Err(miette!(
            "{}: no measured cells (every cell was skipped): nothing to show",
            json.display()
        ));
    }
    if let Some(c) = measured.iter().find(|c| c.picture.is_none()) {
        return Err(miette!(
            help = "run `strandgraph bench --out DIR --pictures` (or `strandgraph report`, which does)",
            "{}: the cell {} at {} on {} has no `picture`: the bench ran without --pictures",
            json.display(),
            c.label(),
            c.view,
            c.backend
        ));
    }
    for c in &measured {
        for rel in c.shown() {
            check_relative(json, rel)?;
            if !dir.join(rel).is_file() {
                return Err(miette!(
                    "{}: {} (of {} at {} on {}) is missing",
                    json.display(),
                    dir.join(rel).display(),
                    c.label(),
                    c.view,
                    c.backend
                ));
            }
        }
    }
    Ok(())
}

/// Which of `points` (time, error) no other point beats on both (lower
/// or equal on each, lower on one): the Pareto frontier.
pub fn frontier(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(t, e)| {
            !points
                .iter()
                .any(|&(t2, e2)| t2 <= t && e2 <= e && (t2 < t || e2 < e))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frontier_keeps_the_undominated() {
        let pts = [(1.0, 0.5), (2.0, 0.2), (3.0, 0.3), (2.0, 0.2), (4.0, 0.1)];
        assert_eq!(frontier(&pts), [true, true, false, true, true]);
    }

    #[test]
    fn pipelines_sharing_a_reference_graph_share_one_reference() {
        let cell = |pipeline: &str, graph: &str, picture: &str| {
            format!(
                r#"{{"backend":"ash","pipeline":"{pipeline}","variant":"v","view":"far","flip":0.1,
                "flip_reference":"scenes/graphs/{graph}.ron","reference_picture":"{picture}"}}"#
            )
        };
        let json = format!(
            r#"{{"size":"s","frames":1,"warmup":0,"cells":[{},{},{},{}]}}"#,
            cell("Kulikov", "kulikov_reference", "k.png"),
            cell("Lipp", "lipp_reference", "l.png"),
            cell("HW strands", "lipp_reference", "hw.png"),
            cell("Lipp", "lipp_reference", "l.png")
        );
        let b: Bench = serde_json::from_str(&json).unwrap();
        let secs = sections(&b);
        let refs = secs[0].references();
        let labels: Vec<String> = refs.iter().map(Reference::label).collect();
        assert_eq!(
            labels,
            [
                "kulikov_reference (Kulikov)",
                "lipp_reference (Lipp, HW strands)"
            ]
        );
        assert_eq!(refs[1].picture, Some("l.png"));
    }

    #[test]
    fn a_bench_without_pictures_is_refused_with_the_reason() {
        let json = r#"{"size":"160x90","frames":1,"warmup":0,"cells":[
            {"backend":"cpu","pipeline":"Kulikov","variant":"all","view":"far",
             "frame":{"median_ms":1.0,"min_ms":1.0,"max_ms":1.0}}]}"#;
        let b: Bench = serde_json::from_str(json).unwrap();
        let e = check_pictures(&b, Path::new("x/bench.json")).unwrap_err();
        assert!(format!("{e}").contains("without --pictures"), "{e}");
    }

    #[test]
    fn picture_paths_must_stay_inside() {
        let p = Path::new("b/bench.json");
        assert!(check_relative(p, "pictures/cpu/far/a.png").is_ok());
        assert!(check_relative(p, "../etc/passwd").is_err());
        assert!(check_relative(p, "/tmp/a.png").is_err());
    }

    #[test]
    fn sections_go_view_then_backend() {
        let cell = |v: &str, b: &str| {
            format!(
                r#"{{"backend":"{b}","pipeline":"P","variant":"v","view":"{v}","skipped":"x"}}"#
            )
        };
        let json = format!(
            r#"{{"size":"s","frames":1,"warmup":0,"devices":[{{"backend":"wgpu","device":"d"}},{{"backend":"cpu","device":"c"}}],"cells":[{},{},{},{}]}}"#,
            cell("close", "cpu"),
            cell("far", "cpu"),
            cell("close", "wgpu"),
            cell("far", "wgpu")
        );
        let b: Bench = serde_json::from_str(&json).unwrap();
        let ids: Vec<String> = sections(&b).iter().map(Section::id).collect();
        assert_eq!(ids, ["close-wgpu", "close-cpu", "far-wgpu", "far-cpu"]);
    }
}
