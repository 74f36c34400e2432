//! Exports: Graphviz DOT for looking at a plan, JSON for tools.

use crate::instance::Instance;
use crate::plan::Plan;
use crate::schema::Queue;
use std::collections::BTreeMap;
use std::fmt::Write;

fn queue_colour(q: Queue) -> &'static str {
    match q {
        Queue::Graphics => "#cfe2ff",
        Queue::AsyncCompute => "#ffe5b4",
        Queue::Transfer => "#d8f5d0",
    }
}

fn quoted(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

/// The plan as a Graphviz digraph: passes coloured and clustered by queue,
/// edges labelled with the resources they carry. Cross-queue edges are red;
/// those that became sync points are bold, the ones other sync points cover
/// are dashed. Culled passes are grey and dashed.
pub fn to_dot(plan: &Plan) -> String {
    let g = &plan.graph;
    let mut out = String::new();
    let _ = writeln!(out, "digraph {} {{", quoted(&g.name));
    let _ = writeln!(out, "  rankdir=LR;");
    let _ = writeln!(
        out,
        "  node [shape=box, style=\"rounded,filled\", fontname=\"Helvetica\"];"
    );
    let _ = writeln!(out, "  edge [fontname=\"Helvetica\", fontsize=10];");
    for q in Queue::ALL {
        let passes: Vec<usize> = (0..g.passes.len())
            .filter(|&p| g.passes[p].queue == q)
            .collect();
        if passes.is_empty() {
            continue;
        }
        let _ = writeln!(out, "  subgraph \"cluster_{q}\" {{");
        let _ = writeln!(
            out,
            "    label={}; style=dashed; color=\"#888888\";",
            quoted(&q.to_string())
        );
        for p in passes {
            let pass = &g.passes[p];
            let label = format!("{}\n{}", pass.name, pass.kind);
            if plan.live[p] {
                let _ = writeln!(
                    out,
                    "    p{p} [label={}, fillcolor=\"{}\"];",
                    quoted(&label),
                    queue_colour(q)
                );
            } else {
                let reason = plan
                    .culled
                    .iter()
                    .find(|c| c.pass == p)
                    .map_or("", |c| c.reason.as_str());
                let _ = writeln!(
                    out,
                    "    p{p} [label={}, fillcolor=\"#eeeeee\", fontcolor=\"#777777\", style=\"rounded,filled,dashed\", tooltip={}];",
                    quoted(&format!("{label}\n(culled)")),
                    quoted(reason)
                );
            }
        }
        let _ = writeln!(out, "  }}");
    }
    let mut grouped: BTreeMap<(usize, usize), Vec<String>> = BTreeMap::new();
    for d in &plan.dependencies {
        grouped.entry((d.from, d.to)).or_default().push(format!(
            "{} ({})",
            g.resources[d.version].name,
            d.hazard.short()
        ));
    }
    for ((from, to), labels) in grouped {
        let cross = g.passes[from].queue != g.passes[to].queue;
        let synced = plan
            .sync_points
            .iter()
            .any(|s| s.after == from && s.before == to);
        let style = match (cross, synced) {
            (false, _) => "color=\"#444444\"",
            (true, true) => "color=\"#cc0000\", penwidth=2.5",
            (true, false) => "color=\"#cc0000\", style=dashed",
        };
        let mut label = labels.join("\n");
        if synced {
            label.push_str("\n[sync]");
        }
        let _ = writeln!(
            out,
            "  p{from} -> p{to} [label={}, {style}];",
            quoted(&label)
        );
    }
    out.push_str("}\n");
    out
}

/// The plan, and the instance when sizes are known, as pretty JSON.
pub fn to_json(plan: &Plan, instance: Option<&Instance>) -> String {
    #[derive(serde::Serialize)]
    struct Export<'a> {
        plan: &'a Plan,
        instance: Option<&'a Instance>,
    }
    serde_json::to_string_pretty(&Export { plan, instance })
        .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}
