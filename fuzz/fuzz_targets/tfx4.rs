//! Fuzz the tfx4 parser: Ok or a positioned Err, never a panic or an
//! allocation sized by an unchecked header field; a parsed groom validates and
//! holds no more points than the file has room for.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(g) = strandgraph_assets::loaders::tfx4::parse(data) {
        if let Err(e) = g.validate() {
            panic!("a parsed groom must validate: {e}");
        }
        // Nothing is sized by the header alone: a TressFX 4 vertex is a float4.
        assert!(g.point_count() * 16 <= data.len());
    }
});
