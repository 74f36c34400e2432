//! # strandgraph-passes
//!
//! Pass definitions shared by every backend. This crate implements the
//! graph compiler's [`PassRegistry`]: graph files name pass kinds such as
//! `"kulikov.raster"`, and the compiler rejects kinds not listed here.
//!
//! Each entry says which pipeline it belongs to and which section of which
//! paper specifies it, so `strandgraph graph` can show where a pass comes from.

mod catalogue;

pub use catalogue::{KINDS, PassKind};
use strandgraph_graph::PassRegistry;

/// The built-in pass kinds.
#[derive(Debug, Clone, Copy, Default)]
pub struct Registry;

impl Registry {
    pub fn get(&self, kind: &str) -> Option<&'static PassKind> {
        KINDS.iter().find(|k| k.name == kind)
    }
}

impl PassRegistry for Registry {
    fn contains(&self, kind: &str) -> bool {
        self.get(kind).is_some()
    }
    fn kinds(&self) -> Vec<&str> {
        KINDS.iter().map(|k| k.name).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_namespaced() {
        let mut names: Vec<&str> = KINDS.iter().map(|k| k.name).collect();
        names.sort_unstable();
        let before = names.len();
        names.dedup();
        assert_eq!(before, names.len(), "duplicate pass kind");
        for k in KINDS {
            assert!(k.name.contains('.'), "{} has no pipeline prefix", k.name);
            assert!(
                !k.source.is_empty() && !k.summary.is_empty(),
                "{} is undocumented",
                k.name
            );
        }
    }

    #[test]
    fn shipped_graphs_use_only_registered_kinds() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/graphs");
        let mut seen = 0;
        for entry in std::fs::read_dir(dir).expect("scenes/graphs exists") {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "ron") {
                strandgraph_graph::compile_file(&path, &Registry).unwrap_or_else(|e| panic!("{e}"));
                seen += 1;
            }
        }
        assert!(
            seen >= 2,
            "expected the kulikov and lipp graphs, found {seen}"
        );
    }
}
