//! Placing transients in the heaps: the plan's offsets checked against
//! the driver's real sizes and alignments (re-planned by the same planner
//! when they do not fit), and which transients end up sharing bytes (the
//! aliasing hand-overs barriers.rs orders).

use ash::vk;
use strandgraph_graph::Plan;
use strandgraph_graph::alias::{AliasRequest, HeapKind};

/// Where transients go: `(resource, heap, offset)`.
pub(crate) type Placements = Vec<(usize, HeapKind, u64)>;

/// Whether the plan's placements honour the real requirements: aligned, and
/// no two resources alive at once overlap.
pub(crate) fn placements_fit(placements: &Placements, requests: &[AliasRequest]) -> bool {
    let request = |r: usize| requests.iter().find(|q| q.resource == r);
    placements.iter().all(|&(r, heap, off)| {
        let Some(a) = request(r) else { return false };
        off % a.alignment == 0
            && placements.iter().all(|&(o, oheap, ooff)| {
                let Some(b) = request(o) else { return false };
                o == r
                    || oheap != heap
                    || !(a.first <= b.end && b.first <= a.end)
                    || off + a.size <= ooff
                    || ooff + b.size <= off
            })
    })
}

/// The transients' real sizes and alignments, with their lifetimes.
pub(crate) fn alias_requests(
    plan: &Plan,
    reqs: &[Option<vk::MemoryRequirements>],
) -> Vec<AliasRequest> {
    plan.lifetimes
        .iter()
        .filter_map(|l| {
            let req = reqs[l.resource]?;
            let heap = if plan.graph.resources[l.resource].decl.is_image() {
                HeapKind::Images
            } else {
                HeapKind::Buffers
            };
            Some(AliasRequest {
                resource: l.resource,
                heap,
                size: req.size,
                alignment: req.alignment.max(heap.default_alignment()),
                first: l.first,
                end: l.end,
            })
        })
        .collect()
}

/// Pairs of one heap's members that share bytes, earlier lifetime first.
pub(crate) fn sharing_bytes(
    members: &[(usize, u64)],
    requests: &[AliasRequest],
) -> Vec<(usize, usize)> {
    let request = |r: usize| requests.iter().find(|q| q.resource == r);
    let mut out = Vec::new();
    for (i, &(a, ao)) in members.iter().enumerate() {
        for &(b, bo) in &members[i + 1..] {
            let (Some(ra), Some(rb)) = (request(a), request(b)) else {
                continue;
            };
            if ao < bo + rb.size && bo < ao + ra.size {
                if ra.end < rb.first {
                    out.push((a, b));
                } else if rb.end < ra.first {
                    out.push((b, a));
                }
            }
        }
    }
    out
}
