//! Fuzz the tfx4 parser: it must return Ok or Err, never panic or allocate from an
//! unchecked header field.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(g) = strandgraph_assets::loaders::tfx4::parse(data) {
        assert!(g.validate().is_ok());
    }
});
