//! Compile a graph file and print its plan, accepting any pass kind.
//!
//! ```sh
//! cargo run -p strandgraph-graph --example compile -- scenes/graphs/kulikov.ron
//! ```
//! The `strandgraph graph` command does the same with the real pass registry.

use strandgraph_graph::{AnyKind, Quantities, compile_file, report};

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "scenes/graphs/kulikov.ron".into());
    let plan = match compile_file(path.as_ref(), &AnyKind, 1) {
        Ok(plan) => plan,
        Err(e) => {
            eprintln!("{:?}", miette::Report::new(e));
            std::process::exit(2);
        }
    };
    match plan.instantiate(&Quantities::example()) {
        Ok(instance) => print!("{}", report::render(&plan, Some(&instance))),
        Err(e) => eprintln!("{:?}", miette::Report::new(e)),
    }
}
