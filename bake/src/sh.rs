//! Clamped L1 spherical harmonics of the scattering-event count.
//!
//! Kulikov, "Visibility function": "We use clamped low order SH as our
//! visibility function because of integration simplicity, low memory
//! requirements and lack of ringing artifacts. [...] instead of encoding
//! visibility directly, we encode the average number of scattering events in
//! any given direction", and "Bias ray misses to have negative number of
//! scattering events when integrating SH, then clamp the result":
//!
//! ```text
//! numScatterEvents = CastRay(rayOrigin, rayDirection);
//! if (numScatterEvents == 0) numScatterEvents = -HAIR_MAX_SCATTER_EVENTS;
//! visSH += EvaluateSHBasisL1(rayDirection) * numScatterEvents;
//! // at runtime
//! numScatterEvents = max(0, ProjectL1SH(visSH, lightDirection));
//! visibility = exp(-absorption * numScatterEvents);
//! ```
//!
//! Coefficients are the real SH in the usual order `[Y00, Y1-1, Y10, Y11]`,
//! i.e. constant, y, z, x; the projection is a Monte Carlo estimate over
//! uniformly distributed directions (weight 4π/N each), so reconstructing a
//! linear function of the direction is exact in the limit.

use glam::{Quat, Vec3A};
use std::f32::consts::PI;

/// `Y00 = 1 / (2 √π)`.
pub const Y0: f32 = 0.282_094_8;
/// `Y1m = √3 / (2 √π) · (y, z, x)`.
pub const Y1: f32 = 0.488_602_5;

/// The L1 basis at unit direction `d` ("EvaluateSHBasisL1").
#[inline]
pub fn basis(d: Vec3A) -> [f32; 4] {
    [Y0, Y1 * d.y, Y1 * d.z, Y1 * d.x]
}

/// The SH function at unit direction `d` ("ProjectL1SH"), unclamped.
#[inline]
pub fn eval(sh: &[f32; 4], d: Vec3A) -> f32 {
    let b = basis(d);
    sh[0] * b[0] + sh[1] * b[1] + sh[2] * b[2] + sh[3] * b[3]
}

/// Kulikov's runtime fetch: `exp(-absorption * max(0, SH(light)))`.
#[inline]
pub fn visibility(sh: &[f32; 4], to_light: Vec3A, absorption: f32) -> f32 {
    (-absorption * eval(sh, to_light).max(0.0)).exp()
}

/// [`visibility`] for callers on another glam version (plain arrays), e.g.
/// the CPU kernel of `kulikov.shade`.
#[inline]
pub fn visibility_towards(sh: &[f32; 4], to_light: [f32; 3], absorption: f32) -> f32 {
    visibility(sh, Vec3A::from(to_light), absorption)
}

/// The value a ray contributes: its event count, or the negative zero-event
/// bias when it escaped.
#[inline]
pub fn biased(events: f32, max_scatter_events: f32) -> f32 {
    if events == 0.0 {
        -max_scatter_events
    } else {
        events
    }
}

/// `n` unit directions spread evenly over the sphere (spherical Fibonacci
/// lattice): far less clumping than independent samples at the handful of
/// rays per vertex a bake affords.
pub fn fibonacci_sphere(n: u32) -> Vec<Vec3A> {
    let golden = PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f32 + 1.0) / n as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * i as f32;
            Vec3A::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// A rotation drawn uniformly from SO(3) by hashing `(seed, index)`, so each
/// vertex sees the lattice at its own orientation (noise instead of a shared
/// pattern of banding) and a bake is reproducible.
pub fn random_rotation(seed: u64, index: u64) -> Quat {
    let h = splitmix(seed ^ splitmix(index));
    let h2 = splitmix(h);
    let u = |x: u64| (x >> 40) as f32 / (1u64 << 24) as f32;
    let (u1, u2, u3) = (u(h), u(h2), u(splitmix(h2)));
    // Shoemake's uniform random quaternion.
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let (t2, t3) = (2.0 * PI * u2, 2.0 * PI * u3);
    Quat::from_xyzw(a * t2.sin(), a * t2.cos(), b * t3.sin(), b * t3.cos()).normalize()
}

fn splitmix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// Accumulates `value(direction)` over directions of equal solid angle and
/// returns the L1 projection.
#[derive(Debug, Default, Clone, Copy)]
pub struct Projection {
    sum: [f32; 4],
    n: u32,
}

impl Projection {
    #[inline]
    pub fn add(&mut self, d: Vec3A, value: f32) {
        let b = basis(d);
        for (s, b) in self.sum.iter_mut().zip(b) {
            *s += b * value;
        }
        self.n += 1;
    }

    pub fn finish(&self) -> [f32; 4] {
        if self.n == 0 {
            return [0.0; 4];
        }
        let w = 4.0 * PI / self.n as f32;
        self.sum.map(|s| s * w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_is_unit_and_balanced() {
        let dirs = fibonacci_sphere(1024);
        let mean = dirs.iter().fold(Vec3A::ZERO, |a, &d| a + d) / dirs.len() as f32;
        assert!(mean.length() < 1e-2, "mean {mean}");
        assert!(dirs.iter().all(|d| (d.length() - 1.0).abs() < 1e-5));
    }

    /// An L1 function (constant + linear in the direction) is reproduced
    /// by projecting and evaluating, for any rotation of the lattice.
    #[test]
    fn linear_function_round_trips() {
        let f = |d: Vec3A| 2.0 + 3.0 * d.x - 1.5 * d.y + 0.5 * d.z;
        for k in 0..4 {
            let q = random_rotation(7, k);
            let mut p = Projection::default();
            for d in fibonacci_sphere(4096) {
                let d = q * d;
                p.add(d, f(d));
            }
            let sh = p.finish();
            for d in fibonacci_sphere(37) {
                assert!(
                    (eval(&sh, d) - f(d)).abs() < 0.02,
                    "{} vs {}",
                    eval(&sh, d),
                    f(d)
                );
            }
        }
    }

    /// Kulikov's bias: a hemisphere of misses under a hemisphere of head
    /// hits reconstructs to "fully visible" above and shadowed below, and
    /// without the bias glancing directions are shadowed (the energy loss
    /// at glancing angles the talk describes).
    #[test]
    fn zero_event_bias_keeps_the_open_side_lit() {
        let max = 5.0;
        let (mut with, mut without) = (Projection::default(), Projection::default());
        for d in fibonacci_sphere(2048) {
            let events = if d.y < 0.0 { max } else { 0.0 };
            with.add(d, biased(events, max));
            without.add(d, events);
        }
        let (with, without) = (with.finish(), without.finish());
        assert_eq!(visibility(&with, Vec3A::Y, 1.0), 1.0);
        assert!(visibility(&with, -Vec3A::Y, 1.0) < 0.01);
        // Sideways (glancing): unbiased, L1 smears the head's 5 events over
        // the horizon (mean 2.5); the bias keeps it lit.
        assert!(visibility(&with, Vec3A::X, 1.0) > 0.9);
        assert!(visibility(&without, Vec3A::X, 1.0) < 0.2);
    }

    #[test]
    fn rotations_differ_and_are_unit() {
        let (a, b) = (random_rotation(1, 0), random_rotation(1, 1));
        assert!((a.length() - 1.0).abs() < 1e-5);
        assert!(a.angle_between(b) > 1e-3);
        assert_eq!(random_rotation(1, 0), a);
    }
}
