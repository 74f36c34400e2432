//! Animated scenes as frame sequences: each frame's inputs with the scene
//! posed at its time ([`strandgraph_assets::Scene::pose_at`]), so a session
//! run frame after frame keeps its history (the simulation's state, last
//! frame's positions for motion vectors) while the head and camera move.

use crate::frame::{Prepared, complete_upload};
use miette::Result;
use strandgraph_passes::layout::words_of;
use strandgraph_passes::sim::chains::{self, CHAIN_MODELS};
use strandgraph_passes::sim::upload::{self as sim, MODELS, REST, SDF};
use strandgraph_passes::upload::{SHADOW_SH, Upload, upload};

/// Inputs that do not depend on the pose: baked once, carried to every frame.
const CARRIED: [&str; 7] = [
    SHADOW_SH,
    SDF,
    REST,
    chains::CHAINS,
    chains::REST,
    chains::POINTS,
    chains::TANGENTS,
];

/// The inputs of frame `index` of a sequence at `fps`: the scene posed at
/// `index / fps` seconds, the simulation stepped by `1 / fps` (the first
/// frame starts it from the rest pose). Leaves `p.scene` in that pose.
pub fn frame_upload(p: &mut Prepared, index: u32, fps: f32) -> Result<Upload> {
    let time = index as f32 / fps;
    p.scene.pose_at(time);
    let (w, h) = (p.upload.quantities.width, p.upload.quantities.height);
    let mut up = upload(&p.scene, w, h);
    for name in CARRIED {
        if let Some(words) = p.upload.resources.get(name) {
            up.set(name, words.clone());
        }
    }
    // The simulation's records, posed (sim::repose).
    for name in [MODELS, CHAIN_MODELS] {
        if let Some(words) = p.upload.resources.get(name) {
            up.set(name, words.clone());
        }
    }
    sim::repose(&p.scene, &mut up);
    complete_upload(&p.plan, &p.scene, &mut up)?;
    let mut frame = up.frame.expect("upload sets the frame");
    frame.time = time;
    frame.delta_time = if index == 0 { 0.0 } else { 1.0 / fps };
    frame.sim_reset = u32::from(index == 0);
    up.set("frame", words_of(&[frame]));
    up.frame = Some(frame);
    Ok(up)
}

/// `up` as a frame of a running sequence at `fps` with nothing moving: the
/// simulation steps by `1 / fps` from the state it kept (a session's first
/// frame finds no state and starts from the rest pose). What the bench
/// times, so the solver's substeps are in every Kulikov frame.
pub fn running(up: &Upload, fps: f32) -> Upload {
    let mut up = up.clone();
    if let Some(mut frame) = up.frame {
        frame.delta_time = 1.0 / fps;
        frame.sim_reset = 0;
        up.set("frame", words_of(&[frame]));
        up.frame = Some(frame);
    }
    up
}

/// The inputs of `count` frames of `p`'s animation at `fps`, for timing
/// them back to back: the first frame's in full, each later one only what
/// changed since the frame before (the camera, the poses, the simulation's
/// per-frame record), so the uploads between frames stay small. `None` for
/// a scene without animation. Leaves the scene at rest.
pub fn animation_frames(p: &mut Prepared, count: usize, fps: f32) -> Result<Option<Vec<Upload>>> {
    if p.scene.desc.animation.is_none() {
        return Ok(None);
    }
    let mut frames = Vec::with_capacity(count);
    let mut last: Option<Upload> = None;
    for k in 0..count {
        let full = frame_upload(p, k as u32, fps)?;
        frames.push(match &last {
            None => full.clone(),
            Some(last) => changed(last, &full),
        });
        last = Some(full);
    }
    p.scene.pose_at(0.0);
    Ok(Some(frames))
}

/// `next` without the resources whose words equal `last`'s.
fn changed(last: &Upload, next: &Upload) -> Upload {
    let mut up = Upload {
        quantities: next.quantities,
        frame: next.frame,
        models: next.models.clone(),
        ..Upload::default()
    };
    for (name, words) in &next.resources {
        if last.resources.get(name) != Some(words) {
            up.set(name, words.clone());
        }
    }
    up
}
