//! Property tests over random DAGs with random queues.
//!
//! The checks recompute what they need from the plan's lanes and sync points
//! with their own breadth-first search, so they do not trust the compiler's
//! reachability code.

use proptest::prelude::*;
use proptest::sample::Index;
use std::collections::{HashSet, VecDeque};
use strandgraph_graph::alias::Aliasing;
use strandgraph_graph::synthetic::{Spec, SynthPass};
use strandgraph_graph::{Plan, Quantities, Queue, compile_str};

fn spec() -> impl Strategy<Value = Spec> {
    let pass = (
        0u8..2,
        prop::collection::vec(any::<Index>(), 0..4),
        prop::bool::weighted(0.15),
        1u64..64,
    );
    (
        prop::collection::vec(pass, 1..40),
        prop::collection::vec(any::<Index>(), 0..3),
    )
        .prop_map(|(passes, extra)| {
            let n = passes.len();
            let passes = passes
                .into_iter()
                .enumerate()
                .map(|(i, (q, reads, atomic, size))| {
                    let mut reads: Vec<usize> = if i == 0 {
                        vec![]
                    } else {
                        reads.iter().map(|x| x.index(i)).collect()
                    };
                    reads.sort_unstable();
                    reads.dedup();
                    SynthPass {
                        queue: if q == 0 {
                            Queue::Graphics
                        } else {
                            Queue::AsyncCompute
                        },
                        reads,
                        atomic,
                        size,
                    }
                })
                .collect();
            let mut outputs: Vec<usize> = extra.iter().map(|x| x.index(n)).chain([n - 1]).collect();
            outputs.sort_unstable();
            outputs.dedup();
            Spec { passes, outputs }
        })
}

fn compile(spec: &Spec) -> Plan {
    compile_str("synthetic.ron", &spec.to_ron(), &Spec::kinds(), 1)
        .unwrap_or_else(|e| panic!("{e}\n{}", spec.to_ron()))
}

/// Successors as the backends enforce order: next pass in the same lane, and sync points.
fn enforced_successors(plan: &Plan) -> Vec<Vec<usize>> {
    let mut succ = vec![Vec::new(); plan.graph.passes.len()];
    for lane in &plan.lanes {
        for w in lane.passes.windows(2) {
            succ[w[0]].push(w[1]);
        }
    }
    for s in &plan.sync_points {
        succ[s.after].push(s.before);
    }
    succ
}

fn happens_before(succ: &[Vec<usize>], from: usize, to: usize) -> bool {
    let mut seen = HashSet::new();
    let mut queue: VecDeque<usize> = succ[from].iter().copied().collect();
    while let Some(p) = queue.pop_front() {
        if p == to {
            return true;
        }
        if seen.insert(p) {
            queue.extend(succ[p].iter().copied());
        }
    }
    false
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn order_is_topological(spec in spec()) {
        let plan = compile(&spec);
        for d in &plan.dependencies {
            let (a, b) = (plan.position(d.from).unwrap(), plan.position(d.to).unwrap());
            prop_assert!(a < b, "{} before {}", plan.pass_name(d.to), plan.pass_name(d.from));
        }
        for lane in &plan.lanes {
            let positions: Vec<usize> = lane.passes.iter().map(|&p| plan.position(p).unwrap()).collect();
            prop_assert!(positions.windows(2).all(|w| w[0] < w[1]));
            prop_assert!(lane.passes.iter().all(|&p| plan.graph.passes[p].queue == lane.queue));
        }
    }

    #[test]
    fn every_dependency_is_enforced_by_lanes_or_sync_points(spec in spec()) {
        let plan = compile(&spec);
        let succ = enforced_successors(&plan);
        for d in &plan.dependencies {
            prop_assert!(happens_before(&succ, d.from, d.to),
                "{} -> {} ({}) not enforced", plan.pass_name(d.from), plan.pass_name(d.to), plan.resource_name(d.resource));
        }
    }

    #[test]
    fn sync_points_are_minimal(spec in spec()) {
        let plan = compile(&spec);
        for skip in 0..plan.sync_points.len() {
            let mut succ = enforced_successors(&plan);
            let s = &plan.sync_points[skip];
            let i = succ[s.after].iter().position(|&x| x == s.before).unwrap();
            succ[s.after].remove(i);
            let still_covered = plan.dependencies.iter().all(|d| happens_before(&succ, d.from, d.to));
            prop_assert!(!still_covered, "sync point {} -> {} is redundant", plan.pass_name(s.after), plan.pass_name(s.before));
        }
    }

    #[test]
    fn aliased_transients_never_share_bytes_while_both_alive(spec in spec()) {
        let plan = compile(&spec);
        let inst = plan.instantiate(&Quantities::example()).unwrap();
        let succ = enforced_successors(&plan);
        let uses = |r: usize| -> Vec<usize> {
            plan.lifetimes.iter().find(|l| l.resource == r).unwrap().uses.iter().map(|u| u.0).collect()
        };
        let all_before = |a: &[usize], b: &[usize]| a.iter().all(|&x| b.iter().all(|&y| happens_before(&succ, x, y)));
        let m = &inst.memory;
        for (i, p) in m.placements.iter().enumerate() {
            prop_assert_eq!(p.offset % 256, 0);
            for q in &m.placements[i + 1..] {
                let share = p.heap == q.heap && p.offset < q.offset + q.size && q.offset < p.offset + p.size;
                if share {
                    let (up, uq) = (uses(p.resource), uses(q.resource));
                    prop_assert!(all_before(&up, &uq) || all_before(&uq, &up),
                        "{} and {} share bytes but may run concurrently", plan.resource_name(p.resource), plan.resource_name(q.resource));
                }
            }
        }
        prop_assert!(m.bytes_with_aliasing <= m.bytes_without_aliasing + 256 * m.placements.len() as u64);
        prop_assert!(m.lower_bound <= m.bytes_with_aliasing);
    }

    #[test]
    fn without_new_waits_bytes_change_hands_only_along_the_data_flow(spec in spec()) {
        let mut plan = compile(&spec);
        plan.aliasing = Aliasing::NoNewWaits;
        let m = plan.instantiate(&Quantities::example()).unwrap().memory;
        for (p, q) in sharing_pairs(&plan, &m) {
            prop_assert!(hands_over_without_a_new_wait(&plan, p, q),
                "{} takes {}'s bytes, but a use of {} does not come before its first use",
                plan.resource_name(q), plan.resource_name(p), plan.resource_name(p));
        }
    }

    #[test]
    fn culling_keeps_every_pass_that_feeds_an_output(spec in spec()) {
        let plan = compile(&spec);
        // Pass i of the spec is pass i + 1 of the graph (pass 0 clears the counter).
        let mut feeds = vec![false; spec.passes.len()];
        for i in (0..spec.passes.len()).rev() {
            let read_by_feeder = (i + 1..spec.passes.len()).any(|j| feeds[j] && spec.passes[j].reads.contains(&i));
            feeds[i] = spec.outputs.contains(&i) || read_by_feeder;
        }
        for (i, f) in feeds.iter().enumerate() {
            if *f {
                prop_assert!(plan.live[i + 1], "p{} feeds an output but was culled", i);
            }
        }
        for c in &plan.culled {
            prop_assert!(!c.reason.is_empty());
        }
    }
}

