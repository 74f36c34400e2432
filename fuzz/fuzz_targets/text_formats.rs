//! Fuzz the text parsers (TressFX 2 and OBJ).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(g) = strandgraph_assets::loaders::tfx2::parse(data) {
        assert!(g.validate().is_ok());
    }
    if let Ok(m) = strandgraph_assets::loaders::obj::parse(data) {
        assert!(m.validate().is_ok());
    }
});
