//! The CPU kernel of the `scheuermann.*` stages: the hardware pipeline
//! emulated. The prologue runs the vertex stage and triangle setup for every
//! triangle ([`crate::hardware_raster`], the rules the GPUs rasterize by);
//! each workgroup then owns a band of rows and rasterizes, shades,
//! depth-tests and blends every triangle in order there, so blending
//! happens in primitive order per pixel, as the hardware's output merger
//! guarantees.

use super::hair::{
    BANDS, HairParams, MIN_ALPHA, SEGMENTS, Stage, VERTEX_WORDS, corner_vertex, stage_state,
};
use super::shading::{Shading, Surface, hair_lighting};
use super::texture;
use crate::contract::CpuKernel;
use crate::hardware_raster::{Fragment, Setup};
use crate::kernel::{CounterValues, Ctx, Words};
use crate::kulikov::debug_resolve::{load_rgba16f, store_rgba16f};
use crate::kulikov::transform;
use crate::layout::{FrameData, LightData, ModelData, read};
use crate::raster_state::{Blend, Compare, Draw, Geometry};
use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;
use std::sync::RwLock;
use strandgraph_assets::octahedral::unpack_unit_vector;

/// What the vertex stage outputs for one vertex.
#[derive(Debug, Clone, Copy)]
struct Varyings {
    clip: Vec4,
    world: Vec3,
    tangent: Vec3,
    normal: Vec3,
    uv: Vec2,
    ao: f32,
    texels_per_metre: f32,
}

impl Varyings {
    fn fetch(vertices: &Words<'_>, frame: &FrameData, v: u32) -> Self {
        let o = v as usize * VERTEX_WORDS;
        let f = |k: usize| vertices.load_f32(o + k);
        let world = Vec3::new(f(0), f(1), f(2));
        let uv = vertices.load(o + 6);
        Self {
            clip: Vec4::from(transform(&frame.view_proj, world.extend(1.0).to_array())),
            world,
            tangent: unpack_unit_vector(vertices.load(o + 4)),
            normal: unpack_unit_vector(vertices.load(o + 5)),
            uv: Vec2::new((uv & 0xFFFF) as f32 / 65535.0, (uv >> 16) as f32 / 65535.0),
            ao: f(3),
            texels_per_metre: f(7),
        }
    }
}

/// A triangle past setup, with its corners' varyings and model.
struct Triangle {
    setup: Setup,
    corners: [Varyings; 3],
    model: u32,
}

impl Triangle {
    /// `@interpolate(perspective)` at a fragment.
    fn at(&self, f: &Fragment) -> (Surface, Vec2, f32, f32) {
        let b = self.setup.perspective(f.screen);
        let mix3 = |g: fn(&Varyings) -> Vec3| {
            g(&self.corners[0]) * b[0] + g(&self.corners[1]) * b[1] + g(&self.corners[2]) * b[2]
        };
        let mix1 = |g: fn(&Varyings) -> f32| {
            g(&self.corners[0]) * b[0] + g(&self.corners[1]) * b[1] + g(&self.corners[2]) * b[2]
        };
        let surface = Surface {
            world: mix3(|c| c.world),
            tangent: mix3(|c| c.tangent),
            normal: mix3(|c| c.normal),
            ao: mix1(|c| c.ao),
        };
        let uv = Vec2::new(mix1(|c| c.uv.x), mix1(|c| c.uv.y));
        (
            surface,
            uv,
            mix1(|c| c.texels_per_metre),
            mix1(|c| c.clip.w),
        )
    }
}

pub(super) struct HairKernel {
    stage: Stage,
    p: HairParams,
    /// The vertex stage and setup of every triangle that survives culling,
    /// in draw order: the prologue's work, redone every frame (a session
    /// keeps its kernels, and the frame's camera may move).
    triangles: RwLock<Vec<Triangle>>,
}

impl HairKernel {
    pub(super) fn new(stage: Stage, p: HairParams) -> Self {
        Self {
            stage,
            p,
            triangles: RwLock::new(Vec::new()),
        }
    }
}

impl CpuKernel for HairKernel {
    fn prologue(&self, ctx: &Ctx<'_>) {
        let frame: FrameData = read(&ctx.words("frame"), 0);
        let (vertices, models) = (ctx.words("patches.vertices"), ctx.words("patches.models"));
        let (w, h) = (ctx.quantities.width, ctx.quantities.height);
        let state = stage_state(self.stage, &self.p, &ctx.quantities);
        let vertices_drawn = match state.geometry {
            Geometry::Vertices(n) => n,
            _ => 0,
        };
        let list = (0..(vertices_drawn / 3) as u32)
            .into_par_iter()
            .filter_map(|t| {
                let corners =
                    [0, 1, 2].map(|k| Varyings::fetch(&vertices, &frame, corner_vertex(t, k)));
                let setup =
                    Setup::from_clip_culled(corners.map(|c| c.clip), frame.near, w, h, state.cull)?;
                Some(Triangle {
                    setup,
                    corners,
                    model: models.load((t / (2 * SEGMENTS)) as usize),
                })
            })
            .collect();
        *self.triangles.write().unwrap_or_else(|e| e.into_inner()) = list;
    }

    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let list = self.triangles.read().unwrap_or_else(|e| e.into_inner());
        let h = ctx.quantities.height;
        let rows = h.div_ceil(BANDS);
        let (first, last) = (group * rows, ((group + 1) * rows).min(h));
        if first >= last {
            return;
        }
        let ctx_data = Shared::load(ctx, self.stage, &self.p);
        let mut counters = CounterValues::default();
        for tri in list.iter() {
            tri.setup.rasterize_rows(first, last - 1, |f| {
                counters.pixels_written += u64::from(ctx_data.fragment(tri, &f));
            });
        }
        if ctx.instrument {
            ctx.counters.add(&counters);
        }
    }
}