/// Pairs of transients that share bytes, earlier lifetime first.
fn sharing_pairs(plan: &Plan, m: &strandgraph_graph::alias::MemoryPlan) -> Vec<(usize, usize)> {
    let first = |r: usize| {
        plan.lifetimes
            .iter()
            .find(|l| l.resource == r)
            .unwrap()
            .first
    };
    let mut pairs = Vec::new();
    for (i, p) in m.placements.iter().enumerate() {
        for q in &m.placements[i + 1..] {
            if p.heap == q.heap && p.offset < q.offset + q.size && q.offset < p.offset + p.size {
                let (a, b) = if first(p.resource) < first(q.resource) {
                    (p.resource, q.resource)
                } else {
                    (q.resource, p.resource)
                };
                pairs.push((a, b));
            }
        }
    }
    pairs
}

/// Every use of `earlier` reaches `later`'s first user along the plan's
/// dependencies (its own search, not the compiler's reachability).
fn hands_over_without_a_new_wait(plan: &Plan, earlier: usize, later: usize) -> bool {
    let mut succ = vec![Vec::new(); plan.graph.passes.len()];
    for d in &plan.dependencies {
        succ[d.from].push(d.to);
    }
    let lifetime = |r: usize| plan.lifetimes.iter().find(|l| l.resource == r).unwrap();
    let first = plan.order[lifetime(later).first];
    lifetime(earlier)
        .uses
        .iter()
        .all(|&(u, _)| happens_before(&succ, u, first))
}

#[test]
fn first_fit_hands_bytes_between_independent_chains_and_no_new_waits_does_not() {
    // Two chains on one queue, p0 -> p1 and p2 -> p3, each through a
    // transient of the same size: the second chain's can reuse the first's
    // bytes, which would make p2 wait for p1.
    let pass = |reads: Vec<usize>| SynthPass {
        queue: Queue::Graphics,
        reads,
        atomic: false,
        size: 8,
    };
    let spec = Spec {
        passes: vec![pass(vec![]), pass(vec![0]), pass(vec![]), pass(vec![2])],
        outputs: vec![1, 3],
    };
    let mut plan = compile(&spec);
    let shared = |plan: &Plan| {
        let m = plan.instantiate(&Quantities::example()).unwrap().memory;
        sharing_pairs(plan, &m)
            .into_iter()
            .filter(|&(a, b)| !hands_over_without_a_new_wait(plan, a, b))
            .count()
    };
    assert!(shared(&plan) > 0, "{}", spec.to_ron());
    plan.aliasing = Aliasing::NoNewWaits;
    assert_eq!(shared(&plan), 0, "{}", spec.to_ron());
}

#[test]
fn large_random_graph_compiles() {
    let spec = Spec::random(1000, 7);
    let plan = compile(&spec);
    assert_eq!(plan.graph.passes.len(), 1001);
    assert!(!plan.sync_points.is_empty());
    plan.instantiate(&Quantities::example()).unwrap();
}
