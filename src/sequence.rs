//! Animated scenes as frame sequences: each frame's inputs with the scene
//! posed at its time ([`strandgraph_assets::Scene::pose_at`]), so a session
//! run frame after frame keeps its history (the simulation's state, last
//! frame's positions for motion vectors) while the head and camera move.

use crate::frame::{Prepared, complete_upload};
use miette::Result;
use strandgraph_passes::layout::words_of;
use strandgraph_passes::sim::upload::{self as sim, MODELS, REST, SDF};
use strandgraph_passes::upload::{SHADOW_SH, Upload, upload};

/// Inputs that do not depend on the pose: baked once, carried to every frame.
const CARRIED: [&str; 3] = [SHADOW_SH, SDF, REST];

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
    if let Some(models) = p
        .upload
        .resources
        .get(strandgraph_passes::sim::upload::MODELS)
    {
        up.set(strandgraph_passes::sim::upload::MODELS, models.clone());
        strandgraph_passes::sim::upload::repose(&p.scene, &mut up);
    }
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
