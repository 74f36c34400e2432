//! Guide strands, grown as a groomer grows them: out of the skin along a
//! comb direction, bent by gravity step by step (follow the leader, each step
//! keeping its length), pushed out of the head's distance field so hair lies
//! on the skull and falls over the shoulders; gathered to a tie for a
//! ponytail or coiled for a bun; cut level for a bob.

use glam::Vec3;
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::styles::{Comb, Gather, Resolved};
use super::surface::Surface;
use crate::groom::arc_length_samples;

/// Points a guide is grown with, whatever the groom's point count: enough for
/// collisions with the head to be resolved smoothly.
const GUIDE_POINTS: usize = 64;
/// The innermost layer's height above the skin.
pub const SKIN_MARGIN: f32 = 0.0012;

/// A polyline with its arc length, sampled by distance from the root.
#[derive(Debug, Clone)]
pub struct Path {
    pub points: Vec<Vec3>,
    arc: Vec<f32>,
}

impl Path {
    pub fn new(points: Vec<Vec3>) -> Path {
        let mut arc = Vec::with_capacity(points.len());
        let mut acc = 0.0;
        for i in 0..points.len() {
            if i > 0 {
                acc += points[i].distance(points[i - 1]);
            }
            arc.push(acc);
        }
        Path { points, arc }
    }
    pub fn length(&self) -> f32 {
        self.arc.last().copied().unwrap_or(0.0)
    }
    /// Position and unit tangent at arc length `s` (clamped to the path).
    pub fn sample(&self, s: f32) -> (Vec3, Vec3) {
        let n = self.points.len();
        if n < 2 {
            return (self.points.first().copied().unwrap_or_default(), Vec3::Y);
        }
        let i = self.arc.partition_point(|&a| a < s).clamp(1, n - 1);
        let (a, b) = (self.points[i - 1], self.points[i]);
        let span = (self.arc[i] - self.arc[i - 1]).max(1e-9);
        let t = ((s - self.arc[i - 1]) / span).clamp(0.0, 1.0);
        (a.lerp(b, t), (b - a).normalize_or(Vec3::Y))
    }
    /// `n` points evenly spaced along the path.
    pub fn resampled(&self, n: usize) -> Vec<Vec3> {
        let p = &self.points;
        arc_length_samples(p, n)
            .into_iter()
            .map(|(i, t)| p[i].lerp(p[(i + 1).min(p.len() - 1)], t))
            .collect()
    }
    /// The path cut where it first goes below `height` (unchanged if it never does).
    pub fn cut_below(mut self, height: f32) -> Path {
        if let Some(i) = self
            .points
            .iter()
            .position(|p| p.y < height)
            .filter(|&i| i >= 1)
        {
            let (a, b) = (self.points[i - 1], self.points[i]);
            let t = (a.y - height) / (a.y - b.y).max(1e-9);
            self.points.truncate(i);
            self.points.push(a.lerp(b, t));
            return Path::new(self.points);
        }
        self
    }
}

