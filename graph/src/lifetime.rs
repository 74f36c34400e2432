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
    let mut out = Vec::new();
    for (r, res) in g.resources.iter().enumerate() {
        if res.decl.lifetime() != LifetimeClass::Transient || res.version_of.is_some() {
            continue;
        }
        let mut uses = Vec::new();
        let mut positions = Vec::new();
        for (pos, &p) in schedule.order.iter().enumerate() {
            // Versions (`a -> b`) share their resource's memory.
            let touches = |a: &&crate::resolve::Access| g.physical(a.resource) == r;
            for a in g.passes[p].accesses.iter().filter(touches) {
                uses.push((p, a.mode));
            }
            if g.passes[p].accesses.iter().any(|a| g.physical(a.resource) == r) {
                positions.push((pos, p));
            }
        }
        let (Some(&(first, _)), Some(&(last, _))) = (positions.first(), positions.last()) else {
            continue;
        };
        // The latest pass not ordered after every use.
        let end = schedule
            .order
            .iter()
            .enumerate()
            .rev()
            .find(|&(_, &q)| positions.iter().any(|&(_, u)| !hb.reaches(u, q)))
            .map_or(last, |(pos, _)| pos.max(last));
        out.push(Lifetime {
            resource: r,
            first,
            last,
            end,
            uses,
        });
    }
    out
}
