//! The bake's occluders behind two BVHs (obvhs's compressed wide BVH8, built
//! with PLOC over AABBs): one over strand segments, one over head triangles,
//! and the scattering-event count of one ray.
//!
//! What a ray counts (Kulikov, "Precomputed self-shadowing": "We trace
//! against the parent mesh as well so hair is always shadowed by the head"):
//! - every strand segment it crosses before `max_distance` or the head is one
//!   scattering event (the segments touching the ray's own vertex excluded);
//! - the head is opaque: a ray that reaches it stops there and counts at
//!   least `HAIR_MAX_SCATTER_EVENTS`, i.e. "fully shadowed" on the talk's
//!   scale, `max(crossings before the head, HAIR_MAX_SCATTER_EVENTS)`, so a
//!   head hit never counts less than the strands in front of it.

use crate::intersect::{Segment, ray_segment, ray_triangle};
use crate::{BakeInput, BakeSettings};
use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::ray::{Ray, RayHit};
use std::time::Duration;

/// Rays start this far from their vertex (metres), past float noise in the
/// vertex position.
pub const T_MIN: f32 = 1e-6;

/// Strand segments and head triangles, with a BVH over each.
pub struct Occluders {
    pub segments: Vec<Segment>,
    pub triangles: Vec<[Vec3A; 3]>,
    segment_bvh: Option<CwBvh>,
    triangle_bvh: Option<CwBvh>,
}

fn finite(p: Vec3A) -> bool {
    p.is_finite()
}

impl Occluders {
    /// Segments of every `occluder_stride`-th strand (skipping any with a
    /// non-finite end), cut into pieces of at most `max_piece` metres, and
    /// the head triangles, and their BVHs.
    ///
    /// Two things keep the traversal affordable on a 2M-segment groom. A
    /// long diagonal segment has a box far larger than its thin capsule, so
    /// a ray overlaps hundreds of boxes per millimetre in dense hair; pieces
    /// shrink the boxes (a piece is counted like a segment: its tip end
    /// belongs to the next piece). And a thinned occluder set with radius
    /// scaled by the stride keeps the expected number of crossings (density
    /// × cross-section), as Kulikov's LOD does with its thickness
    /// compensation, at a fraction of the primitives.
    pub fn new(input: &BakeInput<'_>, settings: &BakeSettings) -> Self {
        let stride = settings.occluder_stride.max(1);
        let widen = stride as f32;
        let mut segments = Vec::new();
        for &[first, count] in input.strands.iter().step_by(stride as usize) {
            for i in 1..count {
                let (v0, v1) = (first + i - 1, first + i);
                let (p, q) = (input.vertices[v0 as usize], input.vertices[v1 as usize]);
                let (a, b) = (Vec3A::new(p[0], p[1], p[2]), Vec3A::new(q[0], q[1], q[2]));
                if !(finite(a) && finite(b)) {
                    continue;
                }
                let (ra, rb) = ((p[3] * 0.5 * widen).max(0.0), (q[3] * 0.5 * widen).max(0.0));
                let pieces = ((a.distance(b) / settings.max_piece).ceil() as u32).clamp(1, 64);
                for k in 0..pieces {
                    let (s0, s1) = (k as f32 / pieces as f32, (k + 1) as f32 / pieces as f32);
                    segments.push(Segment {
                        a: a.lerp(b, s0),
                        b: a.lerp(b, s1),
                        ra: ra + (rb - ra) * s0,
                        rb: ra + (rb - ra) * s1,
                        v0,
                        last: i + 1 == count && k + 1 == pieces,
                    });
                }
            }
        }
        let triangles: Vec<[Vec3A; 3]> = input
            .triangles
            .iter()
            .map(|t| t.map(Vec3A::from))
            .filter(|t| t.iter().all(|&p| finite(p)))
            .collect();
        let seg_boxes: Vec<Aabb> = segments
            .iter()
            .map(|s| {
                let (lo, hi) = s.bounds();
                Aabb::new(lo, hi)
            })
            .collect();
        let tri_boxes: Vec<Aabb> = triangles.iter().map(|t| Aabb::from_points(t)).collect();
        let build = |boxes: &[Aabb]| {
            (!boxes.is_empty()).then(|| {
                build_cwbvh(
                    boxes,
                    BvhBuildParams::medium_build(),
                    &mut Duration::default(),
                )
            })
        };
        Self {
            segment_bvh: build(&seg_boxes),
            triangle_bvh: build(&tri_boxes),
            segments,
            triangles,
        }
    }

    /// The nearest head hit in `(T_MIN, tmax)`, through the BVH.
    pub fn head_hit(&self, origin: Vec3A, dir: Vec3A, tmax: f32) -> Option<f32> {
        let bvh = self.triangle_bvh.as_ref()?;
        let mut hit = RayHit::none();
        let ray = Ray::new(origin, dir, T_MIN, tmax);
        bvh.ray_traverse(ray, &mut hit, |r, id| {
            let tri = &self.triangles[bvh.primitive_indices[id] as usize];
            ray_triangle(r.origin, r.direction, tri, r.tmin, r.tmax).unwrap_or(f32::INFINITY)
        })
        .then_some(hit.t)
    }

    /// Strand crossings in `(T_MIN, tmax)`, through the BVH, ignoring the
    /// segments that touch `own` (the ray's vertex).
    pub fn crossings(&self, origin: Vec3A, dir: Vec3A, tmax: f32, own: u32) -> u32 {
        let Some(bvh) = self.segment_bvh.as_ref() else {
            return 0;
        };
        let mut n = 0;
        bvh.ray_traverse_anyhit(Ray::new(origin, dir, T_MIN, tmax), |r, id| {
            let s = &self.segments[bvh.primitive_indices[id] as usize];
            if !s.touches(own) && ray_segment(r.origin, r.direction, s, r.tmin, r.tmax).is_some() {
                n += 1;
            }
        });
        n
    }

    /// Scattering events along one ray from vertex `own` (see the module
    /// docs for what counts).
    pub fn events(
        &self,
        origin: Vec3A,
        dir: Vec3A,
        max_distance: f32,
        own: u32,
        head_events: f32,
    ) -> f32 {
        let head = self.head_hit(origin, dir, max_distance);
        let strands = self.crossings(origin, dir, head.unwrap_or(max_distance), own) as f32;
        if head.is_some() {
            strands.max(head_events)
        } else {
            strands
        }
    }

    /// [`Self::events`] without the BVHs: every triangle and segment tested.
    /// The reference the tests hold the BVH traversal to.
    pub fn events_brute_force(
        &self,
        origin: Vec3A,
        dir: Vec3A,
        max_distance: f32,
        own: u32,
        head_events: f32,
    ) -> f32 {
        let head = self
            .triangles
            .iter()
            .filter_map(|t| ray_triangle(origin, dir, t, T_MIN, max_distance))
            .reduce(f32::min);
        let tmax = head.unwrap_or(max_distance);
        let strands = self
            .segments
            .iter()
            .filter(|s| !s.touches(own) && ray_segment(origin, dir, s, T_MIN, tmax).is_some())
            .count() as f32;
        if head.is_some() {
            strands.max(head_events)
        } else {
            strands
        }
    }
}
