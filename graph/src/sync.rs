//! Synchronisation: stage, access and layout of every access, so a Vulkan
//! backend can turn each dependency into a `VkDependencyInfo` barrier and
//! each cross-queue dependency into a semaphore wait.
//!
//! Flag names mirror `VK_PIPELINE_STAGE_2_*` and `VK_ACCESS_2_*` so the ash
//! backend maps them one to one; `graph/` itself depends on no graphics API.

use crate::deps::{Edge, Hazard};
use crate::resolve::{Access, Graph, Pass, PassId, ResourceId};
use crate::schema::{AccessMode, Usage};
use serde::Serialize;

bitflags::bitflags! {
    /// Pipeline stages (`VkPipelineStageFlags2`).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
    pub struct Stages: u32 {
        const DRAW_INDIRECT = 1 << 0;
        /// The shaders before rasterization: vertex, or task and mesh.
        const VERTEX_SHADER = 1 << 1;
        const FRAGMENT_SHADER = 1 << 2;
        const EARLY_FRAGMENT_TESTS = 1 << 3;
        const LATE_FRAGMENT_TESTS = 1 << 4;
        const COLOR_ATTACHMENT_OUTPUT = 1 << 5;
        const COMPUTE_SHADER = 1 << 6;
        const COPY = 1 << 7;
    }
}

bitflags::bitflags! {
    /// Memory accesses (`VkAccessFlags2`).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
    pub struct Accesses: u32 {
        const INDIRECT_COMMAND_READ = 1 << 0;
        const UNIFORM_READ = 1 << 1;
        const SHADER_SAMPLED_READ = 1 << 2;
        const SHADER_STORAGE_READ = 1 << 3;
        const SHADER_STORAGE_WRITE = 1 << 4;
        const COLOR_ATTACHMENT_READ = 1 << 5;
        const COLOR_ATTACHMENT_WRITE = 1 << 6;
        const DEPTH_STENCIL_ATTACHMENT_READ = 1 << 7;
        const DEPTH_STENCIL_ATTACHMENT_WRITE = 1 << 8;
        const TRANSFER_READ = 1 << 9;
        const TRANSFER_WRITE = 1 << 10;
    }
}

impl Accesses {
    pub fn writes(self) -> bool {
        self.intersects(
            Accesses::SHADER_STORAGE_WRITE
                | Accesses::COLOR_ATTACHMENT_WRITE
                | Accesses::DEPTH_STENCIL_ATTACHMENT_WRITE
                | Accesses::TRANSFER_WRITE,
        )
    }
}

/// Image layouts (`VkImageLayout`); buffers have none.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub enum Layout {
    Undefined,
    General,
    ShaderReadOnly,
    ColorAttachment,
    DepthAttachment,
    DepthReadOnly,
    TransferSrc,
    TransferDst,
}

/// How one pass touches one resource.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct AccessPoint {
    pub stages: Stages,
    pub access: Accesses,
    /// `None` for buffers.
    pub layout: Option<Layout>,
}

fn shader_stages(pass: &Pass) -> Stages {
    if pass.is_raster() {
        Stages::VERTEX_SHADER | Stages::FRAGMENT_SHADER
    } else {
        Stages::COMPUTE_SHADER
    }
}

fn point(pass: &Pass, a: &Access, is_image: bool) -> AccessPoint {
    let (stages, access, layout) = match (a.usage, a.mode) {
        (Usage::Storage, AccessMode::Read) => (
            shader_stages(pass),
            Accesses::SHADER_STORAGE_READ,
            Layout::General,
        ),
        (Usage::Storage, _) => (
            shader_stages(pass),
            Accesses::SHADER_STORAGE_READ | Accesses::SHADER_STORAGE_WRITE,
            Layout::General,
        ),
        (Usage::Uniform, _) => (shader_stages(pass), Accesses::UNIFORM_READ, Layout::General),
        (Usage::Sampled, _) => (
            shader_stages(pass),
            Accesses::SHADER_SAMPLED_READ,
            Layout::ShaderReadOnly,
        ),
        (Usage::Indirect, _) => (
            Stages::DRAW_INDIRECT,
            Accesses::INDIRECT_COMMAND_READ,
            Layout::General,
        ),
        // Colour writes blend, so they read what is there too.
        (Usage::Color, _) => (
            Stages::COLOR_ATTACHMENT_OUTPUT,
            Accesses::COLOR_ATTACHMENT_READ | Accesses::COLOR_ATTACHMENT_WRITE,
            Layout::ColorAttachment,
        ),
        (Usage::Depth, AccessMode::Read) => (
            Stages::EARLY_FRAGMENT_TESTS | Stages::LATE_FRAGMENT_TESTS,
            Accesses::DEPTH_STENCIL_ATTACHMENT_READ,
            Layout::DepthReadOnly,
        ),
        (Usage::Depth, _) => (
            Stages::EARLY_FRAGMENT_TESTS | Stages::LATE_FRAGMENT_TESTS,
            Accesses::DEPTH_STENCIL_ATTACHMENT_READ | Accesses::DEPTH_STENCIL_ATTACHMENT_WRITE,
            Layout::DepthAttachment,
        ),
        (Usage::Copy, AccessMode::Read) => {
            (Stages::COPY, Accesses::TRANSFER_READ, Layout::TransferSrc)
        }
        (Usage::Copy, _) => (Stages::COPY, Accesses::TRANSFER_WRITE, Layout::TransferDst),
    };
    AccessPoint {
        stages,
        access,
        layout: is_image.then_some(layout),
    }
}

/// The combined access of a pass to a resource's memory (a pass may read and
/// write it in place, or under two versions).
pub fn access_point(g: &Graph, p: PassId, r: ResourceId) -> AccessPoint {
    let pass = &g.passes[p];
    let r = g.physical(r);
    let is_image = g.resources[r].decl.is_image();
    let mut points = pass
        .accesses
        .iter()
        .filter(|a| g.physical(a.resource) == r)
        .map(|a| point(pass, a, is_image));
    let first = points.next().unwrap_or(AccessPoint {
        stages: Stages::empty(),
        access: Accesses::empty(),
        layout: None,
    });
    points.fold(first, |acc, p| AccessPoint {
        stages: acc.stages | p.stages,
        access: acc.access | p.access,
        // Two different layouts in one pass: only GENERAL serves both.
        layout: if acc.layout == p.layout {
            acc.layout
        } else {
            Some(Layout::General)
        },
    })
}

/// One dependency with what a barrier needs to know.
#[derive(Debug, Clone, Serialize)]
pub struct Dependency {
    pub from: PassId,
    pub to: PassId,
    /// The declared resource whose memory the barrier covers.
    pub resource: ResourceId,
    /// The name the passes use for it: `resource` itself or one of its versions.
    pub version: ResourceId,
    pub hazard: Hazard,
    pub src: AccessPoint,
    pub dst: AccessPoint,
    /// The passes run on different queues: a semaphore orders them, and an
    /// exclusive-sharing resource needs a queue-family ownership transfer.
    pub cross_queue: bool,
}

pub fn dependencies(g: &Graph, edges: &[Edge], live: &[bool]) -> Vec<Dependency> {
    edges
        .iter()
        .filter(|e| live[e.from] && live[e.to])
        .map(|e| Dependency {
            from: e.from,
            to: e.to,
            resource: g.physical(e.resource),
            version: e.resource,
            hazard: e.hazard,
            src: access_point(g, e.from, e.resource),
            dst: access_point(g, e.to, e.resource),
            cross_queue: g.passes[e.from].queue != g.passes[e.to].queue,
        })
        .collect()
}
