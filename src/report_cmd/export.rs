//! A run copied into the report's directory: the pictures the page shows
//! (cut by `--crop`, re-encoded by `--jpeg`) and bench.json with their
//! new paths, so `report --from` on the copy works again.

use super::crop::{self, CropArg, Crops};
use super::data::{self, Bench, CropNote};
use image::{DynamicImage, ImageFormat, RgbImage};
use miette::{IntoDiagnostic, Result, WrapErr, miette};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What `--crop` and `--jpeg` ask of the copy.
pub struct Options {
    pub crops: Crops,
    pub jpeg: Option<u8>,
}

impl Options {
    /// Whether the pictures change on the way (else they are copied).
    pub fn transforms(&self) -> bool {
        !self.crops.is_empty() || self.jpeg.is_some()
    }
}

/// One view's crop placed in its pictures.
struct Cut<'a> {
    arg: &'a CropArg,
    at: (u32, u32),
    size: (u32, u32),
}

fn dir_of(json: &Path) -> &Path {
    json.parent().unwrap_or(Path::new("."))
}

/// Copies the run of `json` (read as `bench`) into `out` as `opts` say.
pub fn export(bench: &Bench, json: &Path, out: &Path, opts: &Options) -> Result<()> {
    let from = dir_of(json);
    opts.crops
        .check_views(&data::views(bench), &json.display().to_string())?;
    let shown = shown(bench)?;
    let cuts = cuts(&shown, from, &opts.crops)?;
    let mut renamed: BTreeMap<&str, String> = BTreeMap::new();
    for (rel, view) in &shown {
        let new = target(rel, opts);
        if let Some((old, _)) = renamed.iter().find(|(_, n)| **n == new) {
            return Err(miette!(
                "{} and {} would both be copied to {new}",
                from.join(old).display(),
                from.join(rel).display()
            ));
        }
        let cut = cuts.get(*view);
        let (src, dst) = (from.join(rel), out.join(&new));
        write_picture(&src, &dst, cut, opts.jpeg)
            .wrap_err_with(|| format!("copying {} to {}", src.display(), dst.display()))?;
        renamed.insert(rel, new);
    }
    let notes = notes(bench, &cuts);
    rewrite_json(json, &out.join("bench.json"), &renamed, &notes, opts)?;
    warn_strays(out, &renamed);
    tracing::info!(from = %from.display(), to = %out.display(), pictures = renamed.len(), "copied the run's pictures");
    Ok(())
}

/// Each picture the page shows, once, with its view.
fn shown(bench: &Bench) -> Result<BTreeMap<&str, &str>> {
    let mut out: BTreeMap<&str, &str> = BTreeMap::new();
    for c in &bench.cells {
        for rel in c.shown() {
            match out.insert(rel, &c.view) {
                Some(v) if v != c.view => {
                    return Err(miette!(
                        "{rel} is a picture of both views {v:?} and {:?}: one file can't take two crops",
                        c.view
                    ));
                }
                _ => {}
            }
        }
    }
    Ok(out)
}

/// Each cropped view's crop, placed in its pictures (all of one size).
fn cuts<'a>(
    shown: &BTreeMap<&str, &str>,
    from: &Path,
    crops: &'a Crops,
) -> Result<BTreeMap<String, Cut<'a>>> {
    let mut out: BTreeMap<String, Cut<'a>> = BTreeMap::new();
    for (rel, view) in shown {
        let Some(arg) = crops.get(view) else { continue };
        let path = from.join(rel);
        let size = image::image_dimensions(&path)
            .into_diagnostic()
            .wrap_err_with(|| format!("reading the size of {}", path.display()))?;
        let at = crop::place(arg, rel, size)?;
        if let Some(cut) = out.get(*view)
            && cut.size != size
        {
            return Err(miette!(
                "--crop {}: the pictures of view {view:?} differ in size ({rel} is {}x{}, others {}x{}): \
                 one rectangle can't be the same place in each",
                arg.text,
                size.0,
                size.1,
                cut.size.0,
                cut.size.1
            ));
        }
        out.insert(view.to_string(), Cut { arg, at, size });
    }
    Ok(out)
}

/// `rel`'s path in the copy: `.jpg` with `--jpeg`, `.png` if cut only.
fn target(rel: &str, opts: &Options) -> String {
    let ext = match (opts.jpeg, opts.crops.is_empty()) {
        (Some(_), _) => "jpg",
        (None, false) => "png",
        (None, true) => return rel.to_string(),
    };
    let name_at = rel.rfind('/').map_or(0, |i| i + 1);
    let stem_end = rel[name_at..].rfind('.').map_or(rel.len(), |i| name_at + i);
    format!("{}.{ext}", &rel[..stem_end])
}

fn create_parent(path: &Path) -> Result<()> {
    match path.parent() {
        Some(dir) => std::fs::create_dir_all(dir)
            .into_diagnostic()
            .wrap_err_with(|| format!("creating {}", dir.display())),
        None => Ok(()),
    }
}

