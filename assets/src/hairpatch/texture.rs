//! The hair patches' texture, generated. Scheuermann 2004, "Hair Model - Textures":
//! "Base texture - Stretched noise; Alpha texture - should have fully opaque regions;
//! Specular shift texture; Specular noise texture". Each of the `VARIANTS` columns is a
//! clump of individual strands 1-2 texels wide: an opaque core band, single strands with
//! gaps towards the edges, and every strand ending at its own length near the tip so tips
//! are wispy.

/// Procedural hair textures, Scheuermann 2004 "Hair Model - Textures": base texture
/// (stretched noise), alpha texture (should have fully opaque regions), specular shift
/// texture, specular noise texture; packed as RGBA8 texels: r = base, g = alpha,
/// b = shift, a = specular noise (sparkle mask).
#[derive(Debug, Clone, PartialEq)]
pub struct HairTexture {
    /// Mip levels along u only (v keeps HEIGHT rows in every level: strands run along v,
    /// so the footprint across them is what grows with distance). Level l is
    /// (WIDTH >> l) x HEIGHT, levels stored back to back, row-major (row = v), level 0 first.
    pub texels: Vec<[u8; 4]>,
}

/// A PCG hash (O'Neill's RXS-M-XS output on an LCG step) of a seed and some words:
/// stateless and spelled out here so textures never change with a crate's version.
pub(crate) fn hash(seed: u64, parts: &[u32]) -> u32 {
    let pcg = |x: u32| {
        let state = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
        let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
        (word >> 22) ^ word
    };
    let mut h = pcg(seed as u32 ^ pcg((seed >> 32) as u32));
    for &p in parts {
        h = pcg(h ^ p);
    }
    h
}

/// A hash as a float in [0, 1).
fn unit(seed: u64, parts: &[u32]) -> f32 {
    (hash(seed, parts) >> 8) as f32 / (1u32 << 24) as f32
}

/// Salts that keep the hashes of the texture's different random choices apart.
#[derive(Clone, Copy)]
enum Salt {
    Layout = 1,
    Brightness,
    Shift,
    TipLength,
    Noise,
    Sparkle,
    Band,
}

/// One strand of a variant: its columns and its random attributes.
struct Strand {
    id: u32,
    brightness: f32,
    shift: f32,
    tip: f32,
}

impl HairTexture {
    /// u texels, across VARIANTS clump patterns side by side.
    pub const WIDTH: u32 = 512;
    /// v texels root → tip.
    pub const HEIGHT: u32 = 128;
    /// 512 .. 1 along u.
    pub const LEVELS: u32 = 10;
    /// Clump patterns across u, each 128 texels wide.
    pub const VARIANTS: u32 = 4;

    const COLUMNS: u32 = Self::WIDTH / Self::VARIANTS;
    /// Strands fade out over this fraction of the length before they end.
    const TAPER: f32 = 0.04;

    /// Index of the first texel of `level` (`LEVELS` gives the total texel count).
    pub fn level_offset(level: u32) -> usize {
        (0..level.min(Self::LEVELS))
            .map(|l| ((Self::WIDTH >> l) * Self::HEIGHT) as usize)
            .sum()
    }

    /// The texture for `seed`, all mip levels.
    pub fn generate(seed: u64) -> HairTexture {
        let mut texels = vec![[0u8; 4]; Self::level_offset(Self::LEVELS)];
        let w = Self::WIDTH as usize;
        for variant in 0..Self::VARIANTS {
            let columns = strand_columns(seed, variant);
            for y in 0..Self::HEIGHT {
                let row = &mut texels[y as usize * w..(y as usize + 1) * w];
                let x0 = (variant * Self::COLUMNS) as usize;
                for (x, texel) in row[x0..x0 + Self::COLUMNS as usize].iter_mut().enumerate() {
                    *texel = texel_at(seed, variant, x as u32, y, &columns[x]);
                }
            }
        }
        for l in 1..Self::LEVELS {
            let (src, dst) = (Self::level_offset(l - 1), Self::level_offset(l));
            let (sw, dw) = (
                (Self::WIDTH >> (l - 1)) as usize,
                (Self::WIDTH >> l) as usize,
            );
            for y in 0..Self::HEIGHT as usize {
                for x in 0..dw {
                    let a = texels[src + y * sw + 2 * x];
                    let b = texels[src + y * sw + 2 * x + 1];
                    texels[dst + y * dw + x] = average(a, b);
                }
            }
        }
        HairTexture { texels }
    }
}

