use super::*;
use std::ffi::OsString;

/// Vertices, strands, triangles.
type Geometry = (Vec<[f32; 4]>, Vec<[u32; 2]>, Vec<[[f32; 3]; 3]>);

/// Two strands over a triangle: enough to bake in microseconds.
fn tiny() -> Geometry {
    let vertices = (0..8)
        .map(|i| [(i / 4) as f32 * 0.01, 0.01 * (i % 4) as f32, 0.0, 0.002])
        .collect();
    let strands = vec![[0, 4], [4, 4]];
    let tris = vec![[[-1.0, -0.01, -1.0], [1.0, -0.01, -1.0], [0.0, -0.01, 1.0]]];
    (vertices, strands, tris)
}

fn settings() -> BakeSettings {
    BakeSettings {
        rays: 16,
        ..BakeSettings::default()
    }
}

#[test]
fn second_run_reads_the_cache() {
    let dir = tempfile::tempdir().unwrap();
    let (v, s, t) = tiny();
    let input = BakeInput {
        vertices: &v,
        strands: &s,
        triangles: &t,
    };
    let (a, first) = bake_cached(&input, &settings(), Some(dir.path())).unwrap();
    let (b, second) = bake_cached(&input, &settings(), Some(dir.path())).unwrap();
    assert_eq!(first, BakeOutcome::Baked);
    assert_eq!(second, BakeOutcome::Cached);
    assert_eq!(a, b);
    // Different settings or geometry: a different key, baked again.
    let more = BakeSettings {
        rays: 17,
        ..settings()
    };
    assert_eq!(
        bake_cached(&input, &more, Some(dir.path())).unwrap().1,
        BakeOutcome::Baked
    );
    let mut moved = v.clone();
    moved[3][1] += 0.001;
    let input2 = BakeInput {
        vertices: &moved,
        ..input
    };
    assert_eq!(
        bake_cached(&input2, &settings(), Some(dir.path()))
            .unwrap()
            .1,
        BakeOutcome::Baked
    );
    assert_eq!(
        bake_cached(&input2, &settings(), Some(dir.path()))
            .unwrap()
            .1,
        BakeOutcome::Cached
    );
}

#[test]
fn damaged_files_are_baked_again_not_trusted() {
    let dir = tempfile::tempdir().unwrap();
    let (v, s, t) = tiny();
    let input = BakeInput {
        vertices: &v,
        strands: &s,
        triangles: &t,
    };
    let (good, _) = bake_cached(&input, &settings(), Some(dir.path())).unwrap();
    let k = key(&input, &settings());
    let file = path(dir.path(), &k);
    let bytes = std::fs::read(&file).unwrap();
    let damages: Vec<(&str, Vec<u8>)> = vec![
        ("truncated", bytes[..bytes.len() - 7].to_vec()),
        ("empty", Vec::new()),
        ("flipped payload bit", {
            let mut b = bytes.clone();
            b[crate::blob::HEADER + 5] ^= 0x10;
            b
        }),
        ("bad magic", {
            let mut b = bytes.clone();
            b[0] = b'X';
            b
        }),
        ("huge count in header", {
            let mut b = bytes.clone();
            b[12..20].copy_from_slice(&u64::MAX.to_le_bytes());
            b
        }),
    ];
    for (what, damaged) in damages {
        std::fs::write(&file, &damaged).unwrap();
        assert!(
            read(&file, &k, v.len()).is_err(),
            "{what}: a damaged file must be rejected"
        );
        let (again, outcome) = bake_cached(&input, &settings(), Some(dir.path())).unwrap();
        assert_eq!(outcome, BakeOutcome::Baked, "{what}");
        assert_eq!(again, good, "{what}");
        // ... and the re-bake repaired the file.
        assert_eq!(
            read(&file, &k, v.len()).unwrap(),
            Some(good.clone()),
            "{what}"
        );
    }
}

#[test]
fn cache_dir_precedence() {
    let env = |pairs: &'static [(&'static str, &'static str)]| {
        move |k: &str| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| OsString::from(v))
        }
    };
    let all = env(&[
        ("STRANDGRAPH_CACHE", "/a"),
        ("XDG_CACHE_HOME", "/b"),
        ("HOME", "/c"),
    ]);
    assert_eq!(cache_dir_from(all), Some(PathBuf::from("/a")));
    let xdg = env(&[
        ("STRANDGRAPH_CACHE", ""),
        ("XDG_CACHE_HOME", "/b"),
        ("HOME", "/c"),
    ]);
    assert_eq!(cache_dir_from(xdg), Some(PathBuf::from("/b/strandgraph")));
    let home = env(&[("HOME", "/c")]);
    assert_eq!(
        cache_dir_from(home),
        Some(PathBuf::from("/c/.cache/strandgraph"))
    );
    assert_eq!(cache_dir_from(env(&[])), None);
}