/// `src` to `dst`: copied as is, or decoded, cut and encoded.
fn write_picture(src: &Path, dst: &Path, cut: Option<&Cut>, jpeg: Option<u8>) -> Result<()> {
    create_parent(dst)?;
    if cut.is_none() && jpeg.is_none() {
        std::fs::copy(src, dst).into_diagnostic()?;
        return Ok(());
    }
    let mut img = image::open(src).into_diagnostic()?;
    if let Some(c) = cut {
        img = img.crop_imm(c.at.0, c.at.1, c.arg.rect.w, c.arg.rect.h);
    }
    match jpeg {
        Some(q) => write_jpeg(&img, dst, q),
        None => img
            .save_with_format(dst, ImageFormat::Png)
            .into_diagnostic(),
    }
}

/// `img` over black (as the page shows it) as a JPEG of quality `q`.
fn write_jpeg(img: &DynamicImage, dst: &Path, q: u8) -> Result<()> {
    let rgba = img.to_rgba8();
    let rgb = RgbImage::from_fn(rgba.width(), rgba.height(), |x, y| {
        let [r, g, b, a] = rgba.get_pixel(x, y).0;
        let over = |c: u8| ((u16::from(c) * u16::from(a) + 127) / 255) as u8;
        image::Rgb([over(r), over(g), over(b)])
    });
    let file = std::fs::File::create(dst).into_diagnostic()?;
    let mut w = std::io::BufWriter::new(file);
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut w, q)
        .encode_image(&rgb)
        .into_diagnostic()?;
    std::io::Write::flush(&mut w).into_diagnostic()
}

/// The crop of each view in the copy: this run's cut, composed with an
/// earlier one's where the pictures were crops already.
fn notes(bench: &Bench, cuts: &BTreeMap<String, Cut>) -> Vec<CropNote> {
    let mut out: Vec<CropNote> = Vec::new();
    for view in data::views(bench) {
        let earlier = bench.crops.iter().find(|c| c.view == view);
        match cuts.get(view) {
            Some(c) => out.push(crop::note(view, c.at, c.arg.rect, c.size, earlier)),
            None => out.extend(earlier.cloned()),
        }
    }
    out
}

/// bench.json as read, with the pictures' new paths (`null` for those
/// not copied) and the crops and JPEG quality of the copy.
fn rewrite_json(
    json: &Path,
    dst: &Path,
    renamed: &BTreeMap<&str, String>,
    notes: &[CropNote],
    opts: &Options,
) -> Result<()> {
    let text = std::fs::read_to_string(json)
        .into_diagnostic()
        .wrap_err_with(|| format!("reading {}", json.display()))?;
    let mut v: Value = serde_json::from_str(&text).into_diagnostic()?;
    for cell in v["cells"].as_array_mut().into_iter().flatten() {
        for key in ["picture", "flip_map", "reference_picture"] {
            if let Some(rel) = cell[key].as_str() {
                cell[key] = renamed.get(rel).map_or(Value::Null, |n| n.as_str().into());
            }
        }
    }
    v["crops"] = serde_json::to_value(notes).into_diagnostic()?;
    if let Some(q) = opts.jpeg {
        v["jpeg_quality"] = q.into();
    }
    let text = serde_json::to_string_pretty(&v).into_diagnostic()?;
    std::fs::write(dst, text + "\n")
        .into_diagnostic()
        .wrap_err_with(|| format!("writing {}", dst.display()))
}

/// Files under `out/pictures/` that the page does not name (an earlier
/// report's, say): said, not deleted.
fn warn_strays(out: &Path, renamed: &BTreeMap<&str, String>) {
    let mut files = Vec::new();
    walk(&out.join("pictures"), &mut files);
    let named: Vec<PathBuf> = renamed.values().map(|n| out.join(n)).collect();
    let strays: Vec<&PathBuf> = files.iter().filter(|f| !named.contains(f)).collect();
    if let Some(first) = strays.first() {
        tracing::warn!(
            count = strays.len(),
            first = %first.display(),
            "files under pictures/ that this report does not show (from an earlier one?)"
        );
    }
}

fn walk(dir: &Path, files: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let path = e.path();
        if path.is_dir() {
            walk(&path, files);
        } else {
            files.push(path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(crop: &[&str], jpeg: Option<u8>) -> Options {
        let args: Vec<CropArg> = crop.iter().map(|c| c.parse().unwrap()).collect();
        Options {
            crops: Crops::new(&args).unwrap(),
            jpeg,
        }
    }

    #[test]
    fn targets_change_extension_only_when_transcoded() {
        let rel = "pictures/cpu/far/kulikov-all.png";
        assert_eq!(target(rel, &opts(&[], None)), rel);
        assert_eq!(target(rel, &opts(&["4x4"], None)), rel);
        assert_eq!(
            target(rel, &opts(&[], Some(80))),
            "pictures/cpu/far/kulikov-all.jpg"
        );
        assert_eq!(
            target("pictures/a.b/c", &opts(&[], Some(80))),
            "pictures/a.b/c.jpg"
        );
    }
}
