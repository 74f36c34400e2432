//! Resource memory: one arena for transients (at the plan's offsets) and one
//! allocation per imported or history resource.

use crate::execute::CpuError;
use std::collections::HashMap;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use strandgraph_graph::alias::HeapKind;
use strandgraph_graph::{Instance, LifetimeClass, Plan};

/// Initial contents of imported and history resources, by resource name, as
/// 32-bit words (what [`strandgraph_passes::upload::upload`] packs from a scene).
pub type Inputs = strandgraph_passes::upload::Upload;

/// Where a declared resource's words are.
#[derive(Debug, Clone, Copy)]
enum Home {
    /// Range of words in the transient arena.
    Arena { start: usize, len: usize },
    /// Index into the owned allocations.
    Owned(usize),
    /// Declared but used by no live pass.
    Unused,
}

/// All memory of one frame.
pub struct Memory {
    arena: Vec<AtomicU32>,
    owned: Vec<Vec<AtomicU32>>,
    homes: Vec<Home>,
    /// Counts out-of-range accesses of every kernel.
    pub out_of_bounds: AtomicU64,
    /// Bytes the arena holds (aliased or not).
    pub arena_bytes: u64,
}

fn words_of(bytes: u64) -> usize {
    bytes.div_ceil(4) as usize
}

impl Memory {
    /// Lays out memory for `instance`. With `alias` false every transient
    /// gets its own range, the reference the aliased layout is diffed
    /// against. More than `limit` bytes (default: what the host has
    /// available) is an error.
    pub fn new(
        plan: &Plan,
        instance: &Instance,
        alias: bool,
        limit: Option<u64>,
    ) -> Result<Memory, CpuError> {
        let g = &plan.graph;
        let mut homes = vec![Home::Unused; g.resources.len()];
        // Heaps sit back to back in one arena: buffers, then images.
        let mut heap_base: HashMap<HeapKind, u64> = HashMap::new();
        let mut cursor = 0u64;
        for h in &instance.memory.heaps {
            heap_base.insert(h.heap, cursor);
            cursor += h.bytes.next_multiple_of(4);
        }
        if alias {
            for p in &instance.memory.placements {
                let start = heap_base[&p.heap] + p.offset;
                debug_assert_eq!(start % 4, 0, "placements are aligned");
                homes[p.resource] = Home::Arena {
                    start: (start / 4) as usize,
                    len: words_of(p.size),
                };
            }
        } else {
            cursor = 0;
            for p in &instance.memory.placements {
                homes[p.resource] = Home::Arena {
                    start: (cursor / 4) as usize,
                    len: words_of(p.size),
                };
                cursor += p.size.next_multiple_of(256);
            }
        }
        let arena_bytes = cursor;
        check_budget(plan, instance, arena_bytes, limit.or_else(available_bytes))?;
        let arena = (0..words_of(arena_bytes))
            .map(|_| AtomicU32::new(0))
            .collect();

        let mut owned = Vec::new();
        for (r, res) in g.resources.iter().enumerate() {
            if res.version_of.is_some() || res.decl.lifetime() == LifetimeClass::Transient {
                continue;
            }
            let len = words_of(instance.sizes[r].bytes);
            homes[r] = Home::Owned(owned.len());
            owned.push((0..len).map(|_| AtomicU32::new(0)).collect());
        }
        Ok(Memory {
            arena,
            owned,
            homes,
            out_of_bounds: AtomicU64::new(0),
            arena_bytes,
        })
    }

    /// Writes a frame's inputs into the imported and history resources they
    /// name (from word 0; the rest keeps its contents). Inputs for
    /// transients or for resources the graph lacks are ignored.
    pub fn upload(&self, plan: &Plan, inputs: &Inputs) -> Result<(), CpuError> {
        for (name, words) in &inputs.resources {
            let Some(r) = plan.graph.resource_id(name) else {
                continue;
            };
            let Home::Owned(i) = self.homes[plan.graph.physical(r)] else {
                continue;
            };
            let dst = &self.owned[i];
            if words.len() > dst.len() {
                return Err(CpuError::Input {
                    resource: name.clone(),
                    message: format!(
                        "{} words given, the plan sizes it at {}",
                        words.len(),
                        dst.len()
                    ),
                });
            }
            for (d, &w) in dst.iter().zip(words) {
                d.store(w, Ordering::Relaxed);
            }
        }
        Ok(())
    }

    /// The words of resource `r` (a version resolves to its resource's memory).
    pub fn words(&self, plan: &Plan, r: usize) -> &[AtomicU32] {
        match self.homes[plan.graph.physical(r)] {
            Home::Arena { start, len } => &self.arena[start..start + len],
            Home::Owned(i) => &self.owned[i],
            Home::Unused => &[],
        }
    }

    /// A copy of resource `name`'s words.
    pub fn read(&self, plan: &Plan, name: &str) -> Option<Vec<u32>> {
        let r = plan.graph.resource_id(name)?;
        Some(
            self.words(plan, r)
                .iter()
                .map(|w| w.load(std::sync::atomic::Ordering::Relaxed))
                .collect(),
        )
    }
}

/// The memory the host can still give, from `/proc/meminfo` (`None`
/// elsewhere, where nothing is checked).
fn available_bytes() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Refuses a plan whose memory (the transient arena plus every imported
/// and history resource) exceeds `available`, naming the largest resource:
/// sizes follow the output's resolution and the scene, both user input, so
/// an allocation the host cannot hold must be an error, not an abort.
fn check_budget(
    plan: &Plan,
    instance: &Instance,
    arena_bytes: u64,
    available: Option<u64>,
) -> Result<(), CpuError> {
    let Some(available) = available else {
        return Ok(());
    };
    let g = &plan.graph;
    let owned = (0..g.resources.len()).filter(|&r| {
        g.resources[r].version_of.is_none()
            && g.resources[r].decl.lifetime() != LifetimeClass::Transient
    });
    let needed = arena_bytes + owned.clone().map(|r| instance.sizes[r].bytes).sum::<u64>();
    if needed <= available {
        return Ok(());
    }
    let largest = (0..g.resources.len())
        .filter(|&r| g.resources[r].version_of.is_none())
        .max_by_key(|&r| instance.sizes[r].bytes)
        .map_or(String::from("-"), |r| {
            format!(
                "`{}` at {}",
                g.resources[r].name,
                gib(instance.sizes[r].bytes)
            )
        });
    Err(CpuError::OutOfMemory {
        needed: gib(needed),
        largest,
        available: gib(available),
    })
}

fn gib(bytes: u64) -> String {
    format!("{:.2} GiB", bytes as f64 / (1u64 << 30) as f64)
}
