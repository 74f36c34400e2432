//! Fuzz the environment-map decoder (`loaders::envmap::parse`) on OpenEXR
//! files: Ok or an Err, never a panic, and never an allocation beyond the
//! decoder's limit (`MAX_WIDTH` x `MAX_HEIGHT`, 256 MiB at once). Inputs
//! without the EXR magic are left to `envmap_hdr` (the detection itself is
//! unit-tested). A map that decodes is 2:1, within the bounds, and holds one
//! finite, non-negative texel per pixel.
#![no_main]

use libfuzzer_sys::fuzz_target;
use strandgraph_assets::loaders::envmap::{MAX_HEIGHT, MAX_WIDTH, parse};

fuzz_target!(|data: &[u8]| {
    if !data.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        return;
    }
    if let Ok(m) = parse(data) {
        assert!(m.width == 2 * m.height && m.height >= 1);
        assert!(m.width <= MAX_WIDTH && m.height <= MAX_HEIGHT);
        assert_eq!(m.texels.len(), (m.width * m.height) as usize);
        assert!(
            m.texels
                .iter()
                .flatten()
                .all(|c| c.is_finite() && *c >= 0.0)
        );
    }
});
