//! `kulikov.skin`: strand roots follow their triangle, and every drawn vertex
//! goes to clip space into the post-transform cache.
//!
//! Kulikov, "Skinning": "Skin directly to triangles, store triangle
//! barycentrics and compressed tangent frame for each strand ... Store
//! post-transformed results in global cache (before division by w)".
//! A strand keeps its bind-pose shape relative to the root's tangent frame:
//! `p = root_now + R (p_bind - root_bind)`, `R = frame_now · frame_bindᵀ`.

use super::lod::SKIN_GROUP;
use super::motion::{NOT_TRANSFORMED, drawn_at, motion, pack};
use super::{ModelLod, Scene, transform};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::layout::{ModelData, TriangleData, read};
use crate::params::NoParams;
use glam::{Mat4, Vec3};
use strandgraph_assets::octahedral::{unpack_barycentrics, unpack_unit_vector};

crate::gpu_block! {
    /// `SkinParams`: one reserved word.
    pub struct SkinGpu {
        reserved: u32,
    }
}

/// The bindings of both skinning kinds, then `$extra`.
macro_rules! skin_bindings {
    ($($extra:expr),* $(,)?) => {
        &[
            Binding::read("lod_args"),
            Binding::read("frame"),
            Binding::read("models"),
            Binding::read("lod_models"),
            Binding::read("groom.vertices"),
            Binding::read("groom.strands"),
            Binding::read("groom.skinning"),
            Binding::read("mesh.triangles"),
            Binding::write("clip_positions"),
            $($extra),*
        ]
    };
}

/// A lane per kept strand: the LOD's first indirect dispatch.
const PER_KEPT_STRAND: Dispatch = Dispatch::Indirect {
    binding: "lod_args",
    word: 0,
};

pub static SKIN: PassKind<NoParams, SkinGpu> = PassKind {
    kind: "kulikov.skin",
    summary: "skin roots to triangles (hairRootSkinningInfo_t) and cache post-transform positions",
    source: "Kulikov 2025, 'Skinning'",
    bindings: Some(skin_bindings!()),
    workgroup_size: SKIN_GROUP,
    dispatch: PER_KEPT_STRAND,
    shader: Shader::compute("kulikov/skin.wgsl", "skin"),
    kernel: |_| Box::new(SkinKernel { motion: false }),
    gpu: |_, _| SkinGpu::default(),
    raster: None,
};

/// `kulikov.skin` that also keeps the motion vectors (motion.rs): each
/// drawn vertex's motion against last frame's history, then this frame's
/// NDC over it. Ours: the talk's motion pass reads the post-transform cache
/// back; here the pass that writes it does the work while the vertex is at
/// hand, over drawn vertices only, and no pass clears the cache first.
pub static SKIN_MOTION: PassKind<NoParams, SkinGpu> = PassKind {
    kind: "kulikov.skin_motion",
    summary: "kulikov.skin, plus per-vertex motion vectors against last frame's compressed NDC (UNORM16), which it then overwrites",
    source: "Kulikov 2025, 'Skinning', 'Motion vectors'",
    bindings: Some(skin_bindings!(
        Binding::read("prev_lod_models"),
        Binding::write("prev_clip_positions"),
        Binding::write("vertex_motion"),
    )),
    workgroup_size: SKIN_GROUP,
    dispatch: PER_KEPT_STRAND,
    shader: Shader::compute("kulikov/skin.wgsl", "skin_motion"),
    kernel: |_| Box::new(SkinKernel { motion: true }),
    gpu: |_, _| SkinGpu::default(),
    raster: None,
};

struct SkinKernel {
    /// `kulikov.skin_motion`.
    motion: bool,
}

/// One kept strand's view of the vertex history (`kulikov.skin_motion`).
struct History<'a> {
    /// Whether last frame's LOD kept this strand, and its vertex step.
    kept_last_frame: bool,
    step_last_frame: u32,
    words: Words<'a>,
    motion: Words<'a>,
}

impl<'a> History<'a> {
    fn open(ctx: &Ctx<'a>, model: usize, kept: u32) -> Self {
        let prev = ModelLod::load(&ctx.words("prev_lod_models"), model);
        Self {
            kept_last_frame: kept < prev.strands,
            step_last_frame: prev.vertex_step,
            words: ctx.words("prev_clip_positions"),
            motion: ctx.words("vertex_motion"),
        }
    }

    /// Drawn vertex `v` of a strand of `count` points, global index `i`,
    /// now at clip `c`: its motion against last frame's word (none where
    /// last frame did not draw it), then this frame's word over it.
    fn update(&self, scene: &Scene, i: usize, v: u32, count: u32, c: [f32; 4]) {
        let f = &scene.frame;
        let last = if self.kept_last_frame && drawn_at(v, self.step_last_frame, count) {
            self.words.load(i)
        } else {
            NOT_TRANSFORMED
        };
        let m = motion(last, c, f.near, f.screen[0], f.screen[1]);
        self.motion.store(2 * i, m[0].to_bits());
        self.motion.store(2 * i + 1, m[1].to_bits());
        self.words.store(i, pack(c, f.near));
    }
}

