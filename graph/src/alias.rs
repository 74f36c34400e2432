//! Memory aliasing: transients whose lifetimes do not overlap share bytes.
//!
//! Placement is greedy first-fit by decreasing size over an interval graph,
//! the usual frame-graph heuristic: each resource goes at the lowest aligned
//! offset of its heap not used by a resource alive at the same time. The
//! planner takes sizes and alignments as inputs so a backend can re-run it
//! with the real memory requirements the driver reports.

use serde::Serialize;

/// Heaps are split by resource type: some GPUs cannot place buffers and
/// optimally tiled images in the same memory without extra granularity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum HeapKind {
    Buffers,
    Images,
}

impl HeapKind {
    /// Default placement alignment when the driver's is not known yet
    /// (256 B covers storage-buffer offset alignment on every desktop GPU;
    /// 64 KiB is the usual image placement alignment).
    pub fn default_alignment(self) -> u64 {
        match self {
            HeapKind::Buffers => 256,
            HeapKind::Images => 64 * 1024,
        }
    }
}

/// Which transients may take bytes an earlier one used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize)]
pub enum Aliasing {
    /// Any two whose lifetimes do not overlap.
    #[default]
    FirstFit,
    /// Ours: only where the earlier one's users already come before the
    /// later one's first user through the plan's own dependencies. Reused
    /// bytes are a wait (ash's hand-over barrier makes the later one's
    /// first user wait for the earlier one's users on its queue:
    /// `SyncPlan::waits_on`), and a wait the data flow does not have
    /// takes a pass out of a level it could share
    /// (`Plan::reuse_adds_no_wait`).
    NoNewWaits,
}

impl Aliasing {
    /// The names `FromStr` takes.
    pub const NAMES: [&'static str; 2] = ["first-fit", "no-new-waits"];
}

impl std::str::FromStr for Aliasing {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "first-fit" => Ok(Self::FirstFit),
            "no-new-waits" => Ok(Self::NoNewWaits),
            _ => Err(format!(
                "unknown aliasing `{s}`; expected one of: {}",
                Self::NAMES.join(", ")
            )),
        }
    }
}

impl std::fmt::Display for Aliasing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::FirstFit => Self::NAMES[0],
            Self::NoNewWaits => Self::NAMES[1],
        })
    }
}

/// A transient to place.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct AliasRequest {
    pub resource: usize,
    pub heap: HeapKind,
    pub size: u64,
    pub alignment: u64,
    /// Inclusive interval of schedule positions during which the bytes are in use.
    pub first: usize,
    pub end: usize,
}

impl AliasRequest {
    fn overlaps(&self, o: &AliasRequest) -> bool {
        self.first <= o.end && o.first <= self.end
    }
}

/// Where a transient lives.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Placement {
    pub resource: usize,
    pub heap: HeapKind,
    pub offset: u64,
    pub size: u64,
}

#[derive(Debug, Clone, Serialize)]
pub struct HeapSize {
    pub heap: HeapKind,
    pub bytes: u64,
}

#[derive(Debug, Clone, Serialize)]
pub struct MemoryPlan {
    pub placements: Vec<Placement>,
    pub heaps: Vec<HeapSize>,
    /// Every transient in its own allocation (what wgpu does).
    pub bytes_without_aliasing: u64,
    /// Sum of the heap sizes.
    pub bytes_with_aliasing: u64,
    /// The most bytes alive at any one position: no placement can do better.
    pub lower_bound: u64,
}

fn align_up(x: u64, a: u64) -> u64 {
    x.div_ceil(a.max(1)) * a.max(1)
}

pub fn plan_memory(requests: &[AliasRequest]) -> MemoryPlan {
    plan_memory_with(requests, &|_, _| true)
}

