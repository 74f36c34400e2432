//! The plan's sync section as Vulkan barriers, and nothing more.
//!
//! - A same-queue buffer dependency (`graph/src/sync.rs` `Dependency`)
//!   becomes one `VkBufferMemoryBarrier2` before its `to` pass, with the
//!   plan's stage and access masks.
//! - Images: a pass's accesses to an image run in *groups*: each write is a
//!   group, and the reads between two writes form one group, whose layout is
//!   the plan's layout when the readers agree, else one that serves them all
//!   (a depth image sampled and depth-tested: `DEPTH_STENCIL_READ_ONLY_OPTIMAL`;
//!   otherwise `GENERAL`). The transition into a write group is recorded
//!   before the writer (every earlier access happens before it); the
//!   transition into a read group right after the writer, on the writer's
//!   queue, before it signals, so readers on either queue find the layout
//!   in place without transitioning it twice. The masks are those of the
//!   plan's dependencies between the groups' passes.
//! - A cross-queue dependency is carried by the plan's sync point (a
//!   timeline semaphore; `submit.rs`), not a barrier: every resource is
//!   `VK_SHARING_MODE_CONCURRENT` when two queue families are in use
//!   (memory.rs says why), so no ownership transfer is needed.
//! - Aliasing: when a transient's bytes were another's earlier in the frame
//!   (the memory plan's placements), its first pass waits for the other's
//!   uses on the same queue (uses on the other queue are ordered by the sync
//!   points: `Lifetime::end` guarantees it). This barrier comes from the
//!   memory plan, which is part of the plan too.

use ash::vk;
use std::collections::BTreeMap;
use strandgraph_graph::Plan;
use strandgraph_graph::resolve::PassId;
use strandgraph_graph::schema::LifetimeClass;
use strandgraph_graph::sync::{AccessPoint, Accesses, Layout, Stages, access_point};

pub(crate) fn stages(s: Stages) -> vk::PipelineStageFlags2 {
    use vk::PipelineStageFlags2 as V;
    let mut out = V::NONE;
    for (bit, v) in [
        (Stages::DRAW_INDIRECT, V::DRAW_INDIRECT),
        (Stages::VERTEX_SHADER, V::VERTEX_SHADER),
        (Stages::FRAGMENT_SHADER, V::FRAGMENT_SHADER),
        (Stages::EARLY_FRAGMENT_TESTS, V::EARLY_FRAGMENT_TESTS),
        (Stages::LATE_FRAGMENT_TESTS, V::LATE_FRAGMENT_TESTS),
        (Stages::COLOR_ATTACHMENT_OUTPUT, V::COLOR_ATTACHMENT_OUTPUT),
        (Stages::COMPUTE_SHADER, V::COMPUTE_SHADER),
        (Stages::COPY, V::COPY),
    ] {
        if s.contains(bit) {
            out |= v;
        }
    }
    out
}

pub(crate) fn accesses(a: Accesses) -> vk::AccessFlags2 {
    use vk::AccessFlags2 as V;
    let mut out = V::NONE;
    for (bit, v) in [
        (Accesses::INDIRECT_COMMAND_READ, V::INDIRECT_COMMAND_READ),
        (Accesses::UNIFORM_READ, V::UNIFORM_READ),
        (Accesses::SHADER_SAMPLED_READ, V::SHADER_SAMPLED_READ),
        (Accesses::SHADER_STORAGE_READ, V::SHADER_STORAGE_READ),
        (Accesses::SHADER_STORAGE_WRITE, V::SHADER_STORAGE_WRITE),
        (Accesses::COLOR_ATTACHMENT_READ, V::COLOR_ATTACHMENT_READ),
        (Accesses::COLOR_ATTACHMENT_WRITE, V::COLOR_ATTACHMENT_WRITE),
        (
            Accesses::DEPTH_STENCIL_ATTACHMENT_READ,
            V::DEPTH_STENCIL_ATTACHMENT_READ,
        ),
        (
            Accesses::DEPTH_STENCIL_ATTACHMENT_WRITE,
            V::DEPTH_STENCIL_ATTACHMENT_WRITE,
        ),
        (Accesses::TRANSFER_READ, V::TRANSFER_READ),
        (Accesses::TRANSFER_WRITE, V::TRANSFER_WRITE),
    ] {
        if a.contains(bit) {
            out |= v;
        }
    }
    out
}

pub(crate) fn layout(l: Layout) -> vk::ImageLayout {
    match l {
        Layout::Undefined => vk::ImageLayout::UNDEFINED,
        Layout::General => vk::ImageLayout::GENERAL,
        Layout::ShaderReadOnly => vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        Layout::ColorAttachment => vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        // The combined depth/stencil layouts need no separateDepthStencilLayouts.
        Layout::DepthAttachment => vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
        Layout::DepthReadOnly => vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL,
        Layout::TransferSrc => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        Layout::TransferDst => vk::ImageLayout::TRANSFER_DST_OPTIMAL,
    }
}

