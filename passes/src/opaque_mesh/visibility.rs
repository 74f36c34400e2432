//! `scene.visibility`: opaque meshes (heads, bodies) into a visibility
//! buffer, rasterized in a compute shader.
//!
//! `scene.visibility` holds one 64-bit word per pixel, row-major: NDC depth
//! z/w's f32 bits in the high half, the triangle's index in the low half, so
//! one `atomicMin` keeps the nearest triangle (positive floats order like
//! their bits) and ties go to the lower index. A `common.clear` to all-ones
//! comes first. The result is independent of triangle and workgroup order.
//! `scene.depth_resolve` turns it into `scene.depth`, and `scene.opaque`
//! shades each pixel's triangle: the head is rasterized once, shaded once.
//!
//! Why not the hardware rasterizer: Hopper runs vertex and pixel work on few
//! of its SMs, and the H100 bench's graphics roofline measured a depth
//! prepass plus a depth-equal shading pass at 2.7 ms for the crowd's 560k
//! triangles (benches/results/h100-hw-head.json). One lane per triangle
//! walks its bounding box with exact integer edge functions
//! ([`setup`](super::setup)): 0.027 ms for the crowd, 0.037 ms for the close
//! view (H100, `benches/results/h100.json`).
//!
//! `cooperative_above` (ours, after the binning of large triangles in
//! software rasterizers such as Nanite's) queues triangles whose box holds
//! more pixels than that and rasterizes them with the whole workgroup, one
//! pixel per lane, so that one large triangle does not stall 63 idle lanes.
//! It ships off: at 64 pixels it made the close view's pass 0.146 ms instead
//! of 0.037 (every lane sets each queued triangle up again, one after
//! another), and our heads have no triangle large enough to win it back. The
//! bench row "cooperative large triangles" keeps measuring it.

use super::{GROUP, View, dispatch};
use crate::contract::{Binding, CpuKernel, Shader};
use crate::describe::PassKind;
use crate::kernel::{CounterValues, Ctx, Words};
use crate::params::{Invalid, PassParams};

/// The empty slot: what `common.clear` with `0xFFFFFFFF` leaves.
pub const EMPTY: u64 = u64::MAX;

/// One visibility word: depth bits high, triangle index low.
pub fn pack(depth: f32, triangle: u32) -> u64 {
    (u64::from(depth.to_bits()) << 32) | u64::from(triangle)
}

/// The triangle and NDC depth of a visibility word, `None` when empty.
pub fn unpack(word: u64) -> Option<(u32, f32)> {
    (word != EMPTY).then(|| (word as u32, f32::from_bits((word >> 32) as u32)))
}

/// The pass's parameters, with their defaults.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct VisibilityParams {
    /// Triangles whose clipped bounding box holds more pixels than this are
    /// rasterized by the whole workgroup; 0 = every lane rasterizes its own.
    pub cooperative_above: u32,
}

impl PassParams for VisibilityParams {
    fn validate(&self) -> Result<(), Invalid> {
        crate::params::in_range("cooperative_above", self.cooperative_above, 0..=1 << 24)
    }
}

crate::gpu_block! {
    /// `VisibilityParams` in shaders/opaque_mesh/visibility.wgsl.
    pub struct VisibilityGpu {
        triangles: u32,
        cooperative_above: u32,
        width: u32,
        height: u32,
    }
}

pub static VISIBILITY: PassKind<VisibilityParams, VisibilityGpu> = PassKind {
    kind: "scene.visibility",
    summary: "rasterize opaque meshes (heads, bodies) into a 64-bit visibility buffer in compute",
    source: "strandgraph (compute rasterization; Hopper's graphics SMs are few)",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("mesh.triangles"),
        Binding::atomic("scene.visibility"),
    ]),
    workgroup_size: GROUP,
    dispatch: dispatch(),
    shader: Shader::compute("opaque_mesh/visibility.wgsl", "rasterize"),
    kernel: |p| Box::new(VisibilityKernel { params: *p }),
    gpu: |p, q| VisibilityGpu {
        triangles: u32::try_from(q.triangles).unwrap_or(u32::MAX),
        cooperative_above: p.cooperative_above,
        width: q.width,
        height: q.height,
    },
    raster: None,
};

struct VisibilityKernel {
    params: VisibilityParams,
}

/// Writes one fragment: depth clipping, then the 64-bit `atomicMin`.
fn write(vis: &Words<'_>, view: &View<'_>, x: u32, y: u32, depth: f32, t: u32) -> bool {
    // Depth clipping, as hardware discards fragments outside [0, 1].
    if !(0.0..=1.0).contains(&depth) {
        return false;
    }
    vis.fetch_min_u64(view.texel(x, y), pack(depth, t));
    true
}

