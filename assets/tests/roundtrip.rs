//! Property tests: write a groom, read it back.

use glam::{Vec2, Vec3};
use proptest::prelude::*;
use strandgraph_assets::groom::Groom;
use strandgraph_assets::loaders::{cyhair, tfx2, tfx4};

fn coord() -> impl Strategy<Value = f32> {
    -10.0f32..10.0
}

/// Strands of 2..12 points each (variable counts).
fn variable_groom() -> impl Strategy<Value = Groom> {
    proptest::collection::vec(
        proptest::collection::vec((coord(), coord(), coord(), 1e-6f32..1e-3), 2..12),
        1..20,
    )
    .prop_map(|strands| {
        let mut g = Groom::from_strands(
            strands.iter().map(|s| {
                s.iter()
                    .map(|&(x, y, z, _)| Vec3::new(x, y, z))
                    .collect::<Vec<_>>()
            }),
            0.0,
        );
        g.thickness = strands.iter().flatten().map(|p| p.3).collect();
        g
    })
}

/// Strands of one fixed point count, constant thickness per strand, with strand UVs.
fn fixed_groom() -> impl Strategy<Value = Groom> {
    (2usize..10, 1usize..20).prop_flat_map(|(n, s)| {
        (
            proptest::collection::vec((coord(), coord(), coord()), n * s),
            proptest::collection::vec((0.0f32..1.0, 0.0f32..1.0, 1e-6f32..1e-3), s),
        )
            .prop_map(move |(pts, per_strand)| {
                let mut g = Groom::from_strands(
                    pts.chunks(n).map(|c| {
                        c.iter()
                            .map(|&(x, y, z)| Vec3::new(x, y, z))
                            .collect::<Vec<_>>()
                    }),
                    0.0,
                );
                g.thickness = per_strand
                    .iter()
                    .flat_map(|p| std::iter::repeat_n(p.2, n))
                    .collect();
                g.strand_uvs = Some(per_strand.iter().map(|p| Vec2::new(p.0, p.1)).collect());
                g
            })
    })
}

proptest! {
    #[test]
    fn cyhair_round_trip(mut g in variable_groom(), with_colour in any::<bool>()) {
        if with_colour {
            g.colors = Some(g.positions.iter().map(|p| p.abs() / 10.0).collect());
            g.transparency = Some(vec![0.25; g.point_count()]);
        }
        let back = cyhair::parse(&cyhair::write(&g).unwrap()).unwrap();
        prop_assert_eq!(&back.positions, &g.positions);
        prop_assert_eq!(&back.thickness, &g.thickness);
        prop_assert_eq!(&back.strand_offsets, &g.strand_offsets);
        if with_colour {
            prop_assert_eq!(&back.colors, &g.colors);
            prop_assert_eq!(&back.transparency, &g.transparency);
        }
    }

    #[test]
    fn tfx4_round_trip(g in fixed_groom()) {
        let back = tfx4::parse(&tfx4::write(&g).unwrap()).unwrap();
        prop_assert_eq!(back, g);
    }

    #[test]
    fn tfx2_round_trip(g in variable_groom()) {
        let back = tfx2::parse(tfx2::write(&g).as_bytes()).unwrap();
        prop_assert_eq!(&back.positions, &g.positions);
        prop_assert_eq!(&back.strand_offsets, &g.strand_offsets);
    }
}

#[test]
fn tfx4_refuses_variable_strands() {
    let g = Groom::from_strands([vec![Vec3::ZERO; 2], vec![Vec3::ONE; 3]], 1e-4);
    assert!(tfx4::write(&g).is_err());
}
