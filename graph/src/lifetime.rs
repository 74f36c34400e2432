//! Transient lifetimes in schedule positions, widened for concurrent queues.

use crate::resolve::{Graph, PassId, ResourceId};
use crate::schedule::Schedule;
use crate::schema::{AccessMode, LifetimeClass};
use serde::Serialize;

/// When a transient's memory is in use, as positions in the plan's order.
#[derive(Debug, Clone, Serialize)]
pub struct Lifetime {
    pub resource: ResourceId,
    /// Position of the first use.
    pub first: usize,
    /// Position of the last use.
    pub last: usize,
    /// Last position at which some pass may still run concurrently with a use.
    ///
    /// Equal to `last` on a single queue. When a use runs on async compute,
    /// passes on the graphics queue that have not waited for it may overlap
    /// it, so the memory stays reserved until the graphics queue has waited.
    /// Every pass after `end` happens after every use: another transient
    /// whose `first` is greater than `end` may reuse the bytes.
    pub end: usize,
    pub uses: Vec<(PassId, AccessMode)>,
}

impl Lifetime {
    pub fn overlaps(&self, other: &Lifetime) -> bool {
        self.first <= other.end && other.first <= self.end
    }
}

pub fn lifetimes(g: &Graph, schedule: &Schedule) -> Vec<Lifetime> {
    let hb = &schedule.happens_before;
    // Uses of each declared resource's memory (versions share it), in order.
    let mut uses: Vec<Vec<(usize, PassId, AccessMode)>> = vec![Vec::new(); g.resources.len()];
    for (pos, &p) in schedule.order.iter().enumerate() {
        for a in &g.passes[p].accesses {
            uses[g.physical(a.resource)].push((pos, p, a.mode));
        }
    }
    let mut out = Vec::new();
    for (r, res) in g.resources.iter().enumerate() {
        let transient = res.decl.lifetime() == LifetimeClass::Transient && res.version_of.is_none();
        let (Some(&(first, _, _)), Some(&(last, _, _))) = (uses[r].first(), uses[r].last()) else {
            continue;
        };
        if !transient {
            continue;
        }
        // The latest pass not ordered after every use.
        let end = schedule
            .order
            .iter()
            .enumerate()
            .rev()
            .take_while(|&(pos, _)| pos > last)
            .find(|&(_, &q)| uses[r].iter().any(|&(_, u, _)| !hb.reaches(u, q)))
            .map_or(last, |(pos, _)| pos);
        out.push(Lifetime {
            resource: r,
            first,
            last,
            end,
            uses: uses[r].iter().map(|&(_, p, m)| (p, m)).collect(),
        });
    }
    out
}