/// [`plan_memory`], where two transients whose lifetimes do not overlap
/// share bytes only if `may_follow(earlier, later)` (resource ids) allows.
pub fn plan_memory_with(
    requests: &[AliasRequest],
    may_follow: &dyn Fn(usize, usize) -> bool,
) -> MemoryPlan {
    // Whether bytes may pass from the earlier of two to the later; where
    // not, they are kept apart as if both were alive at once.
    let hands_over = |a: &AliasRequest, b: &AliasRequest| {
        if a.end < b.first {
            may_follow(a.resource, b.resource)
        } else {
            may_follow(b.resource, a.resource)
        }
    };
    let mut order: Vec<&AliasRequest> = requests.iter().collect();
    order.sort_by(|a, b| {
        b.size
            .cmp(&a.size)
            .then(a.first.cmp(&b.first))
            .then(a.resource.cmp(&b.resource))
    });
    let mut placed: Vec<(AliasRequest, u64)> = Vec::new();
    for req in order {
        let mut busy: Vec<(u64, u64)> = placed
            .iter()
            .filter(|(o, _)| o.heap == req.heap && (o.overlaps(req) || !hands_over(o, req)))
            .map(|(o, off)| (*off, off + o.size))
            .collect();
        busy.sort_unstable();
        let mut offset = 0;
        for (start, end) in busy {
            if align_up(offset, req.alignment) + req.size <= start {
                break;
            }
            offset = offset.max(end);
        }
        placed.push((*req, align_up(offset, req.alignment)));
    }
    placed.sort_by_key(|(r, _)| r.resource);

    let mut heaps: Vec<HeapSize> = Vec::new();
    for (r, off) in &placed {
        let end = off + r.size;
        match heaps.iter_mut().find(|h| h.heap == r.heap) {
            Some(h) => h.bytes = h.bytes.max(end),
            None => heaps.push(HeapSize {
                heap: r.heap,
                bytes: end,
            }),
        }
    }
    heaps.sort_by_key(|h| h.heap);
    let max_pos = requests.iter().map(|r| r.end).max().unwrap_or(0);
    let lower_bound = (0..=max_pos)
        .map(|t| {
            requests
                .iter()
                .filter(|r| r.first <= t && t <= r.end)
                .map(|r| r.size)
                .sum::<u64>()
        })
        .max()
        .unwrap_or(0);
    MemoryPlan {
        placements: placed
            .iter()
            .map(|(r, off)| Placement {
                resource: r.resource,
                heap: r.heap,
                offset: *off,
                size: r.size,
            })
            .collect(),
        bytes_without_aliasing: requests.iter().map(|r| r.size).sum(),
        bytes_with_aliasing: heaps.iter().map(|h| h.bytes).sum(),
        heaps,
        lower_bound,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn req(resource: usize, size: u64, first: usize, end: usize) -> AliasRequest {
        AliasRequest {
            resource,
            heap: HeapKind::Buffers,
            size,
            alignment: 256,
            first,
            end,
        }
    }

    #[test]
    fn disjoint_lifetimes_share_memory() {
        let m = plan_memory(&[req(0, 1000, 0, 1), req(1, 1000, 2, 3)]);
        assert_eq!(m.placements[0].offset, 0);
        assert_eq!(m.placements[1].offset, 0);
        assert_eq!(m.bytes_with_aliasing, 1000);
        assert_eq!(m.bytes_without_aliasing, 2000);
    }

    #[test]
    fn overlapping_lifetimes_do_not_and_respect_alignment() {
        let m = plan_memory(&[req(0, 1000, 0, 2), req(1, 100, 2, 3)]);
        assert_eq!(m.placements[0].offset, 0);
        assert_eq!(m.placements[1].offset, 1024);
        assert_eq!(m.lower_bound, 1100);
    }

    #[test]
    fn a_reuse_the_rule_forbids_takes_bytes_of_its_own() {
        // 1 may follow 0 in time, but not hand bytes over from it.
        let reqs = [req(0, 1000, 0, 1), req(1, 1000, 2, 3)];
        let m = plan_memory_with(&reqs, &|a, b| !(a == 0 && b == 1));
        assert_eq!(m.placements[0].offset, 0);
        assert_eq!(m.placements[1].offset, 1024);
        assert_eq!(m.bytes_with_aliasing, 2024);
        let m = plan_memory_with(&reqs, &|_, _| true);
        assert_eq!(m.bytes_with_aliasing, 1000);
    }

    #[test]
    fn aliasing_names_round_trip() {
        for name in Aliasing::NAMES {
            assert_eq!(name.parse::<Aliasing>().unwrap().to_string(), name);
        }
        assert!("first_fit".parse::<Aliasing>().is_err());
    }

    #[test]
    fn fills_gaps_between_live_resources() {
        // 0 and 2 are alive with a hole between them that 3 fits into.
        let m = plan_memory(&[
            req(0, 512, 0, 3),
            req(1, 512, 0, 0),
            req(2, 512, 0, 3),
            req(3, 256, 2, 3),
        ]);
        let off = |r: usize| {
            m.placements
                .iter()
                .find(|p| p.resource == r)
                .unwrap()
                .offset
        };
        assert_eq!(off(3), off(1));
        assert_eq!(m.bytes_with_aliasing, 1536);
    }
}
