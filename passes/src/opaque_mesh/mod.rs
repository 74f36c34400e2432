//! Opaque scene geometry (heads, bodies), the kinds graphs see as
//! `scene.*` (the scene's opaque meshes, as opposed to hair):
//!
//! - `scene.visibility` rasterizes every triangle once, in a compute shader,
//!   into a 64-bit visibility buffer (depth and triangle index per pixel);
//! - `scene.depth_resolve` turns it into `scene.depth`, the depth image the
//!   hair pipelines cull and depth-test against (`scene.depth_hiz` also
//!   writes its 16×16 farthest-depth Hi-Z in the same pass);
//! - `scene.opaque` shades each covered pixel's triangle once;
//! - `scene.depth_attachment` copies `scene.depth` into a depth attachment
//!   for hair drawn through the hardware rasterizer.
//!
//! All three run the same integer rasterizer ([`setup`]) on every backend
//! (`shaders/opaque_mesh/*.wgsl` mirror the CPU kernels).

pub mod depth_attachment;
pub mod depth_resolve;
pub mod opaque;
pub mod setup;
pub mod visibility;

use crate::contract::Dispatch;
use crate::kernel::{Ctx, Words};
use crate::kulikov::transform;
use crate::layout::{FrameData, TriangleData, read};
use glam::{Vec3, Vec4};
use setup::Setup;
use strandgraph_assets::octahedral::unpack_unit_vector;
use strandgraph_graph::schema::Quantity;

/// Lanes per workgroup, one triangle each.
pub const GROUP: u32 = 64;

/// Words per `TriangleData` record.
const TRIANGLE_WORDS: usize = std::mem::size_of::<TriangleData>() / 4;

/// Lanes per workgroup of the per-pixel passes: 256 keeps a 4K screen
/// under the 65,535 workgroups Vulkan guarantees in one dimension.
pub const PIXEL_GROUP: u32 = 256;

/// One workgroup per [`PIXEL_GROUP`] pixels.
const fn pixel_dispatch() -> Dispatch {
    Dispatch::PerElement {
        quantity: Quantity::Pixels,
        per_group: PIXEL_GROUP,
    }
}

const fn dispatch() -> Dispatch {
    Dispatch::PerElement {
        quantity: Quantity::Triangles,
        per_group: GROUP,
    }
}

fn xyz(v: [f32; 4]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

/// World-space corners a, b, c.
pub fn corners(t: &TriangleData) -> [Vec3; 3] {
    [xyz(t.a), xyz(t.b), xyz(t.c)]
}

/// Smooth corner normals, unpacked from the octahedral bits in each `.w`.
pub fn corner_normals(t: &TriangleData) -> [Vec3; 3] {
    [t.a[3], t.b[3], t.c[3]].map(|w| unpack_unit_vector(w.to_bits()))
}

/// What both kernels decode once per workgroup.
struct View<'a> {
    frame: FrameData,
    width: u32,
    height: u32,
    triangles: Words<'a>,
    /// Triangles to draw: the scene's count, never past the bound buffer.
    count: u32,
}

impl<'a> View<'a> {
    fn load(ctx: &Ctx<'a>) -> Self {
        let frame: FrameData = read(&ctx.words("frame"), 0);
        let triangles = ctx.words("mesh.triangles");
        let stored = (triangles.len() / TRIANGLE_WORDS) as u64;
        Self {
            frame,
            width: ctx.quantities.width,
            height: ctx.quantities.height,
            triangles,
            count: ctx.quantities.triangles.min(stored) as u32,
        }
    }

    /// Calls `f` with the index and setup of each of this workgroup's
    /// triangles that survives setup.
    fn for_each_triangle(&self, group: u32, mut f: impl FnMut(u32, &Setup)) {
        let first = group.saturating_mul(GROUP);
        for t in first..first.saturating_add(GROUP).min(self.count) {
            if let Some(s) = self.setup(&self.triangle(t)) {
                f(t, &s);
            }
        }
    }

    /// Triangle `t` (a zeroed record past the bound buffer, as robust access reads).
    fn triangle(&self, t: u32) -> TriangleData {
        read(&self.triangles, t as usize)
    }

    /// The rasterizer's setup of `tri` for this view. The product sums in
    /// column order, as the WGSL `transform` does, so every backend snaps
    /// the same positions.
    fn setup(&self, tri: &TriangleData) -> Option<Setup> {
        let clip = |p: Vec3| Vec4::from(transform(&self.frame.view_proj, [p.x, p.y, p.z, 1.0]));
        // An array literal, not `corners(tri).map(..)`: with rustc 1.95 the
        // `map` form here compiled (in one build of this crate) to an
        // aligned SSE store into an 8-byte-aligned stack slot, a SIGSEGV in
        // the visibility kernel's tests.
        let [a, b, c] = corners(tri);
        Setup::from_clip(
            [clip(a), clip(b), clip(c)],
            self.frame.near,
            self.width,
            self.height,
        )
    }

    /// Row-major texel index.
    fn texel(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }
}

#[cfg(test)]
pub(crate) mod testing {
    //! Scenes built by hand for the tests of the three passes.

    use crate::contract::PassDef;
    use crate::kernel::harness::Harness;
    use crate::layout::{FrameData, LightData, TriangleData, words_of};
    use crate::upload::{FAR, NEAR};
    use glam::{Mat4, Vec3};
    use strandgraph_assets::octahedral::pack_unit_vector;
    use strandgraph_assets::procedural::HeadParams;
    use strandgraph_graph::Quantities;

