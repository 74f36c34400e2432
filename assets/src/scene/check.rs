//! Everything about a scene that can be checked without reading the files it
//! names or running a generator: ranges, finite numbers, names, and the
//! counts that size what loading allocates. [`super::Scene::check`] runs it
//! on the parsed text (the fuzz target `scene_ron` on arbitrary text), and
//! [`super::Scene::load`] before it loads anything.

use super::{Camera, Environment, Fedora, GroomDesc, GroomSource, Light, LodSettings};
use super::{MeshDesc, MeshSource, SceneDesc};
use crate::loaders::Units;

/// The widest and tallest image a scene may ask for.
pub const MAX_RESOLUTION: u32 = 16384;
/// The finest procedural body (`Body(resolution: ..)`): its mesh has about
/// 0.75 × resolution² vertices.
pub const MAX_BODY_RESOLUTION: u32 = 1024;

/// What is wrong, and the text to point at: the `nth` occurrence (0-based)
/// of `needle` in the file, else its first, else line 1.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Problem {
    pub needle: String,
    pub nth: usize,
    pub message: String,
}

fn at(needle: impl Into<String>, message: impl Into<String>) -> Problem {
    Problem {
        needle: needle.into(),
        nth: 0,
        message: message.into(),
    }
}

/// 1-based (line, column) of the `nth` occurrence of `needle` in `text`,
/// else of its first, else (1, 1).
pub(super) fn locate(text: &str, needle: &str, nth: usize) -> (usize, usize) {
    if needle.is_empty() {
        return (1, 1);
    }
    let mut found = text.match_indices(needle).map(|(i, _)| i);
    let first = found.next();
    let nth = if nth == 0 { first } else { found.nth(nth - 1) };
    let Some(at) = nth.or(first) else {
        return (1, 1);
    };
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let col = before.chars().rev().take_while(|&c| c != '\n').count() + 1;
    (line, col)
}

fn finite(values: &[f32]) -> bool {
    values.iter().all(|v| v.is_finite())
}

/// The mesh's or groom's name as the scene file quotes it (the needle for
/// its errors).
fn quoted(name: &str) -> String {
    format!("{name:?}")
}

pub(super) fn check(desc: &SceneDesc) -> Result<(), Problem> {
    let (w, h) = desc.resolution;
    if w == 0 || h == 0 || w > MAX_RESOLUTION || h > MAX_RESOLUTION {
        return Err(at(
            "resolution",
            format!("resolution {w}x{h} is out of range (1..={MAX_RESOLUTION} each)"),
        ));
    }
    camera(&desc.camera).map_err(|m| at("camera", format!("camera: {m}")))?;
    for (i, l) in desc.lights.iter().enumerate() {
        light(l).map_err(|m| at("lights", format!("light {i}: {m}")))?;
    }
    if let Some(e) = &desc.environment {
        environment(e).map_err(|m| at("environment", format!("environment: {m}")))?;
    }
    for (i, m) in desc.meshes.iter().enumerate() {
        let earlier = desc.meshes[..i].iter().filter(|o| o.name == m.name).count();
        if earlier > 0 {
            return Err(Problem {
                needle: quoted(&m.name),
                nth: earlier,
                message: format!("mesh name {:?} is used twice", m.name),
            });
        }
        mesh(m).map_err(|e| at(quoted(&m.name), format!("mesh {:?}: {e}", m.name)))?;
    }
    for g in &desc.grooms {
        if let Some(p) = &g.parent
            && !desc.meshes.iter().any(|m| &m.name == p)
        {
            return Err(at(
                format!("parent: {}", quoted(p)),
                format!("groom {:?}: no mesh named {p:?}", g.name),
            ));
        }
        groom(g).map_err(|e| at(quoted(&g.name), format!("groom {:?}: {e}", g.name)))?;
    }
    if let Some(a) = &desc.animation {
        super::animation::check(a, desc)
            .map_err(|(needle, m)| at(needle, format!("animation: {m}")))?;
    }
    Ok(())
}

fn camera(c: &Camera) -> Result<(), String> {
    let fov = match *c {
        Camera::LookAt {
            position,
            target,
            fov_deg,
        } => {
            if !finite(&position) || !finite(&target) {
                return Err("position and target must be finite".into());
            }
            if position == target {
                return Err("position and target are the same point".into());
            }
            fov_deg
        }
        Camera::Orbit {
            target,
            distance,
            yaw_deg,
            pitch_deg,
            fov_deg,
        } => {
            if !finite(&target) || !finite(&[yaw_deg, pitch_deg]) {
                return Err("target, yaw_deg and pitch_deg must be finite".into());
            }
            if !(distance.is_finite() && distance > 0.0) {
                return Err(format!("distance = {distance} must be finite and > 0"));
            }
            fov_deg
        }
    };
    if !(fov > 0.0 && fov < 180.0) {
        return Err(format!("fov_deg = {fov} must be in (0, 180)"));
    }
    Ok(())
}