impl CpuKernel for VisibilityKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let view = View::load(ctx);
        let vis = ctx.words("scene.visibility");
        let mut local = CounterValues::default();
        let mut queue = Vec::new();
        let limit = self.params.cooperative_above;
        // Phase 1: each lane sets up its triangle; small ones it rasterizes alone.
        view.for_each_triangle(group, |t, setup| {
            if limit > 0 && setup.box_pixels() > limit {
                queue.push((t, *setup));
                return;
            }
            setup.rasterize(|x, y, depth| {
                local.atomics += u64::from(write(&vis, &view, x, y, depth, t));
            });
        });
        // Phase 2: the workgroup walks each queued box, one pixel per lane.
        for (t, setup) in queue {
            let [x0, y0, x1, _] = setup.bounds();
            let width = x1 - x0 + 1;
            for k in 0..setup.box_pixels() {
                let (x, y) = (x0 + k % width, y0 + k / width);
                let e = setup.edges(x, y);
                if setup.covers(e) {
                    local.atomics += u64::from(write(&vis, &view, x, y, setup.depth(e), t));
                }
            }
        }
        if ctx.instrument {
            ctx.counters.add(&local);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{frame, harness, head, near_and_far, run, run_with, triangle};
    use super::*;
    use glam::Vec3;

    /// Linear view depth from NDC depth for `perspective_rh(near, far)`.
    fn view_depth(z: f32, near: f32, far: f32) -> f32 {
        near * far / (far - z * (far - near))
    }

    fn slots(words: &[u32]) -> Vec<u64> {
        words
            .chunks_exact(2)
            .map(|p| u64::from(p[0]) | (u64::from(p[1]) << 32))
            .collect()
    }

    #[test]
    fn params_default_parse_and_reject() {
        let p = VISIBILITY.params(&ron::Value::Unit).unwrap();
        assert_eq!(p, VisibilityParams::default());
        let v: ron::Value = ron::from_str(r#"{"cooperative_above": 64}"#).unwrap();
        assert_eq!(VISIBILITY.params(&v).unwrap().cooperative_above, 64);
        let v: ron::Value = ron::from_str(r#"{"cooperative": 3}"#).unwrap();
        let e = VISIBILITY.params(&v).unwrap_err();
        assert!(e.to_string().contains("scene.visibility"), "{e}");
    }

    #[test]
    fn nearer_triangle_wins_whatever_the_order() {
        let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 40.0, 32, 32);
        let [near, far] = near_and_far(Vec3::Z);
        let mut results = Vec::new();
        for tris in [[near, far], [far, near]] {
            let hs = harness(f, &tris, &[]);
            run(&hs, &VISIBILITY);
            assert_eq!(hs.out_of_bounds(), 0);
            results.push(slots(&hs.read("scene.visibility")));
        }
        // The same depths; the triangle indices swap with the order.
        let (t, z) = unpack(results[0][16 * 32 + 16]).unwrap();
        let (t2, z2) = unpack(results[1][16 * 32 + 16]).unwrap();
        assert_eq!((t, t2, z.to_bits()), (0, 1, z2.to_bits()));
        assert!((view_depth(z, f.near, f.far) - 0.9).abs() < 1e-3, "{z}");
        // The far triangle still shows around the near one; the corners stay empty.
        assert!(results[0].iter().any(|&w| {
            unpack(w)
                .is_some_and(|(t, z)| t == 1 && (view_depth(z, f.near, f.far) - 1.1).abs() < 1e-3)
        }));
        assert_eq!(results[0][0], EMPTY);
    }

    #[test]
    fn back_faces_and_near_plane_crossers_are_not_drawn() {
        let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 40.0, 32, 32);
        let (a, b, c) = (
            Vec3::new(-0.2, -0.2, 0.0),
            Vec3::new(0.2, -0.2, 0.0),
            Vec3::new(0.0, 0.2, 0.0),
        );
        let covered = |t| {
            let hs = harness(f, &[t], &[]);
            run(&hs, &VISIBILITY);
            assert_eq!(hs.out_of_bounds(), 0);
            slots(&hs.read("scene.visibility"))
                .iter()
                .filter(|&&w| w != EMPTY)
                .count()
        };
        assert!(covered(triangle(a, b, c, Vec3::Z)) > 20);
        assert_eq!(covered(triangle(a, c, b, -Vec3::Z)), 0);
        // One corner behind the camera.
        assert_eq!(
            covered(triangle(a, b, Vec3::new(0.0, 0.2, 2.0), Vec3::Z)),
            0
        );
    }

    #[test]
    fn cooperative_rasterization_changes_no_bit() {
        // Close to the head: boxes of hundreds of pixels, both paths busy.
        let f = frame(
            Vec3::new(0.0, 0.05, 0.45),
            Vec3::new(0.0, 0.05, 0.0),
            35.0,
            320,
            240,
        );
        let tris = head();
        let render = |limit: u32| {
            let hs = harness(f, &tris, &[]);
            let p = format!("{{\"cooperative_above\": {limit}}}");
            run_with(&hs, &VISIBILITY, &ron::from_str(&p).unwrap());
            assert_eq!(hs.out_of_bounds(), 0);
            hs.read("scene.visibility")
        };
        let alone = render(0);
        assert!(alone == render(4), "cooperative boxes drew different bits");
        assert!(alone == render(64));
    }

    #[test]
    fn procedural_head_faces_the_camera() {
        // 1 m in front of the face (+z), 128×128.
        let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 35.0, 128, 128);
        let hs = harness(f, &head(), &[]);
        run(&hs, &VISIBILITY);
        assert_eq!(hs.out_of_bounds(), 0);
        let vis = slots(&hs.read("scene.visibility"));
        let covered = vis.iter().filter(|&&w| w != EMPTY).count();
        let fraction = covered as f64 / vis.len() as f64;
        assert!(fraction > 0.05 && fraction < 0.8, "{fraction}");
        // With the right winding we see the face (z = +half_depth, 0.902 m
        // away), not the back of the skull (1.098 m) through a culled front.
        let (_, z) = unpack(vis[64 * 128 + 64]).unwrap();
        let centre = view_depth(z, f.near, f.far);
        assert!((centre - 0.902).abs() < 0.01, "centre at {centre} m");
    }
}