impl HairTexture {
    /// The level-0 columns that lie on one of the texture's strands (not in
    /// a gap or on a variant's border), left to right.
    pub fn strand_columns(seed: u64) -> Vec<u32> {
        (0..Self::VARIANTS)
            .flat_map(|variant| {
                strand_columns(seed, variant)
                    .into_iter()
                    .enumerate()
                    .filter(|(_, c)| matches!(c, Some((_, true))))
                    .map(move |(x, _)| variant * Self::COLUMNS + x as u32)
            })
            .collect()
    }
}

/// The box average of two texels, rounding to nearest (halves up).
fn average(a: [u8; 4], b: [u8; 4]) -> [u8; 4] {
    [0, 1, 2, 3].map(|c| (a[c] as u16 + b[c] as u16).div_ceil(2) as u8)
}

/// What covers each column of a variant: `Some((strand, true))` on a strand,
/// `Some((strand, false))` in a gap after it (opaque only in the core band and at the
/// root), `None` on the variant's border columns, which stay transparent so variants
/// never bleed into each other.
fn strand_columns(seed: u64, variant: u32) -> Vec<Option<(Strand, bool)>> {
    let cols = HairTexture::COLUMNS;
    let mut out: Vec<Option<(Strand, bool)>> = vec![None];
    let mut id = 0;
    while out.len() < cols as usize - 1 {
        let r = hash(seed, &[Salt::Layout as u32, variant, id]);
        let (width, gap) = (1 + (r & 1), [0, 1, 1, 2][(r >> 1) as usize & 3]);
        let strand = |id| Strand {
            id,
            brightness: 0.6 + 0.4 * unit(seed, &[Salt::Brightness as u32, variant, id]),
            shift: unit(seed, &[Salt::Shift as u32, variant, id]),
            tip: 0.75 + 0.25 * unit(seed, &[Salt::TipLength as u32, variant, id]),
        };
        for covered in (0..width + gap).map(|k| k < width) {
            if out.len() < cols as usize - 1 {
                out.push(Some((strand(id), covered)));
            }
        }
        id += 1;
    }
    out.push(None);
    out
}