/// The comb's pull at root `p` (head frame), before projection onto the skin.
fn comb_direction(comb: Comb, p: Vec3, rng: &mut Pcg64Mcg) -> Vec3 {
    let smooth = |e0: f32, e1: f32, x: f32| {
        let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    match comb {
        Comb::Parted(parting) => {
            let side = if (p.x - parting).abs() < 0.001 {
                if rng.random::<bool>() { 1.0 } else { -1.0 }
            } else {
                (p.x - parting).signum()
            };
            // At the front the sweep is to the side, clear of the face; on top
            // and behind it is back and down.
            let front = smooth(-0.02, 0.07, p.z);
            let top = smooth(0.0, 0.1, p.y);
            Vec3::new(
                side * (0.3 + 0.9 * front),
                -0.2 - 0.8 * (1.0 - top),
                -0.8 + 0.2 * front,
            )
        }
        Comb::FromCrown => {
            let crown = Vec3::new(0.0, 0.1, -0.04);
            (p - crown).normalize_or(Vec3::Z) + Vec3::new(0.0, 0.0, 0.3)
        }
        Comb::Along(d) => d,
        Comb::Temples => Vec3::new(p.x.signum(), 0.15, -0.1),
    }
}

/// The length, as a fraction, of a strand rooted on a fading region's edge.
const EDGE_LENGTH: f32 = 0.35;

/// Grows one guide from `root` (head frame) with skin normal `normal`.
pub fn grow(surface: &Surface, r: &Resolved, root: Vec3, normal: Vec3, rng: &mut Pcg64Mcg) -> Path {
    // Near a fading region's edge strands are shorter as well as sparser
    // (Region::fade): a third of the length at the edge.
    let fade = r.region.fade(root - surface.center);
    let length = r.length
        * (1.0 - r.length_variation * 0.5 * rng.random::<f32>())
        * (EDGE_LENGTH + (1.0 - EDGE_LENGTH) * fade);
    let step = length / (GUIDE_POINTS - 1) as f32;
    let comb = comb_direction(r.comb, root - surface.center, rng)
        .reject_from(normal)
        .normalize_or_zero();
    let mut dir = (normal * r.lift + comb * (1.0 - r.lift)).normalize_or(normal);
    // Each guide lies at its own depth in the hair's volume.
    let depth = r.volume * (0.15 + 0.85 * rng.random::<f32>());
    let mut gather = r.gather.map(|g| Gathering::new(g, surface.center, rng));
    let mut points = Vec::with_capacity(GUIDE_POINTS);
    points.push(root);
    let mut p = root;
    for i in 1..GUIDE_POINTS {
        let s = i as f32 * step;
        let wanted = match &mut gather {
            Some(g) => g.direction(p, s, dir, normal),
            None => None,
        };
        dir = match wanted {
            Some(w) => w,
            None => (dir + r.bend * (r.gravity * step)).normalize_or(dir),
        };
        // The layer rises from the skin over the first centimetre and a half.
        let margin = SKIN_MARGIN + depth * (s / 0.015).min(1.0);
        let free = p + dir * step;
        let moved = surface.push_out(free, margin);
        let next = p + (moved - p).normalize_or(dir) * step;
        dir = (next - p).normalize_or(dir);
        if moved.distance_squared(free) > 0.0 {
            // A collision slides the strand along the skin; it does not
            // bounce it off (keeping the push's outward turn would carry
            // strands up into loops above the head).
            let n = surface.field_normal(next);
            dir = dir.reject_from(n).normalize_or(dir);
        }
        p = next;
        points.push(p);
    }
    let path = Path::new(points);
    match r.cut_height {
        Some(h) => path.cut_below(h + surface.center.y),
        None => path,
    }
}

/// A strand's way to the tie and, for a bun, around it.
struct Gathering {
    tie: Vec3,
    bun: bool,
    /// The bun's centre, its axis and this strand's coil radius and phase.
    centre: Vec3,
    axis: Vec3,
    radius: f32,
    phase: f32,
    /// Arc length at which the strand reached the tie.
    reached: Option<f32>,
}

impl Gathering {
    fn new(g: Gather, centre: Vec3, rng: &mut Pcg64Mcg) -> Gathering {
        let axis = Vec3::new(0.0, 0.35, -1.0).normalize();
        let (a, b) = axis.any_orthonormal_pair();
        let angle = rng.random::<f32>() * std::f32::consts::TAU;
        let spread = rng.random::<f32>().sqrt() * 0.012;
        Gathering {
            tie: centre + g.tie + (a * angle.cos() + b * angle.sin()) * spread,
            bun: g.bun,
            centre: centre + g.tie + axis * 0.022,
            axis,
            radius: 0.01 + 0.02 * rng.random::<f32>(),
            phase: rng.random::<f32>() * std::f32::consts::TAU,
            reached: None,
        }
    }

    /// The direction to step in from `p` at arc length `s`, or `None` to let
    /// gravity act (the tail of a ponytail).
    fn direction(&mut self, p: Vec3, s: f32, dir: Vec3, normal: Vec3) -> Option<Vec3> {
        if self.reached.is_none() && p.distance(self.tie) < 0.008 {
            self.reached = Some(s);
        }
        match self.reached {
            None => {
                // Pulled taut over the scalp towards the tie.
                let to_tie = (self.tie - p).normalize_or(dir);
                Some((to_tie * 0.8 + normal * 0.05 + dir * 0.4).normalize_or(to_tie))
            }
            Some(s0) if self.bun => {
                // Around the bun's axis, slowly outwards and forwards.
                let (a, b) = self.axis.any_orthonormal_pair();
                let angle = self.phase + (s - s0) / self.radius;
                let ring =
                    self.radius * (1.0 + 0.15 * (s - s0) / (std::f32::consts::TAU * self.radius));
                let target = self.centre
                    + (a * angle.cos() + b * angle.sin()) * ring
                    + self.axis * (0.006 * (angle * 0.5).sin());
                Some((target - p).normalize_or(dir))
            }
            Some(s0) if s - s0 < 0.03 => Some((dir + Vec3::new(0.0, -0.3, -0.9)).normalize()),
            Some(_) => None,
        }
    }
}
