//! Fuzz the scene parser and checker (`Scene::check`: RON, then every check
//! that needs no file and no generator) on arbitrary text: a scene
//! description or an error at a line and column inside the text, never a
//! panic. A description that passes is written back as RON and must read
//! back equal (the checks leave no NaN, which would not compare equal).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use ron::extensions::Extensions;
use strandgraph_assets::{AssetError, Scene};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("fuzz.ron");
    match Scene::check(path, text) {
        Ok(desc) => {
            let config = ron::ser::PrettyConfig::default()
                .extensions(Extensions::UNWRAP_VARIANT_NEWTYPES | Extensions::IMPLICIT_SOME);
            let again = ron::ser::to_string_pretty(&desc, config)
                .unwrap_or_else(|e| panic!("a checked scene must serialise: {e}"));
            match Scene::check(path, &again) {
                Ok(back) => assert_eq!(back, desc, "read back differs:\n{again}"),
                Err(e) => panic!("a checked scene, written back, fails: {e}\n{again}"),
            }
        }
        Err(AssetError::Scene { line, col, .. }) => {
            let lines: Vec<&str> = text.split('\n').collect();
            assert!(
                line >= 1 && line <= lines.len(),
                "line {line} of {}",
                lines.len()
            );
            let chars = lines[line - 1].chars().count();
            assert!(
                col >= 1 && col <= chars + 1,
                "{line}:{col}, the line has {chars} characters"
            );
        }
        Err(e) => panic!("not a positioned scene error: {e}"),
    }
});
