//! Which way is "out" at a point of a groom: the direction the patches face.
//!
//! Scheuermann's patches face out of the hair volume, and the shading's
//! tweaked N·L lights that side. Away from the head's centre is right where
//! hair lies on the scalp, but not where it drapes over the shoulders or
//! hangs in front of the chest: there the side facing away from the head is
//! the one underneath. The density of strands falls towards the outside of
//! the hair wherever it lies, so the direction is away from the head bent
//! towards where the density falls, by how clearly it falls.

use glam::Vec3;

use crate::density::DensityGrid;

/// A density gradient (in the grid's normalized units per cell) at which the
/// falling density outweighs the radial direction entirely.
const CLEAR_GRADIENT: f32 = 0.25;

pub(super) struct Outward<'a> {
    pub centre: Vec3,
    /// The groom's strand density (`ao::density`); `None` for a groom
    /// without extent, where only the centre decides.
    pub grid: Option<&'a DensityGrid>,
}

impl Outward<'_> {
    /// Unit "out" at `p` (zero only where `p` is the centre and the density
    /// is flat).
    pub fn at(&self, p: Vec3) -> Vec3 {
        let radial = (p - self.centre).normalize_or_zero();
        let Some(g) = self.grid else {
            return radial;
        };
        let q = g.to_grid(p);
        let diff = |o: Vec3| 0.5 * (g.sample(q + o) - g.sample(q - o));
        let falling = -Vec3::new(diff(Vec3::X), diff(Vec3::Y), diff(Vec3::Z));
        let len = falling.length();
        // Also catches a NaN gradient.
        if len.is_nan() || len <= 1e-6 {
            return radial;
        }
        let weight = (len / CLEAR_GRADIENT).min(1.0);
        (radial + 2.0 * weight * falling / len).normalize_or(radial)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Aabb;

    #[test]
    fn out_bends_towards_where_the_density_falls() {
        // A slab of hair below the centre, dense at z < 0, thin above: out of
        // the slab is +z although the centre lies straight above.
        let bounds = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let mut g = DensityGrid::cubic(bounds, 16).unwrap();
        for i in 0..16 {
            for j in 0..16 {
                for k in 0..8 {
                    let cell = Vec3::new(i as f32, j as f32, k as f32) + 0.5;
                    g.add(bounds.min + cell * g.cell_size(), 1.0);
                }
            }
        }
        let out = Outward {
            centre: Vec3::new(0.0, 5.0, 0.0),
            grid: Some(&g),
        };
        let at_surface = out.at(Vec3::new(0.0, 0.0, 0.0));
        assert!(at_surface.z > 0.8, "{at_surface}");
        // Without a grid, or where the density is flat, away from the centre.
        let radial = Outward {
            centre: Vec3::new(0.0, 5.0, 0.0),
            grid: None,
        };
        assert!((radial.at(Vec3::ZERO) - Vec3::NEG_Y).length() < 1e-6);
        let p = Vec3::new(0.0, 0.0, -0.7);
        let deep = out.at(p);
        let away = (p - Vec3::new(0.0, 5.0, 0.0)).normalize();
        assert!((deep - away).length() < 1e-3, "{deep}");
    }
}
