//! Hair styles: each a set of defaults for the groom generator, in the
//! procedural head's frame (metres; y up, +z the face; see `HeadParams`).

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::surface::Region;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Style {
    /// Shoulder-length, straight, parted in the middle.
    Straight,
    /// Below the shoulders, in soft waves, parted on the left.
    Wavy,
    /// Ringlets: clumps coiled as helices.
    Curly,
    /// Long straight hair to the chest, side-parted, falling over the shoulders.
    Long,
    /// Chin-length, cut level all round.
    Bob,
    /// A short crop, combed out from the crown.
    Short,
    /// Gathered at the back of the head and falling from the tie.
    Ponytail,
    /// Gathered high at the back and coiled into a bun.
    Bun,
    Beard,
    Eyebrows,
    Eyelashes,
    /// Short fur over a whole body.
    Fur,
}

/// How strands leave the skin: the direction a comb pulls them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Comb {
    /// Away from a parting at this x, swept back; at the front more to the side,
    /// so the face stays clear.
    Parted(f32),
    /// Out from a crown point (short crops).
    FromCrown,
    /// Along a fixed head-frame direction (beards, fur, eyelashes).
    Along(Vec3),
    /// Out towards the temples (eyebrows).
    Temples,
}

/// Gathering strands at a tie (ponytail) and optionally coiling them (bun).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gather {
    pub tie: Vec3,
    pub bun: bool,
}

/// Every generator setting, resolved from a style's defaults and the scene's
/// overrides.
#[derive(Debug, Clone, Copy)]
pub struct Resolved {
    pub region: Region,
    /// Strand length (metres) and its random variation (0.2 = up to 20% shorter).
    pub length: f32,
    pub length_variation: f32,
    pub root_thickness: f32,
    pub tip_thickness: f32,
    /// Curvature (radians per metre) that bends strands towards `bend`.
    pub gravity: f32,
    pub bend: Vec3,
    /// How much strands leave along the normal (1) rather than the comb (0).
    pub lift: f32,
    pub comb: Comb,
    /// Largest height above the skin of a strand's inner layer (hair volume).
    pub volume: f32,
    pub wave_amplitude: f32,
    pub wave_frequency: f32,
    pub curl_radius: f32,
    pub curl_frequency: f32,
    /// Random high-frequency displacement at the tips (metres).
    pub frizz: f32,
    /// Fraction of strands that leave their clump.
    pub stray_fraction: f32,
    /// How far children are pulled to their guide at the tip (0 none, 1 all).
    pub clump: f32,
    /// Clump profile exponent: below 1 clumps form early, above 1 at the tips.
    pub clump_profile: f32,
    /// Strands per guide; 1 grows every strand on its own (short facial hair, fur).
    pub strands_per_guide: u32,
    /// Strands are cut level at this height (bob).
    pub cut_height: Option<f32>,
    pub gather: Option<Gather>,
}

impl Style {
    /// The style's defaults.
    pub fn defaults(self) -> Resolved {
        let scalp = Resolved {
            region: Region::Scalp,
            length: 0.3,
            length_variation: 0.12,
            root_thickness: 70e-6,
            tip_thickness: 25e-6,
            gravity: 14.0,
            bend: Vec3::NEG_Y,
            lift: 0.06,
            comb: Comb::Parted(0.0),
            volume: 0.012,
            wave_amplitude: 0.0,
            wave_frequency: 0.0,
            curl_radius: 0.0,
            curl_frequency: 0.0,
            frizz: 0.0012,
            stray_fraction: 0.01,
            clump: 0.5,
            clump_profile: 1.5,
            strands_per_guide: 40,
            cut_height: None,
            gather: None,
        };
        let single = Resolved {
            strands_per_guide: 1,
            clump: 0.0,
            stray_fraction: 0.0,
            volume: 0.0,
            ..scalp
        };
        match self {
            Style::Straight => scalp,
            Style::Wavy => Resolved {
                length: 0.38,
                comb: Comb::Parted(-0.022),
                volume: 0.016,
                wave_amplitude: 0.01,
                wave_frequency: 6.0,
                ..scalp
            },
            Style::Curly => Resolved {
                length: 0.26,
                length_variation: 0.18,
                gravity: 9.0,
                lift: 0.35,
                volume: 0.03,
                curl_radius: 0.007,
                curl_frequency: 20.0,
                frizz: 0.002,
                clump: 0.8,
                clump_profile: 0.6,
                root_thickness: 80e-6,
                ..scalp
            },
            Style::Long => Resolved {
                length: 0.5,
                comb: Comb::Parted(0.025),
                wave_amplitude: 0.003,
                wave_frequency: 4.0,
                clump: 0.55,
                ..scalp
            },
            Style::Bob => Resolved {
                length: 0.32,
                length_variation: 0.04,
                comb: Comb::Parted(0.02),
                volume: 0.015,
                clump: 0.35,
                cut_height: Some(-0.095),
                ..scalp
            },
            Style::Short => Resolved {
                length: 0.035,
                length_variation: 0.25,
                gravity: 4.0,
                lift: 0.45,
                comb: Comb::FromCrown,
                volume: 0.004,
                clump: 0.3,
                strands_per_guide: 12,
                root_thickness: 80e-6,
                ..scalp
            },
            Style::Ponytail => Resolved {
                length: 0.45,
                length_variation: 0.08,
                lift: 0.05,
                volume: 0.004,
                wave_amplitude: 0.003,
                wave_frequency: 5.0,
                gather: Some(Gather {
                    tie: Vec3::new(0.0, 0.03, -0.108),
                    bun: false,
                }),
                ..scalp
            },
            Style::Bun => Resolved {
                length: 0.36,
                length_variation: 0.05,
                lift: 0.05,
                volume: 0.004,
                clump: 0.3,
                gather: Some(Gather {
                    tie: Vec3::new(0.0, 0.075, -0.1),
                    bun: true,
                }),
                ..scalp
            },
            Style::Beard => Resolved {
                region: Region::Beard,
                length: 0.022,
                length_variation: 0.3,
                gravity: 20.0,
                lift: 0.45,
                comb: Comb::Along(Vec3::new(0.0, -1.0, 0.25)),
                curl_radius: 0.0022,
                curl_frequency: 45.0,
                frizz: 0.0012,
                root_thickness: 100e-6,
                tip_thickness: 40e-6,
                ..single
            },
            Style::Eyebrows => Resolved {
                region: Region::Eyebrows,
                length: 0.011,
                length_variation: 0.25,
                gravity: 0.0,
                lift: 0.2,
                comb: Comb::Temples,
                frizz: 0.0003,
                root_thickness: 90e-6,
                tip_thickness: 30e-6,
                ..single
            },
            Style::Eyelashes => Resolved {
                region: Region::Eyelashes,
                length: 0.009,
                length_variation: 0.25,
                // Lashes curl up, not down.
                gravity: 90.0,
                bend: Vec3::Y,
                lift: 0.3,
                comb: Comb::Along(Vec3::new(0.0, 0.2, 1.0)),
                frizz: 0.0,
                root_thickness: 80e-6,
                tip_thickness: 20e-6,
                ..single
            },
            Style::Fur => Resolved {
                region: Region::Everywhere,
                length: 0.02,
                length_variation: 0.15,
                gravity: 4.0,
                lift: 0.6,
                comb: Comb::Along(Vec3::new(0.0, -0.3, -1.0)),
                frizz: 0.001,
                root_thickness: 60e-6,
                tip_thickness: 18e-6,
                ..single
            },
        }
    }
}
