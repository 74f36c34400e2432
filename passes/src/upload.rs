//! Packs a loaded scene into the imported resources the graphs declare
//! (`frame`, `models`, `lights`, `mesh.triangles`, `groom.*`), as 32-bit
//! words every backend uploads unchanged.

use crate::layout::{
    FrameData, LightData, MODEL_FACIAL_HAIR, MODEL_LOD_ENABLED, ModelData, TriangleData, words_of,
};
use glam::{Mat4, Vec3};
use std::borrow::Cow;
use std::collections::BTreeMap;
use strandgraph_assets::octahedral::pack_unit_vector;
use strandgraph_assets::scene::{Light, SceneGroom};
use strandgraph_assets::{Groom, Scene};
use strandgraph_graph::Quantities;

/// Near plane distance in metres; hair closer than this is clipped.
pub const NEAR: f32 = 0.02;
/// Far plane distance in metres.
pub const FAR: f32 = 500.0;

/// Imported resources by name, plus the quantities that size the plan.
#[derive(Debug, Clone, Default)]
pub struct Upload {
    pub resources: BTreeMap<String, Vec<u32>>,
    pub quantities: Quantities,
    pub frame: Option<FrameData>,
    pub models: Vec<ModelData>,
}

impl Upload {
    pub fn set(&mut self, name: &str, words: Vec<u32>) {
        self.resources.insert(name.to_string(), words);
    }
}

/// Camera matrices for a scene at a resolution.
pub fn frame(scene: &Scene, width: u32, height: u32, models: u32) -> FrameData {
    let (eye, target, fov) = scene.desc.camera.eye_target_fov();
    let (eye, target) = (Vec3::from(eye), Vec3::from(target));
    let view = Mat4::look_at_rh(eye, target, Vec3::Y);
    let proj = Mat4::perspective_rh(
        fov.to_radians(),
        width as f32 / height.max(1) as f32,
        NEAR,
        FAR,
    );
    let view_proj = proj * view;
    FrameData {
        view_proj: view_proj.to_cols_array(),
        inv_view_proj: view_proj.inverse().to_cols_array(),
        camera_pos: [eye.x, eye.y, eye.z, 1.0],
        screen: [
            width as f32,
            height as f32,
            1.0 / width as f32,
            1.0 / height as f32,
        ],
        near: NEAR,
        far: FAR,
        model_count: models,
        light_count: scene.desc.lights.len() as u32,
        pixels_per_unit: proj.y_axis.y * height as f32 * 0.5,
        time: 0.0,
        delta_time: 0.0,
        sim_reset: 1,
        _pad: [0; 16],
    }
}

/// Packs `scene` for a `width`×`height` frame.
pub fn upload(scene: &Scene, width: u32, height: u32) -> Upload {
    let mut up = Upload::default();
    let (triangles, triangle_first) = pack_triangles(scene);
    let hair = pack_grooms(scene, &triangle_first);
    let lights: Vec<LightData> = scene.desc.lights.iter().map(light_data).collect();
    let frame = frame(scene, width, height, hair.models.len() as u32);
    let counts = scene.counts();
    up.quantities = Quantities {
        strands: hair.strands.len() as u64,
        vertices: hair.vertices.len() as u64,
        segments: hair.segments,
        bundles: counts.bundles,
        mesh_strands: counts.mesh_strands,
        models: hair.models.len() as u64,
        // Built only for graphs that draw them (scheuermann::upload::pack).
        patches: 0,
        triangles: triangles.len() as u64,
        lights: lights.len() as u64,
        width,
        height,
    };
    up.set("frame", words_of(&[frame]));
    up.set("models", words_of(&hair.models));
    up.set("lights", words_of(&lights));
    up.set("mesh.triangles", words_of(&triangles));
    up.set(
        "groom.vertices",
        bytemuck::cast_slice(&hair.vertices).to_vec(),
    );
    up.set(
        "groom.strands",
        bytemuck::cast_slice(&hair.strands).to_vec(),
    );
    up.set(
        "groom.skinning",
        bytemuck::cast_slice(&hair.skinning).to_vec(),
    );
    // Lipp: hair-mesh bundles, layers and the environment SH (passes/src/lipp/upload.rs).
    crate::lipp::upload::pack(scene, &mut up);
    up.frame = Some(frame);
    up.models = hair.models;
    up
}

