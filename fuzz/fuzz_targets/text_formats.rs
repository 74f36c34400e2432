//! Fuzz the text parsers (TressFX 2 and OBJ): Ok or a positioned Err, never a
//! panic; what parses validates, and holds no more than the text has room for
//! (a TressFX 2 vertex is a line `x y z`, at least 5 bytes; an OBJ face corner
//! is at least an index and a separator).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(g) = strandgraph_assets::loaders::tfx2::parse(data) {
        if let Err(e) = g.validate() {
            panic!("a parsed groom must validate: {e}");
        }
        assert!(g.point_count() * 5 <= data.len());
    }
    if let Ok(m) = strandgraph_assets::loaders::obj::parse(data) {
        if let Err(e) = m.validate() {
            panic!("a parsed mesh must validate: {e}");
        }
        assert!(m.positions.len() <= data.len() && m.triangles.len() <= data.len());
    }
});
