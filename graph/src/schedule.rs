//! Queue scheduling: one order per queue, and the fewest cross-queue sync points.

use crate::deps::{Dependencies, Edge};
use crate::reach::Reach;
use crate::resolve::{Graph, PassId, ResourceId};
use crate::schema::Queue;
use serde::Serialize;
use std::collections::BTreeMap;

/// The passes one queue runs, in order.
#[derive(Debug, Clone, Serialize)]
pub struct Lane {
    pub queue: Queue,
    pub passes: Vec<PassId>,
}

/// `wait_queue` waits, before running `before`, until `signal_queue` has run `after`.
///
/// On Vulkan this is one timeline semaphore per queue: the signalling queue
/// signals `value` after `after`, and the waiting queue waits for it.
#[derive(Debug, Clone, Serialize)]
pub struct SyncPoint {
    pub signal_queue: Queue,
    pub after: PassId,
    /// 1-based position of `after` in its lane: the timeline value to signal and wait for.
    pub value: u64,
    pub wait_queue: Queue,
    pub before: PassId,
    /// Resources whose dependencies this point carries directly.
    pub resources: Vec<ResourceId>,
}

#[derive(Debug, Clone)]
pub struct Schedule {
    /// Live passes in one topological order; lanes are its per-queue subsequences.
    pub order: Vec<PassId>,
    pub lanes: Vec<Lane>,
    pub sync_points: Vec<SyncPoint>,
    /// Happens-before as the backends will enforce it: lane order plus sync points.
    pub happens_before: Reach,
}

pub fn schedule(g: &Graph, deps: &Dependencies, live: &[bool]) -> Schedule {
    let order: Vec<PassId> = deps.order.iter().copied().filter(|&p| live[p]).collect();
    let lanes: Vec<Lane> = Queue::ALL
        .iter()
        .map(|&q| Lane {
            queue: q,
            passes: order
                .iter()
                .copied()
                .filter(|&p| g.passes[p].queue == q)
                .collect(),
        })
        .filter(|l| !l.passes.is_empty())
        .collect();
    let lane_edges: Vec<(PassId, PassId)> = lanes
        .iter()
        .flat_map(|l| l.passes.windows(2).map(|w| (w[0], w[1])))
        .collect();

    let queue = |p: PassId| g.passes[p].queue;
    let mut cross: BTreeMap<(PassId, PassId), Vec<ResourceId>> = BTreeMap::new();
    for e in deps
        .edges
        .iter()
        .filter(|e| live[e.from] && live[e.to] && queue(e.from) != queue(e.to))
    {
        cross.entry((e.from, e.to)).or_default().push(e.resource);
    }

    // Transitive reduction restricted to cross-queue edges: (u, v) is redundant
    // when another successor w of u (in lane order or across queues) reaches v.
    let n = g.passes.len();
    let all_edges: Vec<(PassId, PassId)> = lane_edges
        .iter()
        .copied()
        .chain(cross.keys().copied())
        .collect();
    let reach = Reach::new(n, &order, all_edges.iter().copied());
    let mut succ = vec![Vec::new(); n];
    for &(a, b) in &all_edges {
        succ[a].push(b);
    }
    let position_in_lane = |p: PassId| {
        lanes
            .iter()
            .find_map(|l| l.passes.iter().position(|&x| x == p))
            .map_or(0, |i| i as u64 + 1)
    };
    let sync_points: Vec<SyncPoint> = cross
        .iter()
        .filter(|((u, v), _)| !succ[*u].iter().any(|&w| w != *v && reach.reaches(w, *v)))
        .map(|(&(u, v), resources)| SyncPoint {
            signal_queue: queue(u),
            after: u,
            value: position_in_lane(u),
            wait_queue: queue(v),
            before: v,
            resources: resources.clone(),
        })
        .collect();

    let enforced = lane_edges
        .iter()
        .copied()
        .chain(sync_points.iter().map(|s| (s.after, s.before)));
    let happens_before = Reach::new(n, &order, enforced);
    Schedule {
        order,
        lanes,
        sync_points,
        happens_before,
    }
}

/// Whether every edge is enforced by the schedule (lane order or sync points).
pub fn covers(schedule: &Schedule, edges: &[Edge]) -> bool {
    edges
        .iter()
        .all(|e| schedule.happens_before.reaches(e.from, e.to))
}