/// Every mesh's triangles in world space with packed world normals
/// (`mesh.triangles`), and the index of each mesh's first triangle.
fn pack_triangles(scene: &Scene) -> (Vec<TriangleData>, Vec<u32>) {
    let mut triangles = Vec::new();
    let mut triangle_first = Vec::new();
    for (i, m) in scene.meshes.iter().enumerate() {
        triangle_first.push(triangles.len() as u32);
        let world = m.mesh.transform.matrix();
        let normal_matrix = glam::Mat3::from_mat4(world).inverse().transpose();
        let normals = m.mesh.vertex_normals();
        for (t, tri) in m.mesh.triangles.iter().enumerate() {
            let [a, b, c] = m.mesh.corners(t).map(|p| world.transform_point3(p));
            let n = |k: usize| {
                let v = normals.get(tri[k] as usize).copied().unwrap_or(Vec3::Y);
                f32::from_bits(pack_unit_vector((normal_matrix * v).normalize_or(Vec3::Y)))
            };
            let albedo = |k: usize| {
                m.mesh
                    .colors
                    .get(tri[k] as usize)
                    .map_or(0, |c| crate::layout::pack_albedo(c.to_array()))
            };
            triangles.push(TriangleData {
                a: [a.x, a.y, a.z, n(0)],
                b: [b.x, b.y, b.z, n(1)],
                c: [c.x, c.y, c.z, n(2)],
                mesh: i as u32,
                albedo: [albedo(0), albedo(1), albedo(2)],
            });
        }
    }
    (triangles, triangle_first)
}

/// The grooms' strands as the pipelines read them: `groom.vertices`,
/// `groom.strands` and `groom.skinning`, and one model per groom, in scene
/// order.
#[derive(Default)]
struct PackedGrooms {
    vertices: Vec<[f32; 4]>,
    strands: Vec<[u32; 2]>,
    skinning: Vec<[u32; 4]>,
    models: Vec<ModelData>,
    /// Segments packed so far (strands × (points − 1)).
    segments: u64,
}

fn pack_grooms(scene: &Scene, triangle_first: &[u32]) -> PackedGrooms {
    let mut hair = PackedGrooms::default();
    for g in &scene.grooms {
        let groom = uniform_groom(g);
        let points = groom.uniform_points_per_strand().unwrap_or(2) as u32;
        let skinned = g.parent.is_some()
            && g.skinning
                .as_ref()
                .is_some_and(|s| s.len() == groom.strand_count());
        let model = hair.model(scene, g, &groom, skinned, triangle_first);
        hair.models.push(model);
        hair.segments += groom.strand_count() as u64 * u64::from(points - 1);
        hair.push_strands(g, &groom, skinned);
    }
    hair
}

/// The pipelines index segments as strand × (points − 1): grooms whose
/// strands vary in length are resampled to the longest strand's count.
pub(crate) fn uniform_groom(g: &SceneGroom) -> Cow<'_, Groom> {
    if g.groom.uniform_points_per_strand().is_some() {
        return Cow::Borrowed(&g.groom);
    }
    let n = (0..g.groom.strand_count())
        .map(|s| g.groom.strand_range(s).len())
        .max()
        .unwrap_or(2);
    tracing::info!(groom = %g.name, points = n, "resampling strands to a uniform point count");
    Cow::Owned(g.groom.resampled(n))
}

impl PackedGrooms {
    /// The model record of groom `g` (its strands `groom`), whose strands
    /// are packed next.
    fn model(
        &self,
        scene: &Scene,
        g: &SceneGroom,
        groom: &Groom,
        skinned: bool,
        triangle_first: &[u32],
    ) -> ModelData {
        let points = groom.uniform_points_per_strand().unwrap_or(2) as u32;
        let bounds = g.world_bounds();
        let mesh_rotation = g
            .parent
            .map_or(Mat4::IDENTITY, |p| scene.meshes[p].mesh.transform.matrix());
        let rot = glam::Mat3::from_mat4(mesh_rotation);
        let row = |r: usize| [rot.row(r).x, rot.row(r).y, rot.row(r).z, 0.0];
        let color = g.material.color();
        let fedora = g.fedora;
        ModelData {
            world: g.world.to_cols_array(),
            bounds_min: [bounds.min.x, bounds.min.y, bounds.min.z, 0.0],
            bounds_max: [bounds.max.x, bounds.max.y, bounds.max.z, 0.0],
            strand_first: self.strands.len() as u32,
            strand_count: groom.strand_count() as u32,
            points_per_strand: points,
            vertex_first: self.vertices.len() as u32,
            segment_first: self.segments as u32,
            skinned: u32::from(skinned),
            triangle_first: g.parent.map_or(0, |p| triangle_first[p]),
            flags: if g.lod.enabled { MODEL_LOD_ENABLED } else { 0 }
                | if g.facial_hair { MODEL_FACIAL_HAIR } else { 0 },
            mesh_rotation: [row(0), row(1), row(2)],
            color: [color[0], color[1], color[2], g.material.roughness],
            fedora_min: fedora.map_or([0.0; 4], |f| {
                [f.box_min[0], f.box_min[1], f.box_min[2], 1.0]
            }),
            fedora_max: fedora.map_or([0.0; 4], |f| {
                [f.box_max[0], f.box_max[1], f.box_max[2], 0.0]
            }),
            fedora_sphere: fedora.map_or([0.0; 4], |f| {
                [
                    f.sphere_center[0],
                    f.sphere_center[1],
                    f.sphere_center[2],
                    f.sphere_radius,
                ]
            }),
            min_fraction: g.lod.min_fraction,
            highlight_shift: g.material.highlight_shift_deg.to_radians(),
            thickness: groom.thickness.first().copied().unwrap_or(0.0),
            _pad: 0,
        }
    }