/// Stage and access masks of one side of a barrier.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Scope {
    pub stages: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
}

impl Scope {
    pub const NONE: Scope = Scope {
        stages: vk::PipelineStageFlags2::NONE,
        access: vk::AccessFlags2::NONE,
    };

    /// The plan's access point, limited to what a queue supports: a
    /// compute-only queue has no vertex, fragment or attachment stages.
    pub fn of(ap: &AccessPoint, compute_only: bool) -> Scope {
        let mut s = stages(ap.stages);
        let mut a = accesses(ap.access);
        if compute_only {
            use vk::AccessFlags2 as A;
            use vk::PipelineStageFlags2 as S;
            s &= S::COMPUTE_SHADER | S::DRAW_INDIRECT | S::COPY;
            a &= A::INDIRECT_COMMAND_READ
                | A::UNIFORM_READ
                | A::SHADER_SAMPLED_READ
                | A::SHADER_STORAGE_READ
                | A::SHADER_STORAGE_WRITE
                | A::TRANSFER_READ
                | A::TRANSFER_WRITE;
        }
        if s == vk::PipelineStageFlags2::NONE {
            a = vk::AccessFlags2::NONE;
        }
        Scope {
            stages: s,
            access: a,
        }
    }

    pub fn or(self, o: Scope) -> Scope {
        Scope {
            stages: self.stages | o.stages,
            access: self.access | o.access,
        }
    }

