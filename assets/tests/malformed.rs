//! Every loader rejects every kind of bad input with an error that says what and where,
//! and never panics.

use glam::Vec3;
use strandgraph_assets::error::{FormatError, FormatErrorKind, Location};
use strandgraph_assets::groom::Groom;
use strandgraph_assets::loaders::{cyhair, obj, tfx2, tfx3, tfx4};

fn small_groom() -> Groom {
    Groom::from_strands(
        (0..3).map(|s| {
            (0..4)
                .map(|i| Vec3::new(s as f32, i as f32, 0.5))
                .collect::<Vec<_>>()
        }),
        1e-4,
    )
}

fn cyhair_file() -> Vec<u8> {
    cyhair::write(&small_groom()).unwrap()
}
fn tfx4_file() -> Vec<u8> {
    tfx4::write(&small_groom()).unwrap()
}
/// A TressFX 3 file: 296-byte header, float3 positions at 296.
fn tfx3_file() -> Vec<u8> {
    let g = small_groom();
    let mut b = vec![0u8; 296];
    b[0..4].copy_from_slice(&3.0f32.to_le_bytes());
    b[4..8].copy_from_slice(&3u32.to_le_bytes());
    b[8..12].copy_from_slice(&4u32.to_le_bytes());
    b[144..148].copy_from_slice(&296u32.to_le_bytes());
    for p in &g.positions {
        for v in p.to_array() {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    b
}
fn tfx2_file() -> String {
    tfx2::write(&small_groom())
}
const OBJ: &str = "o tri\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n";

fn put_u32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}
fn put_f32(b: &mut [u8], at: usize, v: f32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

type Parse = fn(&[u8]) -> Result<Groom, FormatError>;
/// (name, parser, file, strands field offset, points field offset, first position byte)
type BinaryCase = (&'static str, Parse, Vec<u8>, usize, usize, usize);

fn binary_formats() -> Vec<BinaryCase> {
    vec![
        (
            "cyhair",
            cyhair::parse as Parse,
            cyhair_file(),
            4,
            8,
            128 + 3 * 2,
        ),
        ("tfx4", tfx4::parse as Parse, tfx4_file(), 4, 8, 160),
        ("tfx3", tfx3::parse as Parse, tfx3_file(), 4, 8, 296),
    ]
}

#[test]
fn valid_files_parse() {
    for (name, parse, file, ..) in binary_formats() {
        let g = parse(&file).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(g.strand_count(), 3, "{name}");
        assert_eq!(g.point_count(), 12, "{name}");
    }
    assert_eq!(
        tfx2::parse(tfx2_file().as_bytes()).unwrap().point_count(),
        12
    );
    assert_eq!(obj::parse(OBJ.as_bytes()).unwrap().triangle_count(), 2);
}

#[test]
fn truncated_files_fail_with_offset_at_every_length() {
    for (name, parse, file, ..) in binary_formats() {
        for len in 0..file.len() {
            let e = parse(&file[..len]).expect_err(name);
            let Location::Byte(at) = e.location else {
                panic!("{name}: {e} has no byte offset");
            };
            assert!(at <= len, "{name}: offset {at} beyond length {len}");
            assert!(
                matches!(
                    e.kind,
                    FormatErrorKind::Truncated { .. } | FormatErrorKind::CountExceedsFile { .. }
                ),
                "{name} cut at {len}: {e}"
            );
        }
    }
    let text = tfx2_file();
    let lines: Vec<&str> = text.lines().collect();
    for n in 1..lines.len() {
        let cut = lines[..n].join("\n");
        let e = tfx2::parse(cut.as_bytes()).expect_err("tfx2 truncated");
        assert!(
            matches!(e.location, Location::Line(_) | Location::LineCol(..)),
            "{e}"
        );
    }
    // An OBJ cut before its vertices: the face refers to vertices that are not there.
    let e = obj::parse(b"v 0 0 0\nf 1 2 3\n").unwrap_err();
    assert_eq!(e.location, Location::LineCol(2, 5), "{e}");
}

#[test]
fn counts_exceeding_the_file_are_rejected_before_allocation() {
    for (name, parse, file, strands_at, _, _) in binary_formats() {
        let mut b = file.clone();
        put_u32(&mut b, strands_at, 1_000_000); // plausible, but far larger than the file
        let e = parse(&b).unwrap_err();
        assert!(
            matches!(e.kind, FormatErrorKind::CountExceedsFile { .. }),
            "{name}: {e}"
        );
        assert!(matches!(e.location, Location::Byte(_)), "{name}: {e}");
    }
    // tfx2: numStrands larger than the lines left.
    let t = tfx2_file().replace("numStrands 3", "numStrands 900000");
    let e = tfx2::parse(t.as_bytes()).unwrap_err();
    assert!(
        matches!(e.kind, FormatErrorKind::CountExceedsFile { .. }),
        "{e}"
    );
    assert_eq!(e.location, Location::Line(9));
    let t = tfx2_file().replacen("numVerts 4", "numVerts 4000", 1);
    let e = tfx2::parse(t.as_bytes()).unwrap_err();
    assert!(
        matches!(e.kind, FormatErrorKind::CountExceedsFile { .. }),
        "{e}"
    );
    assert_eq!(e.location, Location::LineCol(11, 19));
}

#[test]
fn zero_counts_are_rejected() {
    for (name, parse, file, strands_at, points_at, _) in binary_formats() {
        for at in [strands_at, points_at] {
            let mut b = file.clone();
            put_u32(&mut b, at, 0);
            let e = parse(&b).unwrap_err();
            assert!(
                matches!(e.kind, FormatErrorKind::ZeroCount { .. }),
                "{name}: {e}"
            );
            assert_eq!(e.location, Location::Byte(at), "{name}");
        }
    }
    let t = tfx2_file().replace("numStrands 3", "numStrands 0");
    let e = tfx2::parse(t.as_bytes()).unwrap_err();
    assert!(matches!(e.kind, FormatErrorKind::ZeroCount { .. }), "{e}");
    let t = tfx2_file().replacen("numVerts 4", "numVerts 0", 1);
    let e = tfx2::parse(t.as_bytes()).unwrap_err();
    assert!(matches!(e.kind, FormatErrorKind::ZeroCount { .. }), "{e}");
    let e = obj::parse(b"# nothing\n").unwrap_err();
    assert!(matches!(e.kind, FormatErrorKind::ZeroCount { .. }), "{e}");
    let e = obj::parse(b"v 0 0 0\nv 1 0 0\n").unwrap_err();
    assert!(matches!(e.kind, FormatErrorKind::ZeroCount { .. }), "{e}");
}

#[test]
fn absurd_counts_are_rejected() {
    for (name, parse, file, strands_at, points_at, _) in binary_formats() {
        for at in [strands_at, points_at] {
            let mut b = file.clone();
            put_u32(&mut b, at, u32::MAX);
            let e = parse(&b).unwrap_err();
            assert!(
                matches!(e.kind, FormatErrorKind::AbsurdCount { .. }),
                "{name}: {e}"
            );
            assert_eq!(e.location, Location::Byte(at), "{name}");
        }
    }
    let t = tfx2_file().replace("numStrands 3", "numStrands 99999999999");
    let e = tfx2::parse(t.as_bytes()).unwrap_err();
    assert!(matches!(e.kind, FormatErrorKind::AbsurdCount { .. }), "{e}");
    let e = obj::parse(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4000000000\n").unwrap_err();
    assert_eq!(e.location, Location::LineCol(4, 7), "{e}");
}

#[test]
fn nan_and_inf_positions_are_rejected() {
    for (name, parse, file, _, _, pos_at) in binary_formats() {
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let mut b = file.clone();
            let at = pos_at + 4 * 7; // a coordinate of the third point or so
            put_f32(&mut b, at, bad);
            let e = parse(&b).unwrap_err();
            assert!(
                matches!(e.kind, FormatErrorKind::NonFinite { .. }),
                "{name}: {e}"
            );
            assert_eq!(e.location, Location::Byte(at), "{name}");
        }
    }
    for bad in ["NaN", "inf", "-inf"] {
        let t = tfx2_file();
        let mut lines: Vec<String> = t.lines().map(String::from).collect();
        lines[11] = format!("0 {bad} 0");
        let e = tfx2::parse(lines.join("\n").as_bytes()).unwrap_err();
        assert!(matches!(e.kind, FormatErrorKind::NonFinite { .. }), "{e}");
        assert_eq!(e.location, Location::LineCol(12, 3));
        let o = OBJ.replace("v 1 0 0", &format!("v 1 {bad} 0"));
        let e = obj::parse(o.as_bytes()).unwrap_err();
        assert!(matches!(e.kind, FormatErrorKind::NonFinite { .. }), "{e}");
        assert_eq!(e.location, Location::LineCol(3, 5));
    }
}

#[test]
fn wrong_magic_is_rejected() {
    let mut b = cyhair_file();
    b[0..4].copy_from_slice(b"HAIX");
    let e = cyhair::parse(&b).unwrap_err();
    assert!(matches!(e.kind, FormatErrorKind::BadMagic { .. }), "{e}");
    assert_eq!(e.location, Location::Byte(0));
    // A TressFX 3 file given to the TressFX 4 parser and vice versa.
    let e = tfx4::parse(&tfx3_file()).unwrap_err();
    assert!(matches!(e.kind, FormatErrorKind::BadMagic { .. }), "{e}");
    let e = tfx3::parse(&tfx4_file()).unwrap_err();
    assert!(matches!(e.kind, FormatErrorKind::BadMagic { .. }), "{e}");
    let e = tfx2::parse(b"HAIR binary stuff").unwrap_err();
    assert!(matches!(e.kind, FormatErrorKind::BadMagic { .. }), "{e}");
    assert_eq!(e.location, Location::Line(1));
    let e = obj::parse(&[0xff, 0xfe, 0, 1]).unwrap_err();
    assert_eq!(e.location, Location::Byte(0), "{e}");
}

#[test]
fn inconsistent_headers_are_rejected() {
    // cyHair segments that do not add up to point_count.
    let mut b = cyhair_file();
    put_u32(&mut b, 8, 11);
    let e = cyhair::parse(&b).unwrap_err();
    assert!(matches!(e.kind, FormatErrorKind::Inconsistent(_)), "{e}");
    // cyHair without a points array.
    let mut b = cyhair_file();
    put_u32(&mut b, 12, 1);
    assert!(cyhair::parse(&b).is_err());
    // TressFX 4 position offset pointing into the header.
    let mut b = tfx4_file();
    put_u32(&mut b, 12, 8);
    let e = tfx4::parse(&b).unwrap_err();
    assert_eq!(e.location, Location::Byte(12), "{e}");
    // TressFX 2 coordinate that is not a number, reported with line and column.
    let t = tfx2_file().replacen("0 0.5", "0 zz", 1);
    let e = tfx2::parse(t.as_bytes()).unwrap_err();
    assert!(matches!(e.kind, FormatErrorKind::Syntax(_)), "{e}");
    assert!(matches!(e.location, Location::LineCol(12, _)), "{e}");
    // OBJ face texcoord and normal indices out of range.
    let e = obj::parse(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/5 2/1 3/1\n").unwrap_err();
    assert_eq!(e.location, Location::LineCol(5, 3), "{e}");
    let e = obj::parse(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//9 2//1 3//1\n").unwrap_err();
    assert_eq!(e.location, Location::LineCol(4, 3), "{e}");
    // OBJ face with two vertices.
    let e = obj::parse(b"v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap_err();
    assert_eq!(e.location, Location::Line(3), "{e}");
}

#[test]
fn tfx2_accepts_what_the_reference_tools_accept() {
    let t = tfx2_file().replace("texcoord 0 0", "texcoord 0.000000 000000");
    let g = tfx2::parse(t.as_bytes()).unwrap();
    assert_eq!(g.strand_count(), 3);
}

#[test]
fn header_defaults_fill_absent_cyhair_arrays() {
    // Only points: segments, thickness, transparency and colour come from the header.
    let mut b = vec![0u8; 128];
    b[0..4].copy_from_slice(b"HAIR");
    put_u32(&mut b, 4, 2);
    put_u32(&mut b, 8, 6);
    put_u32(&mut b, 12, cyhair::BIT_POINTS);
    put_u32(&mut b, 16, 2);
    put_f32(&mut b, 20, 0.25);
    put_f32(&mut b, 24, 0.5);
    put_f32(&mut b, 28, 0.1);
    put_f32(&mut b, 32, 0.2);
    put_f32(&mut b, 36, 0.3);
    for i in 0..18 {
        b.extend_from_slice(&(i as f32).to_le_bytes());
    }
    let g = cyhair::parse(&b).unwrap();
    assert_eq!(g.strand_count(), 2);
    assert_eq!(g.strand_offsets, vec![0, 3, 6]);
    assert!(g.thickness.iter().all(|&t| t == 0.25));
    assert!(g.transparency.unwrap().iter().all(|&t| t == 0.5));
    assert!(
        g.colors
            .unwrap()
            .iter()
            .all(|&c| c == Vec3::new(0.1, 0.2, 0.3))
    );
    // d_segments that do not match point_count.
    put_u32(&mut b, 16, 3);
    let e = cyhair::parse(&b).unwrap_err();
    assert_eq!(e.location, Location::Byte(16), "{e}");
}

mod no_panics {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

        #[test]
        fn random_bytes_never_panic(data in proptest::collection::vec(any::<u8>(), 0..600)) {
            let _ = cyhair::parse(&data);
            let _ = tfx2::parse(&data);
            let _ = tfx3::parse(&data);
            let _ = tfx4::parse(&data);
            let _ = obj::parse(&data);
        }

        #[test]
        fn corrupted_valid_files_never_panic(at in 0usize..400, byte in any::<u8>()) {
            for (_, parse, mut file, ..) in binary_formats() {
                let i = at % file.len();
                file[i] = byte;
                let _ = parse(&file);
            }
            let mut t = tfx2_file().into_bytes();
            let i = at % t.len();
            t[i] = byte;
            let _ = tfx2::parse(&t);
        }
    }
}