    /// Appends each strand of `groom`: its range, its vertices (position,
    /// thickness) and its root's skinning (zero when not `skinned`).
    fn push_strands(&mut self, g: &SceneGroom, groom: &Groom, skinned: bool) {
        for s in 0..groom.strand_count() {
            let range = groom.strand_range(s);
            self.strands
                .push([self.vertices.len() as u32, range.len() as u32]);
            for p in range {
                let q = groom.positions[p];
                self.vertices.push([q.x, q.y, q.z, groom.thickness[p]]);
            }
            let info = g
                .skinning
                .as_ref()
                .filter(|_| skinned)
                .and_then(|k| k.get(s));
            self.skinning.push(info.map_or([0; 4], |k| {
                [
                    k.idx_triangle,
                    k.barycentrics,
                    k.triangle_normal,
                    k.triangle_tangent,
                ]
            }));
        }
    }
}

/// A scene light as `lights` holds it: w = 0 for a direction (the way the
/// light travels), 1 for a position; radiance `color × intensity`.
fn light_data(light: &Light) -> LightData {
    let radiance = |color: [f32; 3], intensity: f32| {
        [
            color[0] * intensity,
            color[1] * intensity,
            color[2] * intensity,
            0.0,
        ]
    };
    match *light {
        Light::Directional {
            direction,
            color,
            intensity,
        } => {
            let d = Vec3::from(direction).normalize_or(Vec3::NEG_Y);
            LightData {
                position_or_direction: [d.x, d.y, d.z, 0.0],
                radiance: radiance(color, intensity),
                _pad: [0; 8],
            }
        }
        Light::Point {
            position,
            color,
            intensity,
        } => LightData {
            position_or_direction: [position[0], position[1], position[2], 1.0],
            radiance: radiance(color, intensity),
            _pad: [0; 8],
        },
    }
}

/// The packed resource [`bake_shadow_sh`] fills: 4 × f32 per packed vertex.
pub const SHADOW_SH: &str = "groom.shadow_sh";

/// Kulikov, "Precomputed self-shadowing": the bake's geometry from a packed
/// scene, in the packed vertex order (so the SH lines up with
/// `groom.vertices` one to one, resampled strands included): world-space
/// vertices (each model's rest pose through its world matrix), the strand
/// table, and every scene triangle as an opaque occluder ("We trace against
/// the parent mesh as well so hair is always shadowed by the head").
pub fn shadow_bake_geometry(up: &Upload) -> ShadowBakeGeometry {
    let words = |name: &str| up.resources.get(name).map_or(&[][..], Vec::as_slice);
    let local: &[[f32; 4]] = bytemuck::cast_slice(words("groom.vertices"));
    let mut vertices = local.to_vec();
    for m in &up.models {
        let world = Mat4::from_cols_array(&m.world);
        let first = m.vertex_first as usize;
        let n = m.strand_count as usize * m.points_per_strand as usize;
        for v in vertices.iter_mut().skip(first).take(n) {
            let p = world.transform_point3(Vec3::new(v[0], v[1], v[2]));
            *v = [p.x, p.y, p.z, v[3]];
        }
    }
    let strands = bytemuck::cast_slice(words("groom.strands")).to_vec();
    let triangles = words("mesh.triangles")
        .chunks_exact(16)
        .map(|t| {
            let corner = |k: usize| [0, 1, 2].map(|i| f32::from_bits(t[4 * k + i]));
            [corner(0), corner(1), corner(2)]
        })
        .collect();
    ShadowBakeGeometry {
        vertices,
        strands,
        triangles,
    }
}

/// What [`shadow_bake_geometry`] returns; [`Self::input`] borrows it for the bake.
#[derive(Debug, Clone, Default)]
pub struct ShadowBakeGeometry {
    pub vertices: Vec<[f32; 4]>,
    pub strands: Vec<[u32; 2]>,
    pub triangles: Vec<[[f32; 3]; 3]>,
}

impl ShadowBakeGeometry {
    pub fn input(&self) -> strandgraph_bake::BakeInput<'_> {
        strandgraph_bake::BakeInput {
            vertices: &self.vertices,
            strands: &self.strands,
            triangles: &self.triangles,
        }
    }
}

/// Bakes (or loads from the cache in `cache`) the self-shadowing SH of
/// every packed vertex and stores it as [`SHADOW_SH`].
pub fn bake_shadow_sh(
    up: &mut Upload,
    settings: &strandgraph_bake::BakeSettings,
    cache: Option<&std::path::Path>,
) -> Result<strandgraph_bake::BakeOutcome, strandgraph_bake::BakeError> {
    let geometry = shadow_bake_geometry(up);
    let (sh, outcome) = strandgraph_bake::bake_cached(&geometry.input(), settings, cache)?;
    up.set(SHADOW_SH, bytemuck::cast_slice(&sh).to_vec());
    Ok(outcome)
}