/// What every fragment of a band reads.
struct Shared<'a> {
    frame: FrameData,
    lights: Vec<LightData>,
    /// Each model's colour, decoded once per band rather than per fragment.
    colours: Vec<Vec3>,
    camera: Vec3,
    texture: Words<'a>,
    output: Words<'a>,
    depth: Words<'a>,
    stage: Stage,
    p: HairParams,
    shading: Shading,
    draw: Draw,
    width: u32,
}

impl<'a> Shared<'a> {
    fn load(ctx: &Ctx<'a>, stage: Stage, p: &HairParams) -> Self {
        let frame: FrameData = read(&ctx.words("frame"), 0);
        let lights = ctx.words("lights");
        let stored = lights.len() / (std::mem::size_of::<LightData>() / 4);
        let lights = (0..(frame.light_count as usize).min(stored))
            .map(|i| read(&lights, i))
            .collect();
        let models = ctx.words("models");
        let stored = models.len() / (std::mem::size_of::<ModelData>() / 4);
        let colours = (0..(ctx.quantities.models as usize).min(stored))
            .map(|i| {
                let c = read::<ModelData>(&models, i).color;
                Vec3::new(c[0], c[1], c[2])
            })
            .collect();
        let camera = Vec3::from_slice(&frame.camera_pos[..3]);
        Self {
            frame,
            lights,
            colours,
            camera,
            texture: ctx.words("patches.texture"),
            output: ctx.words("output"),
            depth: ctx.words("depth_buffer"),
            stage,
            p: *p,
            shading: p.shading(),
            draw: stage_state(stage, p, &ctx.quantities).draws[0],
            width: ctx.quantities.width,
        }
    }

    /// Depth test, fragment shader and output merger for one fragment;
    /// whether the fragment shader ran (the `pixels_written` the bench
    /// compares with the fragment roofline). Every stage that writes depth
    /// here may also discard, which makes the hardware test depth after
    /// shading ("Early Z culling can't be used when alpha test is enabled");
    /// the others test first.
    fn fragment(&self, tri: &Triangle, f: &Fragment) -> bool {
        let (state, p) = (self.draw, &self.p);
        let i = f.y as usize * self.width as usize + f.x as usize;
        let stored = self.depth.load_f32(i);
        let passes = match state.depth_compare {
            Compare::Always => true,
            Compare::Less => f.depth < stored,
            Compare::Equal => f.depth == stored,
        };
        // Depth clipping: hardware discards fragments outside [0, 1].
        if !passes || !(0.0..=1.0).contains(&f.depth) {
            return state.depth_write;
        }
        let (surface, uv, density, w) = tri.at(f);
        let fetch = |k: usize| self.texture.load(k);
        let lod = texture::lod(density, w, self.frame.pixels_per_unit, p.lod_bias);
        let tex = texture::sample(&fetch, uv, lod);
        let alpha = tex.y;
        let keep = match self.stage {
            Stage::PrimeDepth => alpha >= p.opaque_alpha,
            Stage::Opaque => p.primed || alpha >= p.opaque_alpha,
            Stage::BackFaces | Stage::FrontFaces => alpha >= MIN_ALPHA,
        };
        if !keep {
            return true;
        }
        if state.color_writes {
            // Past the bound models a GPU's robust access reads zeros.
            let colour = self.colours.get(tri.model as usize).copied();
            let colour = colour.unwrap_or(Vec3::ZERO);
            let lit = hair_lighting(
                &self.shading,
                &surface,
                tex,
                colour,
                self.camera,
                &self.lights,
            );
            let src = match state.blend {
                Blend::Replace => lit.truncate().extend(1.0),
                Blend::PremultipliedOver => (lit.truncate() * lit.w).extend(lit.w),
            };
            let dst = Vec4::from(load_rgba16f(&self.output, i));
            let out = match state.blend {
                Blend::Replace => src,
                Blend::PremultipliedOver => src + (1.0 - src.w) * dst,
            };
            store_rgba16f(&self.output, i, out.to_array());
        }
        if state.depth_write {
            self.depth.store_f32(i, f.depth);
        }
        true
    }
}
