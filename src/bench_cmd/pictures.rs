//! `bench --pictures`: every measured cell's last frame, its FLIP error
//! map and its pipeline's reference as PNG files under `OUT/pictures/`, so
//! `strandgraph report --from OUT/bench.json` can draw the page later from
//! the JSON alone (the H100 run comes back as files; the page is made here).

use super::Variant;
use super::quality::Judged;
use image::RgbaImage;
use miette::{IntoDiagnostic, Result, WrapErr};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use strandgraph::runner::Backend;

/// Where one cell's pictures went, relative to bench.json's directory
/// (always with `/`, as the HTML page links them).
#[derive(Debug, Clone)]
pub struct Saved {
    pub picture: String,
    /// The FLIP error map (magma); `None` without a reference.
    pub flip_map: Option<String>,
    pub reference: Option<String>,
}

/// A reference picture, and where it was written.
type Written = (RgbaImage, String);

/// Writes the pictures of one bench run under `out/pictures/`.
pub struct Saver {
    out: PathBuf,
    /// Paths taken so far, so two rows whose names slug alike stay apart.
    taken: BTreeSet<String>,
    /// The references of each (backend, view, pipeline), each written
    /// once: one, or more where rows simulate differently (a row's
    /// `simulate.*` overrides carry over to its reference).
    references: BTreeMap<(Backend, String, &'static str), Vec<Written>>,
}

/// `Kulikov: no sort` as `kulikov-no-sort`: file names that need no
/// escaping in a URL or a shell.
fn slug(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        match c {
            'a'..='z' | '0'..='9' => out.push(c),
            'A'..='Z' => out.push(c.to_ascii_lowercase()),
            '+' => out.push_str("-plus-"),
            _ => out.push('-'),
        }
    }
    let parts: Vec<&str> = out.split('-').filter(|p| !p.is_empty()).collect();
    parts.join("-")
}

impl Saver {
    pub fn new(out: &Path) -> Saver {
        Saver {
            out: out.to_path_buf(),
            taken: BTreeSet::new(),
            references: BTreeMap::new(),
        }
    }

    /// A free relative path `pictures/BACKEND/VIEW/STEM[-n].png`.
    fn claim(&mut self, backend: Backend, view: &str, stem: &str) -> String {
        let dir = format!("pictures/{}/{}", backend.name(), slug(view));
        let mut rel = format!("{dir}/{stem}.png");
        let mut n = 2;
        while self.taken.contains(&rel) {
            rel = format!("{dir}/{stem}-{n}.png");
            n += 1;
        }
        self.taken.insert(rel.clone());
        rel
    }

    /// Writes `image` to `rel` under the output directory.
    fn write(&self, rel: &str, image: &impl Png) -> Result<()> {
        let path = self.out.join(rel);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)
                .into_diagnostic()
                .wrap_err_with(|| format!("creating {}", dir.display()))?;
        }
        image
            .save_png(&path)
            .into_diagnostic()
            .wrap_err_with(|| format!("writing {}", path.display()))
    }

    /// Saves row `v`'s `picture` on `backend` at `view`, with its error map
    /// and (once per backend, view, pipeline and picture) its reference.
    pub fn save(
        &mut self,
        backend: Backend,
        view: &str,
        v: &Variant,
        picture: &RgbaImage,
        judged: Option<&Judged>,
    ) -> Result<Saved> {
        let stem = slug(&format!("{}: {}", v.pipeline, v.name));
        let rel = self.claim(backend, view, &stem);
        self.write(&rel, picture)?;
        let (mut flip_map, mut reference) = (None, None);
        if let Some(j) = judged {
            let map = self.claim(backend, view, &format!("{stem}-flip"));
            self.write(&map, &j.diff.error_map)?;
            flip_map = Some(map);
            reference = Some(self.reference(backend, view, v.pipeline, &j.reference.image)?);
        }
        Ok(Saved {
            picture: rel,
            flip_map,
            reference,
        })
    }

    /// The reference of `pipeline` at `view` on `backend`, written the first
    /// time it is asked for.
    fn reference(
        &mut self,
        backend: Backend,
        view: &str,
        pipeline: &'static str,
        image: &RgbaImage,
    ) -> Result<String> {
        let key = (backend, view.to_string(), pipeline);
        let mut known = self.references.get(&key).into_iter().flatten();
        if let Some((_, rel)) = known.find(|(seen, _)| seen == image) {
            return Ok(rel.clone());
        }
        let rel = self.claim(backend, view, &format!("reference-{}", slug(pipeline)));
        self.write(&rel, image)?;
        self.references
            .entry(key)
            .or_default()
            .push((image.clone(), rel.clone()));
        Ok(rel)
    }
}

/// The two picture types saved, as PNG.
trait Png {
    fn save_png(&self, path: &Path) -> image::ImageResult<()>;
}

impl Png for RgbaImage {
    fn save_png(&self, path: &Path) -> image::ImageResult<()> {
        self.save_with_format(path, image::ImageFormat::Png)
    }
}

impl Png for image::RgbImage {
    fn save_png(&self, path: &Path) -> image::ImageResult<()> {
        self.save_with_format(path, image::ImageFormat::Png)
    }
}

#[cfg(test)]
mod tests {
    use super::slug;

    #[test]
    fn slugs_are_url_safe_and_keep_plus_apart() {
        assert_eq!(slug("Kulikov: no sort"), "kulikov-no-sort");
        assert_eq!(
            slug("Lipp: SWR 1+F+L (as published)"),
            "lipp-swr-1-plus-f-plus-l-as-published"
        );
        assert_ne!(slug("SWR 1+L"), slug("SWR 1 L"));
    }
}
