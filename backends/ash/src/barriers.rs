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
        // Every stage before rasterization: vertex, and task and mesh where
        // a pass draws with mesh shaders (hw_strands.mesh).
        (Stages::VERTEX_SHADER, V::PRE_RASTERIZATION_SHADERS),
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
    /// Indexed by pass id: the passes on its queue whose work its barriers
    /// wait for (its same-queue dependencies, and the earlier users of
    /// bytes it reuses). What [`crate::Barriers::Levels`] groups by.
    pub waits_on: Vec<Vec<PassId>>,
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

/// The plan and the backend's placement, with the lookups every step uses.
struct Planner<'a> {
    plan: &'a Plan,
    at: &'a Placement<'a>,
}

impl Planner<'_> {
    /// Backend queue of pass `p`.
    fn q(&self, p: PassId) -> usize {
        self.at.queue_of[p]
    }

    /// Whether pass `p` runs on a compute-only queue.
    fn co(&self, p: PassId) -> bool {
        self.at.compute_only[self.q(p)]
    }

    fn point(&self, p: PassId, r: usize) -> AccessPoint {
        access_point(&self.plan.graph, p, r)
    }

    /// Buffers: one barrier per same-queue dependency, merged per (pass,
    /// buffer); counts the dependencies barriers and semaphores carry.
    fn buffer_barriers(&self, out: &mut SyncPlan) {
        let g = &self.plan.graph;
        let mut buffer: BTreeMap<(PassId, usize), (Scope, Scope)> = BTreeMap::new();
        for d in &self.plan.dependencies {
            if self.q(d.from) != self.q(d.to) {
                out.semaphore_deps += 1;
                continue;
            }
            out.barrier_deps += 1;
            out.waits_on[d.to].push(d.from);
            if g.resources[d.resource].decl.is_image() {
                continue;
            }
            let e = buffer
                .entry((d.to, d.resource))
                .or_insert((Scope::NONE, Scope::NONE));
            e.0 = e.0.or(Scope::of(&d.src, self.co(d.to)));
            e.1 = e.1.or(Scope::of(&d.dst, self.co(d.to)));
        }
        for ((p, r), (src, dst)) in buffer {
            out.before[p].push(Barrier {
                target: Target::Buffer(r),
                src,
                dst,
            });
        }
    }

    /// Per transient that reuses another's bytes: its first pass, and the
    /// earlier transient's uses on that pass's queue.
    fn alias_sources(&self, waits_on: &mut [Vec<PassId>]) -> BTreeMap<usize, (PassId, Scope)> {
        let plan = self.plan;
        let mut alias_src: BTreeMap<usize, (PassId, Scope)> = BTreeMap::new();
        for &(a, b) in self.at.aliases {
            let (Some(la), Some(lb)) = (
                plan.lifetimes.iter().find(|l| l.resource == a),
                plan.lifetimes.iter().find(|l| l.resource == b),
            ) else {
                continue;
            };
            let first = plan.order[lb.first];
            let mut src = Scope::NONE;
            for &(u, _) in &la.uses {
                if self.q(u) == self.q(first) {
                    src = src.or(Scope::of(&self.point(u, a), self.co(first)));
                    waits_on[first].push(u);
                }
            }
            let e = alias_src.entry(b).or_insert((first, Scope::NONE));
            e.1 = e.1.or(src);
        }
        alias_src
    }

    /// Image `r`'s accesses in plan order as groups: each write alone, the
    /// reads between two writes together, in a layout that serves them all.
    fn image_groups(&self, r: usize) -> Vec<Group> {
        let g = &self.plan.graph;
        let mut groups: Vec<Group> = Vec::new();
        for &p in &self.plan.order {
            if !g.passes[p]
                .accesses
                .iter()
                .any(|a| g.physical(a.resource) == r)
            {
                continue;
            }
            let ap = self.point(p, r);
            let l = layout(ap.layout.unwrap_or(Layout::General));
            let write = ap.access.writes();
            match groups.last_mut() {
                Some(last) if !write && !last.write => {
                    if last.layout != l {
                        last.layout = if (self.at.is_depth)(r) {
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
        groups
    }

    /// The barrier before the writer of `groups[i]` (a write group): after
    /// the earlier accesses on its queue, into the group's layout; for the
    /// first group of a transient that reuses bytes, after their last users.
    fn write_transition(
        &self,
        r: usize,
        groups: &[Group],
        i: usize,
        alias_src: &mut BTreeMap<usize, (PassId, Scope)>,
    ) -> Option<(PassId, Barrier)> {
        let group = &groups[i];
        let p = group.passes[0];
        let transient = self.plan.graph.resources[r].decl.lifetime() == LifetimeClass::Transient;
        let old = match i {
            // Imported images are put in their first layout by the prologue.
            0 if !transient => return None,
            0 => vk::ImageLayout::UNDEFINED,
            _ => groups[i - 1].layout,
        };
        let mut src = Scope::NONE;
        let mut cross = false;
        for d in self
            .plan
            .dependencies
            .iter()
            .filter(|d| d.to == p && d.resource == r)
        {
            if self.q(d.from) == self.q(p) {
                src = src.or(Scope::of(&d.src, self.co(p)));
            } else {
                cross = true;
            }
        }
        let dst = Scope::of(&self.point(p, r), self.co(p));
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
        let target = Target::Image {
            resource: r,
            old,
            new: group.layout,
        };
        (old != group.layout || !src.is_none()).then_some((p, Barrier { target, src, dst }))
    }

    /// The barrier after the writer that precedes read group `groups[i]`,
    /// on the writer's queue: into the readers' layout, before it signals.
    fn read_transition(&self, r: usize, groups: &[Group], i: usize) -> Option<(PassId, Barrier)> {
        let group = &groups[i];
        let w = groups[i - 1].passes[0];
        let src = Scope::of(&self.point(w, r), self.co(w));
        let mut dst = Scope::NONE;
        let mut cross = false;
        for &p in &group.passes {
            if self.q(p) == self.q(w) {
                dst = dst.or(Scope::of(&self.point(p, r), self.co(w)));
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
        let target = Target::Image {
            resource: r,
            old,
            new: group.layout,
        };
        (old != group.layout || !dst.is_none()).then_some((w, Barrier { target, src, dst }))
    }

    /// Images: groups of accesses and the transitions between them.
    fn image_barriers(&self, out: &mut SyncPlan, alias_src: &mut BTreeMap<usize, (PassId, Scope)>) {
        for (r, res) in self.plan.graph.resources.iter().enumerate() {
            if res.version_of.is_some() || !res.decl.is_image() {
                continue;
            }
            let groups = self.image_groups(r);
            let (Some(first), Some(last)) = (groups.first(), groups.last()) else {
                continue;
            };
            out.first_layout.insert(r, first.layout);
            out.last_layout.insert(r, last.layout);
            for (i, group) in groups.iter().enumerate() {
                for &p in &group.passes {
                    out.layout_in.insert((p, r), group.layout);
                }
                if group.write {
                    if let Some((p, b)) = self.write_transition(r, &groups, i, alias_src) {
                        out.before[p].push(b);
                    }
                } else if i > 0
                    && let Some((w, b)) = self.read_transition(r, &groups, i)
                {
                    out.after[w].push(b);
                }
            }
        }
    }
}

pub(crate) fn plan_sync(plan: &Plan, at: &Placement<'_>) -> SyncPlan {
    let n = plan.graph.passes.len();
    let mut out = SyncPlan {
        before: vec![Vec::new(); n],
        after: vec![Vec::new(); n],
        waits_on: vec![Vec::new(); n],
        ..SyncPlan::default()
    };
    let planner = Planner { plan, at };
    planner.buffer_barriers(&mut out);
    let mut alias_src = planner.alias_sources(&mut out.waits_on);
    planner.image_barriers(&mut out, &mut alias_src);
    // Buffers (and images whose first use was not a write) that reuse bytes.
    for (b, (first, src)) in alias_src {
        if src.is_none() {
            continue;
        }
        out.before[first].push(Barrier {
            target: Target::Global,
            src,
            dst: Scope::of(&planner.point(first, b), planner.co(first)),
        });
    }
    out
}