/// One texel of a variant at level 0.
fn texel_at(seed: u64, variant: u32, x: u32, y: u32, column: &Option<(Strand, bool)>) -> [u8; 4] {
    let Some((s, on_strand)) = column else {
        return [0; 4];
    };
    let v = (y as f32 + 0.5) / HairTexture::HEIGHT as f32;
    let opaque = *on_strand || in_core(seed, variant, x, v) || v < 0.06;
    let length = ((s.tip - v) / HairTexture::TAPER).clamp(0.0, 1.0);
    let alpha = if opaque { length } else { 0.0 };
    // Stretched noise: slow value noise along the strand, none across it.
    let base = s.brightness * (0.85 + 0.3 * value_noise(seed, Salt::Noise, variant, s.id, v, 6.0));
    let sparkle = if *on_strand {
        sparkle(seed, variant, s.id, v)
    } else {
        0.0
    };
    [base, alpha, s.shift, sparkle].map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// Whether column `x` lies in the variant's opaque core at `v`: a band about the middle
/// whose half-width (14..34 texels) wanders slowly along v and narrows towards the tip.
fn in_core(seed: u64, variant: u32, x: u32, v: f32) -> bool {
    let centre = 64.0 + 12.0 * (unit(seed, &[Salt::Band as u32, variant, 0]) - 0.5);
    let base = 14.0 + 20.0 * unit(seed, &[Salt::Band as u32, variant, 1]);
    let wander = 8.0 * (value_noise(seed, Salt::Band, variant, 2, v, 3.0) - 0.5);
    let half = (base + wander) * (1.0 - 0.5 * v);
    (x as f32 + 0.5 - centre).abs() < half
}

/// Smooth 1D value noise in [0, 1] along v with `cells` lattice cells over the length.
fn value_noise(seed: u64, salt: Salt, variant: u32, id: u32, v: f32, cells: f32) -> f32 {
    let x = v * cells;
    let (i, f) = (x.floor(), x - x.floor());
    let at = |k: f32| unit(seed, &[salt as u32, variant, id, k as u32]);
    let s = f * f * (3.0 - 2.0 * f);
    at(i) + (at(i + 1.0) - at(i)) * s
}

/// The secondary highlight's sparkle mask: along each strand, one in four stretches of
/// 1/16 of the length carries a streak (a bright tent 3..9 texels long), else 0.
fn sparkle(seed: u64, variant: u32, id: u32, v: f32) -> f32 {
    let x = v * 16.0;
    let cell = x.floor() as u32;
    let h = hash(seed, &[Salt::Sparkle as u32, variant, id, cell]);
    if h & 3 != 0 {
        return 0.0;
    }
    let centre = 0.25 + 0.5 * ((h >> 8) & 0xff) as f32 / 255.0;
    let half = (1.5 + 3.0 * ((h >> 16) & 0xff) as f32 / 255.0) / 8.0; // in cells (8 texels)
    let d = (x - cell as f32 - centre).abs() / half;
    (1.0 - d).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(t: &HairTexture, l: u32) -> (&[[u8; 4]], usize) {
        let w = (HairTexture::WIDTH >> l) as usize;
        let o = HairTexture::level_offset(l);
        (&t.texels[o..o + w * HairTexture::HEIGHT as usize], w)
    }

    #[test]
    fn layout_and_mips() {
        let t = HairTexture::generate(7);
        assert_eq!(HairTexture::level_offset(0), 0);
        assert_eq!(HairTexture::level_offset(1), 512 * 128);
        assert_eq!(t.texels.len(), 1023 * 128);
        assert_eq!(
            HairTexture::level_offset(HairTexture::LEVELS),
            t.texels.len()
        );
        for l in 1..HairTexture::LEVELS {
            let ((a, aw), (b, bw)) = (level(&t, l - 1), level(&t, l));
            for y in 0..HairTexture::HEIGHT as usize {
                for x in 0..bw {
                    for c in 0..4 {
                        let (p, q) = (a[y * aw + 2 * x][c] as u32, a[y * aw + 2 * x + 1][c] as u32);
                        assert_eq!(b[y * bw + x][c] as u32, (p + q).div_ceil(2), "{l} {x} {y}");
                    }
                }
            }
        }
        assert_eq!(t, HairTexture::generate(7));
        assert_ne!(t, HairTexture::generate(8));
    }

    #[test]
    fn alpha_has_borders_core_gaps_and_wispy_tips() {
        let t = HairTexture::generate(3);
        let (l0, w) = level(&t, 0);
        let alpha = |x: u32, y: u32| l0[y as usize * w + x as usize][1];
        for v in 0..HairTexture::VARIANTS {
            let x0 = v * HairTexture::COLUMNS;
            let x1 = x0 + HairTexture::COLUMNS - 1;
            assert!((0..HairTexture::HEIGHT).all(|y| alpha(x0, y) == 0 && alpha(x1, y) == 0));
            // At mid length: an opaque run of 20+ texels, and gaps towards the edges.
            let y = HairTexture::HEIGHT / 2;
            let (mut run, mut best) = (0, 0);
            for x in x0..=x1 {
                run = if alpha(x, y) == 255 { run + 1 } else { 0 };
                best = best.max(run);
            }
            assert!(best >= 20, "variant {v}: {best}");
            assert!((x0 + 1..x0 + 24).any(|x| alpha(x, y) == 0), "variant {v}");
            // Fully opaque inside near the root; strands end one by one near the tip.
            let columns = strand_columns(3, v);
            assert!((x0 + 1..x1).all(|x| alpha(x, 2) == 255));
            let ends: Vec<u32> = (x0 + 1..x1)
                .filter(|&x| columns[(x - x0) as usize].as_ref().is_some_and(|c| c.1))
                .filter_map(|x| (0..HairTexture::HEIGHT).rev().find(|&y| alpha(x, y) > 0))
                .collect();
            let (lo, hi) = (ends.iter().min().unwrap(), ends.iter().max().unwrap());
            assert!(*lo >= 90 && *hi <= 127 && hi - lo > 15, "{lo}..{hi}");
        }
    }

    #[test]
    fn sparkles_are_sparse_streaks() {
        let t = HairTexture::generate(1);
        let (l0, _) = level(&t, 0);
        let bright = l0.iter().filter(|p| p[3] > 200).count() as f32 / l0.len() as f32;
        assert!(bright > 0.005 && bright < 0.15, "{bright}");
        let base: Vec<u8> = l0.iter().filter(|p| p[1] > 0).map(|p| p[0]).collect();
        let (lo, hi) = (base.iter().min().unwrap(), base.iter().max().unwrap());
        assert!(*lo >= 120 && *hi > 230, "{lo}..{hi}");
    }
}
