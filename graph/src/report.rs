//! A plan printed for people: lanes, order, sync points, culling, the
//! lifetime matrix and the aliasing table.

use crate::instance::Instance;
use crate::plan::Plan;
use crate::schema::AccessMode;
use std::fmt::Write;

/// Bytes as KiB/MiB/GiB with one decimal.
pub fn human_bytes(b: u64) -> String {
    const UNITS: [&str; 4] = ["B", "KiB", "MiB", "GiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

pub fn render(plan: &Plan, instance: Option<&Instance>) -> String {
    let mut s = String::new();
    lanes(&mut s, plan);
    order(&mut s, plan);
    sync_points(&mut s, plan);
    culled(&mut s, plan);
    lifetime_matrix(&mut s, plan);
    if let Some(inst) = instance {
        memory(&mut s, plan, inst);
    }
    s
}

fn lanes(s: &mut String, plan: &Plan) {
    let g = &plan.graph;
    let _ = writeln!(
        s,
        "graph `{}` ({}): {} passes, {} live, {} resources\n",
        g.name,
        g.source.name,
        g.passes.len(),
        plan.order.len(),
        g.resources.len()
    );
    let _ = writeln!(s, "Queue lanes");
    for lane in &plan.lanes {
        let names: Vec<&str> = lane.passes.iter().map(|&p| plan.pass_name(p)).collect();
        let _ = writeln!(s, "  {:<14} {}", lane.queue.to_string(), names.join(" → "));
    }
    s.push('\n');
}

fn order(s: &mut String, plan: &Plan) {
    let _ = writeln!(s, "Order");
    let _ = writeln!(
        s,
        "  {:>3}  {:<14} {:<22} {:<26} waits for",
        "#", "queue", "pass", "kind"
    );
    for (i, &p) in plan.order.iter().enumerate() {
        let pass = &plan.graph.passes[p];
        let waits: Vec<String> = plan
            .sync_points
            .iter()
            .filter(|sp| sp.before == p)
            .map(|sp| format!("{}:{}", sp.signal_queue, plan.pass_name(sp.after)))
            .collect();
        let _ = writeln!(
            s,
            "  {i:>3}  {:<14} {:<22} {:<26} {}",
            pass.queue.to_string(),
            pass.name,
            pass.kind,
            waits.join(", ")
        );
    }
    s.push('\n');
}

fn sync_points(s: &mut String, plan: &Plan) {
    let cross = plan.dependencies.iter().filter(|d| d.cross_queue).count();
    let _ = writeln!(
        s,
        "Sync points: {} (covering {cross} cross-queue dependencies after transitive reduction)",
        plan.sync_points.len()
    );
    for sp in &plan.sync_points {
        let res: Vec<&str> = sp
            .resources
            .iter()
            .map(|&r| plan.resource_name(r))
            .collect();
        let _ = writeln!(
            s,
            "  {} signals {} after `{}`  →  {} waits before `{}`   [{}]",
            sp.signal_queue,
            sp.value,
            plan.pass_name(sp.after),
            sp.wait_queue,
            plan.pass_name(sp.before),
            res.join(", ")
        );
    }
    let barriers = plan.dependencies.len() - cross;
    let _ = writeln!(
        s,
        "  plus {barriers} same-queue dependencies, each a pipeline barrier\n"
    );
}

fn culled(s: &mut String, plan: &Plan) {
    if plan.culled.is_empty() {
        let _ = writeln!(s, "Culled: none\n");
        return;
    }
    let _ = writeln!(s, "Culled");
    for c in &plan.culled {
        let _ = writeln!(s, "  {}: {}", plan.pass_name(c.pass), c.reason);
    }
    s.push('\n');
}

fn lifetime_matrix(s: &mut String, plan: &Plan) {
    let _ = writeln!(
        s,
        "Transient lifetimes (columns: passes in order; W write, R read, A atomic, = alive, ~ alive until another queue has waited)"
    );
    let width = plan
        .lifetimes
        .iter()
        .map(|l| plan.resource_name(l.resource).len())
        .max()
        .unwrap_or(8)
        .max(8);
    let header: String = (0..plan.order.len())
        .map(|i| format!("{:>3}", i % 1000))
        .collect();
    let _ = writeln!(s, "  {:<width$} {header}", "");
    for l in &plan.lifetimes {
        let mut row = String::new();
        for (pos, &p) in plan.order.iter().enumerate() {
            let modes: Vec<AccessMode> = l
                .uses
                .iter()
                .filter(|(u, _)| *u == p)
                .map(|(_, m)| *m)
                .collect();
            let mode = match modes.as_slice() {
                [] => None,
                [AccessMode::Read] => Some("R"),
                [AccessMode::Write] => Some("W"),
                [AccessMode::Atomic] => Some("A"),
                _ => Some("RW"),
            };
            let cell = match mode {
                Some(m) => m,
                None if pos > l.first && pos < l.last => "=",
                None if pos > l.last && pos <= l.end => "~",
                None => "·",
            };
            let _ = write!(row, "{cell:>3}");
        }
        let _ = writeln!(s, "  {:<width$} {row}", plan.resource_name(l.resource));
    }
    s.push('\n');
}

fn memory(s: &mut String, plan: &Plan, inst: &Instance) {
    let q = &inst.quantities;
    let _ = writeln!(
        s,
        "Memory for {} strands, {} vertices, {} segments, {} bundles, {} models, {}x{}",
        q.strands, q.vertices, q.segments, q.bundles, q.models, q.width, q.height
    );
    let width = plan
        .lifetimes
        .iter()
        .map(|l| plan.resource_name(l.resource).len())
        .max()
        .unwrap_or(8)
        .max(8);
    let _ = writeln!(
        s,
        "  {:<width$} {:<8} {:>12} {:>12}  lifetime",
        "transient", "heap", "offset", "size"
    );
    for p in &inst.memory.placements {
        let l = plan.lifetimes.iter().find(|l| l.resource == p.resource);
        let span = l.map_or(String::new(), |l| format!("{}..={}", l.first, l.end));
        let _ = writeln!(
            s,
            "  {:<width$} {:<8} {:>12} {:>12}  {span}",
            plan.resource_name(p.resource),
            format!("{:?}", p.heap),
            human_bytes(p.offset),
            human_bytes(p.size)
        );
    }
    for h in &inst.memory.heaps {
        let _ = writeln!(s, "  heap {:?}: {}", h.heap, human_bytes(h.bytes));
    }
    let m = &inst.memory;
    let _ = writeln!(
        s,
        "Peak transient memory: {} without aliasing, {} with aliasing ({:.0}% saved; lower bound {})",
        human_bytes(m.bytes_without_aliasing),
        human_bytes(m.bytes_with_aliasing),
        100.0 * (1.0 - m.bytes_with_aliasing as f64 / m.bytes_without_aliasing.max(1) as f64),
        human_bytes(m.lower_bound)
    );
    let persistent: u64 = plan
        .graph
        .resources
        .iter()
        .enumerate()
        .filter(|(_, r)| {
            r.version_of.is_none() && r.decl.lifetime() != crate::schema::LifetimeClass::Transient
        })
        .map(|(i, _)| inst.sizes[i].bytes)
        .sum();
    let _ = writeln!(
        s,
        "Imported and history resources: {}",
        human_bytes(persistent)
    );
}