    pub fn is_none(&self) -> bool {
        self.stages == vk::PipelineStageFlags2::NONE
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Target {
    /// Every resource (aliasing: another resource's bytes).
    Global,
    Buffer(usize),
    Image {
        resource: usize,
        old: vk::ImageLayout,
        new: vk::ImageLayout,
    },
}

#[derive(Debug, Clone, Copy)]
pub(crate) struct Barrier {
    pub target: Target,
    pub src: Scope,
    pub dst: Scope,
}

/// Barriers around each pass, and the layout every image is in.
#[derive(Debug, Default)]
pub(crate) struct SyncPlan {
    /// Indexed by pass id.
    pub before: Vec<Vec<Barrier>>,
    pub after: Vec<Vec<Barrier>>,
    /// Image layout while a pass runs, by `(pass, physical resource)`.
    pub layout_in: BTreeMap<(PassId, usize), vk::ImageLayout>,
    /// Per physical image: its first group's layout (where the frame
    /// prologue puts imported images) and its layout when the frame ends.
    pub first_layout: BTreeMap<usize, vk::ImageLayout>,
    pub last_layout: BTreeMap<usize, vk::ImageLayout>,
    /// Same-queue dependencies of the plan realised as barriers, and
    /// cross-queue ones left to the sync points (for the frame notes).
    pub barrier_deps: usize,
    pub semaphore_deps: usize,
}

/// What the planner needs to know about the backend's queues and memory.
pub(crate) struct Placement<'a> {
    /// Backend queue index of every pass (by pass id).
    pub queue_of: &'a [usize],
    /// Which backend queues are compute-only.
    pub compute_only: &'a [bool],
    /// Physical images that are depth formats.
    pub is_depth: &'a dyn Fn(usize) -> bool,
    /// Pairs `(earlier, later)` of transients whose bytes overlap.
    pub aliases: &'a [(usize, usize)],
}

struct Group {
    passes: Vec<PassId>,
    write: bool,
    layout: vk::ImageLayout,
}

pub(crate) fn plan_sync(plan: &Plan, at: &Placement<'_>) -> SyncPlan {
    let g = &plan.graph;
    let n = g.passes.len();
    let mut out = SyncPlan {
        before: vec![Vec::new(); n],
        after: vec![Vec::new(); n],
        ..SyncPlan::default()
    };
    let q = |p: PassId| at.queue_of[p];
    let co = |p: PassId| at.compute_only[q(p)];
    let point = |p: PassId, r: usize| access_point(g, p, r);

    // Buffers: one barrier per same-queue dependency, merged per (pass, buffer).
    let mut buffer: BTreeMap<(PassId, usize), (Scope, Scope)> = BTreeMap::new();
    for d in &plan.dependencies {
        if q(d.from) != q(d.to) {
            out.semaphore_deps += 1;
            continue;
        }
        out.barrier_deps += 1;
        if g.resources[d.resource].decl.is_image() {
            continue;
        }
        let e = buffer
            .entry((d.to, d.resource))
            .or_insert((Scope::NONE, Scope::NONE));
        e.0 = e.0.or(Scope::of(&d.src, co(d.to)));
        e.1 = e.1.or(Scope::of(&d.dst, co(d.to)));
    }
    for ((p, r), (src, dst)) in buffer {
        out.before[p].push(Barrier {
            target: Target::Buffer(r),
            src,
            dst,
        });
    }

    // Aliasing predecessors' uses on the first pass's queue.
    let mut alias_src: BTreeMap<usize, (PassId, Scope)> = BTreeMap::new();
    for &(a, b) in at.aliases {
        let (Some(la), Some(lb)) = (
            plan.lifetimes.iter().find(|l| l.resource == a),
            plan.lifetimes.iter().find(|l| l.resource == b),
        ) else {
            continue;
        };
        let first = plan.order[lb.first];
        let mut src = Scope::NONE;
        for &(u, _) in &la.uses {
            if q(u) == q(first) {
                src = src.or(Scope::of(&point(u, a), co(first)));
            }
        }
        let e = alias_src.entry(b).or_insert((first, Scope::NONE));
        e.1 = e.1.or(src);
    }

    // Images: groups of accesses and the transitions between them.
    for (r, res) in g.resources.iter().enumerate() {
        if res.version_of.is_some() || !res.decl.is_image() {
            continue;
        }
        let mut groups: Vec<Group> = Vec::new();
        for &p in &plan.order {
            if !g.passes[p]
                .accesses
                .iter()
                .any(|a| g.physical(a.resource) == r)
            {
                continue;
            }
            let ap = point(p, r);
            let l = layout(ap.layout.unwrap_or(Layout::General));
            let write = ap.access.writes();
            match groups.last_mut() {
                Some(last) if !write && !last.write => {
                    if last.layout != l {
                        last.layout = if (at.is_depth)(r) {
                            vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL
                        } else {
                            vk::ImageLayout::GENERAL
                        };
                    }
                    last.passes.push(p);
                }
                _ => groups.push(Group {
                    passes: vec![p],
                    write,
                    layout: l,
                }),
            }
        }
        let (Some(first), Some(last)) = (groups.first(), groups.last()) else {
            continue;
        };
        out.first_layout.insert(r, first.layout);
        out.last_layout.insert(r, last.layout);
        let transient = res.decl.lifetime() == LifetimeClass::Transient;
        for (i, group) in groups.iter().enumerate() {
            for &p in &group.passes {
                out.layout_in.insert((p, r), group.layout);
            }
            if group.write {
                let p = group.passes[0];
                let old = match i {
                    // Imported images are put in their first layout by the prologue.
                    0 if !transient => continue,
                    0 => vk::ImageLayout::UNDEFINED,
                    _ => groups[i - 1].layout,
                };
                let mut src = Scope::NONE;
                let mut cross = false;
                for d in plan
                    .dependencies
                    .iter()
                    .filter(|d| d.to == p && d.resource == r)
                {
                    if q(d.from) == q(p) {
                        src = src.or(Scope::of(&d.src, co(p)));
                    } else {
                        cross = true;
                    }
                }
                let dst = Scope::of(&point(p, r), co(p));
                if cross {
                    // Chains with the semaphore wait before this batch.
                    src = src.or(Scope {
                        stages: dst.stages,
                        access: vk::AccessFlags2::NONE,
                    });
                }
                if i == 0
                    && let Some((f, s)) = alias_src.remove(&r)
                    && f == p
                {
                    src = src.or(s);
                }
                if old != group.layout || !src.is_none() {
                    out.before[p].push(Barrier {
                        target: Target::Image {
                            resource: r,
                            old,
                            new: group.layout,
                        },
                        src,
                        dst,
                    });
                }
            } else if i > 0 {
                // After the writer that precedes this read group, on its queue.
                let w = groups[i - 1].passes[0];
                let src = Scope::of(&point(w, r), co(w));
                let mut dst = Scope::NONE;
                let mut cross = false;
                for &p in &group.passes {
                    if q(p) == q(w) {
                        dst = dst.or(Scope::of(&point(p, r), co(w)));
                    } else {
                        cross = true;
                    }
                }
                if cross {
                    dst = dst.or(Scope {
                        stages: vk::PipelineStageFlags2::ALL_COMMANDS,
                        access: vk::AccessFlags2::NONE,
                    });
                }
                let old = groups[i - 1].layout;
                if old != group.layout || !dst.is_none() {
                    out.after[w].push(Barrier {
                        target: Target::Image {
                            resource: r,
                            old,
                            new: group.layout,
                        },
                        src,
                        dst,
                    });
                }
            }
        }
    }
    // Buffers (and images whose first use was not a write) that reuse bytes.
    for (b, (first, src)) in alias_src {
        if src.is_none() {
            continue;
        }
        out.before[first].push(Barrier {
            target: Target::Global,
            src,
            dst: Scope::of(&point(first, b), co(first)),
        });
    }
    out
}
