//! The render graphs shipped in `scenes/graphs/`, built in: the demo scene
//! writes them out beside itself (so an installed viewer can switch between
//! them), and the `param` fuzz target compiles them with these passes.

macro_rules! graphs {
    ($($name:literal),+ $(,)?) => {
        [$(($name, include_str!(concat!("../../scenes/graphs/", $name)))),+]
    };
}

/// Every `scenes/graphs/*.ron` by file name, and its text.
pub const GRAPHS: [(&str, &str); 11] = graphs![
    "hw_mesh.ron",
    "hw_strands.ron",
    "kulikov.ron",
    "kulikov_reference.ron",
    "kulikov_visibility.ron",
    "lipp.ron",
    "lipp_msaa.ron",
    "lipp_reference.ron",
    "roofline.ron",
    "scheuermann.ron",
    "scheuermann_reference.ron",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_graph_is_built_in_and_compiles() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/graphs");
        let shipped = std::fs::read_dir(dir)
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .path()
                    .extension()
                    .is_some_and(|x| x == "ron")
            })
            .count();
        assert_eq!(GRAPHS.len(), shipped, "add new graphs to shipped::GRAPHS");
        for (name, text) in GRAPHS {
            strandgraph_graph::compile_str(name, text, &crate::Registry, 1)
                .unwrap_or_else(|e| panic!("{name}: {e:?}"));
        }
    }
}