fn vec3(v: [f32; 4]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

/// Where a strand's root is now and how its bind frame has rotated.
struct RootMotion {
    root_bind: Vec3,
    root_now: Vec3,
    /// (tangent, normal, bitangent) now and at bind time, in world space.
    now: [Vec3; 3],
    bind: [Vec3; 3],
}

impl RootMotion {
    fn apply(&self, p_bind: Vec3) -> Vec3 {
        let d = p_bind - self.root_bind;
        self.root_now
            + (0..3)
                .map(|i| self.now[i] * d.dot(self.bind[i]))
                .sum::<Vec3>()
    }
}

fn root_motion(
    m: &ModelData,
    world: &Mat4,
    root_local: Vec3,
    info: [u32; 4],
    tris: &Words<'_>,
) -> Option<RootMotion> {
    let t: TriangleData = read(tris, (m.triangle_first + info[0]) as usize);
    let (a, b, c) = (vec3(t.a), vec3(t.b), vec3(t.c));
    let w = unpack_barycentrics(info[1]);
    let n = (b - a).cross(c - a).try_normalize()?;
    let tan = (b - a).reject_from(n).try_normalize()?;
    let rot = |v: Vec3| {
        let r = &m.mesh_rotation;
        Vec3::new(vec3(r[0]).dot(v), vec3(r[1]).dot(v), vec3(r[2]).dot(v))
    };
    let (nb, tb) = (
        rot(unpack_unit_vector(info[2])).normalize(),
        rot(unpack_unit_vector(info[3])).normalize(),
    );
    Some(RootMotion {
        root_bind: world.transform_point3(root_local),
        root_now: a * w.x + b * w.y + c * w.z,
        now: [tan, n, n.cross(tan)],
        bind: [tb, nb, nb.cross(tb)],
    })
}

impl CpuKernel for SkinKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let (verts, strands, skinning, tris, out) = (
            ctx.words("groom.vertices"),
            ctx.words("groom.strands"),
            ctx.words("groom.skinning"),
            ctx.words("mesh.triangles"),
            ctx.words("clip_positions"),
        );
        let total = ctx.words("lod_args").load(3);
        let lods = scene.lods(ctx);
        for lane in 0..SKIN_GROUP {
            let g = group * SKIN_GROUP + lane;
            if g >= total {
                break;
            }
            let Some(m) = lods
                .iter()
                .position(|l| g >= l.strand_prefix && g < l.strand_prefix + l.strands)
            else {
                continue;
            };
            let (model, lod) = (&scene.models[m], &lods[m]);
            let strand = (model.strand_first + g - lod.strand_prefix) as usize;
            let (first, count) = (strands.load(2 * strand), strands.load(2 * strand + 1));
            let world = Mat4::from_cols_array(&model.world);
            let local = |v: u32| vec3(verts.load_vec4((first + v) as usize));
            let info = [0, 1, 2, 3].map(|k| skinning.load(4 * strand + k));
            let motion = if model.skinned != 0 {
                root_motion(model, &world, local(0), info, &tris)
            } else {
                None
            };
            let kept = g - lod.strand_prefix;
            let history = self.motion.then(|| History::open(ctx, m, kept));
            let mut v = 0;
            loop {
                let p = world.transform_point3(local(v));
                let p = motion.as_ref().map_or(p, |mo| mo.apply(p));
                let c = transform(&scene.frame.view_proj, [p.x, p.y, p.z, 1.0]);
                out.store_vec4((first + v) as usize, c);
                if let Some(h) = &history {
                    h.update(&scene, (first + v) as usize, v, count, c);
                }
                if v + 1 >= count {
                    break;
                }
                v = (v + lod.vertex_step).min(count - 1);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unmoved_mesh_keeps_the_strand_in_place() {
        // A triangle in the xz plane with a root at its centroid and a strand along +y.
        let (a, b, c) = (
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, -1.0),
        );
        let n = (b - a).cross(c - a).normalize();
        let tan = (b - a).reject_from(n).normalize();
        let pack = strandgraph_assets::octahedral::pack_unit_vector;
        let bary = strandgraph_assets::octahedral::pack_barycentrics(Vec3::splat(1.0 / 3.0));
        let tri = TriangleData {
            a: [0.0; 4],
            b: [1.0, 0.0, 0.0, 0.0],
            c: [0.0, 0.0, -1.0, 0.0],
            mesh: 0,
            albedo: [0; 3],
        };
        let words = crate::layout::words_of(&[tri]);
        let atoms: Vec<_> = words
            .into_iter()
            .map(std::sync::atomic::AtomicU32::new)
            .collect();
        let oob = std::sync::atomic::AtomicU64::new(0);
        let tris = Words::new(&atoms, &oob);
        let mut m: ModelData = bytemuck::Zeroable::zeroed();
        m.mesh_rotation = [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ];
        let root = (a + b + c) / 3.0;
        let mo = root_motion(
            &m,
            &Mat4::IDENTITY,
            root,
            [0, bary, pack(n), pack(tan)],
            &tris,
        )
        .unwrap();
        let tip = root + Vec3::new(0.0, 0.3, 0.0);
        assert!((mo.apply(tip) - tip).length() < 1e-3, "{:?}", mo.apply(tip));
    }
}