    pub fn frame(eye: Vec3, target: Vec3, fov_deg: f32, w: u32, h: u32) -> FrameData {
        let view = Mat4::look_at_rh(eye, target, Vec3::Y);
        let proj = Mat4::perspective_rh(fov_deg.to_radians(), w as f32 / h as f32, NEAR, FAR);
        let vp = proj * view;
        FrameData {
            view_proj: vp.to_cols_array(),
            inv_view_proj: vp.inverse().to_cols_array(),
            camera_pos: [eye.x, eye.y, eye.z, 1.0],
            screen: [w as f32, h as f32, 1.0 / w as f32, 1.0 / h as f32],
            near: NEAR,
            far: FAR,
            model_count: 0,
            light_count: 0,
            pixels_per_unit: proj.y_axis.y * h as f32 * 0.5,
            time: 0.0,
            delta_time: 0.0,
            sim_reset: 1,
            _pad: [0; 16],
        }
    }

    /// A triangle with one normal at every corner.
    pub fn triangle(a: Vec3, b: Vec3, c: Vec3, n: Vec3) -> TriangleData {
        let n = f32::from_bits(pack_unit_vector(n.normalize()));
        TriangleData {
            a: [a.x, a.y, a.z, n],
            b: [b.x, b.y, b.z, n],
            c: [c.x, c.y, c.z, n],
            mesh: 0,
            albedo: [0; 3],
        }
    }

    /// Two front-facing triangles seen from +z: a small one at z = 0.1
    /// (normal +z) in front of a larger one at z = -0.1 (normal `far_normal`).
    pub fn near_and_far(far_normal: Vec3) -> [TriangleData; 2] {
        let near = triangle(
            Vec3::new(-0.2, -0.2, 0.1),
            Vec3::new(0.2, -0.2, 0.1),
            Vec3::new(0.0, 0.2, 0.1),
            Vec3::Z,
        );
        let far = triangle(
            Vec3::new(-0.3, -0.3, -0.1),
            Vec3::new(0.3, -0.3, -0.1),
            Vec3::new(0.0, 0.3, -0.1),
            far_normal,
        );
        [near, far]
    }

    /// The procedural head's triangles, as `upload` packs them (identity transform).
    pub fn head() -> Vec<TriangleData> {
        let m = HeadParams::default().build();
        let normals = m.vertex_normals();
        (0..m.triangle_count())
            .map(|t| {
                let [a, b, c] = m.corners(t);
                let n =
                    m.triangles[t].map(|i| f32::from_bits(pack_unit_vector(normals[i as usize])));
                TriangleData {
                    a: [a.x, a.y, a.z, n[0]],
                    b: [b.x, b.y, b.z, n[1]],
                    c: [c.x, c.y, c.z, n[2]],
                    mesh: 0,
                    albedo: [0; 3],
                }
            })
            .collect()
    }

    pub fn sun(direction: Vec3, radiance: f32) -> LightData {
        let d = direction.normalize();
        LightData {
            position_or_direction: [d.x, d.y, d.z, 0.0],
            radiance: [radiance, radiance, radiance, 0.0],
            _pad: [0; 8],
        }
    }

    /// A harness with every binding of the three passes, the visibility
    /// buffer cleared to empty.
    pub fn harness(mut frame: FrameData, tris: &[TriangleData], lights: &[LightData]) -> Harness {
        let (w, h) = (frame.screen[0] as u32, frame.screen[1] as u32);
        frame.light_count = lights.len() as u32;
        let mut hs = Harness::new(Quantities {
            triangles: tris.len() as u64,
            lights: lights.len() as u64,
            width: w,
            height: h,
            ..Default::default()
        });
        hs.buffer("frame", words_of(&[frame]))
            .buffer("mesh.triangles", words_of(tris))
            .buffer("lights", words_of(lights))
            .buffer("skin_shadow", vec![u32::MAX; (w * h) as usize])
            .buffer("scene.visibility", vec![u32::MAX; (2 * w * h) as usize])
            .buffer("scene.depth", vec![0; (w * h) as usize])
            .buffer("output", vec![0; (2 * w * h) as usize]);
        hs
    }

    /// Runs one pass with default parameters.
    pub fn run(hs: &Harness, def: &dyn PassDef) {
        run_with(hs, def, &ron::Value::Unit);
    }

    /// Runs one pass with `params`, over the workgroups its dispatch asks for.
    pub fn run_with(hs: &Harness, def: &dyn PassDef, params: &ron::Value) {
        let kernel = def.cpu_kernel(params).expect("valid params");
        let groups = def
            .dispatch()
            .direct_groups(&hs.quantities, 0)
            .expect("a direct dispatch");
        hs.run(kernel.as_ref(), groups as u32, def.workgroup_size());
    }

    /// Visibility, depth resolve and shading: what a graph runs, in order.
    pub fn render(hs: &Harness) {
        use super::{depth_resolve::DEPTH_RESOLVE, opaque::OPAQUE, visibility::VISIBILITY};
        for def in [&VISIBILITY as &dyn PassDef, &DEPTH_RESOLVE, &OPAQUE] {
            run(hs, def);
        }
    }
}