fn colour_and_intensity(color: &[f32; 3], intensity: f32) -> Result<(), String> {
    if !color
        .iter()
        .chain([&intensity])
        .all(|v| v.is_finite() && *v >= 0.0)
    {
        return Err("color and intensity must be finite and >= 0".into());
    }
    Ok(())
}

fn light(l: &Light) -> Result<(), String> {
    match l {
        Light::Directional {
            direction,
            color,
            intensity,
        } => {
            if !finite(direction) || direction.iter().all(|&v| v == 0.0) {
                return Err("direction must be finite and not zero".into());
            }
            colour_and_intensity(color, *intensity)
        }
        Light::Point {
            position,
            color,
            intensity,
        } => {
            if !finite(position) {
                return Err("position must be finite".into());
            }
            colour_and_intensity(color, *intensity)
        }
    }
}

fn environment(e: &Environment) -> Result<(), String> {
    colour_and_intensity(&e.color, e.intensity)
}

fn units(u: &Units) -> Result<(), String> {
    match *u {
        Units::Scale(s) if !(s.is_finite() && s > 0.0) => {
            Err(format!("units Scale({s}) must be finite and > 0"))
        }
        _ => Ok(()),
    }
}

fn mesh(m: &MeshDesc) -> Result<(), String> {
    match &m.source {
        MeshSource::Head(p) => {
            if p.scalp
                .is_some_and(|c| !c.iter().all(|v| (0.0..=1.0).contains(v)))
            {
                return Err("scalp is a linear RGB albedo in 0..=1".into());
            }
        }
        MeshSource::Body(p) => {
            if p.resolution > MAX_BODY_RESOLUTION {
                return Err(format!(
                    "resolution = {} must be at most {MAX_BODY_RESOLUTION}",
                    p.resolution
                ));
            }
            if !p.half_extents.iter().all(|v| v.is_finite() && *v > 0.0) {
                return Err("half_extents must be finite and > 0".into());
            }
        }
        MeshSource::File { units: u, .. } => units(u)?,
    }
    if !m.transform.is_finite() {
        return Err("bad transform".into());
    }
    Ok(())
}

fn lod(l: &LodSettings) -> Result<(), String> {
    if !(0.0..=1.0).contains(&l.min_fraction) {
        return Err(format!(
            "lod: min_fraction = {} must be in 0..=1",
            l.min_fraction
        ));
    }
    if !(l.lambda.is_finite() && l.lambda >= 0.0) {
        return Err(format!(
            "lod: lambda = {} must be finite and >= 0",
            l.lambda
        ));
    }
    Ok(())
}

fn fedora(f: &Fedora) -> Result<(), String> {
    let all = [f.box_min, f.box_max, f.sphere_center].concat();
    if !(finite(&all) && f.sphere_radius.is_finite() && f.sphere_radius >= 0.0) {
        return Err("fedora: every number must be finite (sphere_radius >= 0)".into());
    }
    Ok(())
}

fn groom(g: &GroomDesc) -> Result<(), String> {
    g.material
        .validate()
        .map_err(|m| format!("material: {m}"))?;
    g.patches
        .unwrap_or_default()
        .validate()
        .map_err(|m| format!("patches: {m}"))?;
    if let Some(h) = &g.hair_mesh {
        h.validate().map_err(|m| format!("hair_mesh: {m}"))?;
    }
    lod(&g.lod)?;
    if let Some(f) = &g.fedora {
        fedora(f)?;
    }
    match &g.source {
        GroomSource::Procedural(params) | GroomSource::HairMesh(params) => {
            params.validate()?;
            if g.parent.is_none() {
                return Err("a procedural groom needs a parent mesh".into());
            }
            if matches!(g.source, GroomSource::HairMesh(_)) && g.hair_mesh.is_none() {
                return Err(
                    "a HairMesh source needs `hair_mesh: (bundles: .., layers: ..)`".into(),
                );
            }
        }
        GroomSource::File {
            units: u,
            thickness,
            ..
        } => {
            units(u)?;
            if thickness.is_some_and(|t| !(t.is_finite() && t > 0.0)) {
                return Err("thickness must be finite and > 0".into());
            }
        }
    }
    if !g.transform.is_finite() {
        return Err("bad transform".into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_finds_the_nth_occurrence_by_characters() {
        let text = "a\n  \"héad\" x \"héad\"\n";
        assert_eq!(locate(text, "\"héad\"", 0), (2, 3));
        assert_eq!(locate(text, "\"héad\"", 1), (2, 12));
        // Past the last occurrence: the first; absent or empty: line 1.
        assert_eq!(locate(text, "\"héad\"", 5), (2, 3));
        assert_eq!(locate(text, "nose", 0), (1, 1));
        assert_eq!(locate(text, "", 0), (1, 1));
    }
}
