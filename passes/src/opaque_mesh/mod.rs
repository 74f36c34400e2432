//! Opaque scene geometry (heads, bodies): a depth prepass and a forward
//! shading pass, the kinds `scene.depth_prepass` and `scene.opaque` (named
//! for what graphs see: the scene's opaque meshes, as opposed to hair). The Kulikov pipeline composes its hair coverage over this
//! opaque head, and culls and depth-tests hair against `scene.depth`.
//!
//! Both passes run one lane per triangle on the CPU simulator and share the
//! fixed-point rasterizer in [`raster`], so the opaque pass's depth-equal test
//! sees exactly the bits the prepass wrote. On the GPU backends they are real
//! raster pipelines (`shaders/opaque_mesh/*.wgsl`), which apply the same rules.

pub mod depth_prepass;
pub mod opaque;
pub mod raster;

use crate::contract::Dispatch;
use crate::kernel::{Ctx, Words};
use crate::layout::{FrameData, TriangleData, read};
use glam::{Mat4, Vec3, Vec4};
use raster::Setup;
use strandgraph_assets::octahedral::unpack_unit_vector;
use strandgraph_graph::schema::Quantity;

/// Lanes per workgroup, one triangle each.
pub const GROUP: u32 = 64;

/// Words per `TriangleData` record.
const TRIANGLE_WORDS: usize = std::mem::size_of::<TriangleData>() / 4;

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
    view_proj: Mat4,
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
            view_proj: Mat4::from_cols_array(&frame.view_proj),
            frame,
            width: ctx.quantities.width,
            height: ctx.quantities.height,
            triangles,
            count: ctx.quantities.triangles.min(stored) as u32,
        }
    }

    /// Calls `f` with each of this workgroup's triangles that survives setup.
    fn for_each_triangle(&self, group: u32, mut f: impl FnMut(&TriangleData, &Setup)) {
        let first = group.saturating_mul(GROUP);
        for t in first..first.saturating_add(GROUP).min(self.count) {
            let tri: TriangleData = read(&self.triangles, t as usize);
            let clip = corners(&tri).map(|p| self.view_proj * Vec4::from((p, 1.0)));
            if let Some(s) = Setup::from_clip(clip, self.frame.near, self.width, self.height) {
                f(&tri, &s);
            }
        }
    }

    /// Row-major texel index.
    fn texel(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }
}

/// Fills every word of `words` with `value` (a render pass's clear load op).
fn clear(words: &Words<'_>, value: u32) {
    use rayon::prelude::*;
    (0..words.len())
        .into_par_iter()
        .with_min_len(1 << 14)
        .for_each(|i| words.store(i, value));
}

#[cfg(test)]
pub(crate) mod testing {
    //! Scenes built by hand for the tests of both passes.

    use super::GROUP;
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
            _pad: [0; 19],
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

    /// A harness with every binding of both passes.
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
            .buffer("scene.depth", vec![0; (w * h) as usize])
            .buffer("output", vec![0; (2 * w * h) as usize]);
        hs
    }

    /// Runs one pass with default parameters over every triangle.
    pub fn run(hs: &Harness, def: &dyn PassDef) {
        let kernel = def.cpu_kernel(&ron::Value::Unit).expect("default params");
        let groups = hs.quantities.triangles.div_ceil(u64::from(GROUP)) as u32;
        hs.run(kernel.as_ref(), groups, def.workgroup_size());
    }
}
