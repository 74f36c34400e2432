//! `lipp.shade`: Lipp §3.4, deferred shading of both G-buffer layers, one
//! invocation per pixel, into the `shaded` records ([`super::shaded`]:
//! RGB9E5 radiance, depth and hit flags). Only the centre layer's record is
//! written where no sample is (the filter's taps read its flags); the tiles
//! with a sample are listed for `lipp.filter` ([`super::tiles`],
//! `hair_tiles`). The pass runs over the groom's screen rectangle (ours,
//! [`super::rect`]): a workgroup per run of 64 pixels the rectangle
//! touches, through the indirect dispatch `lipp.lod_scan` writes (the
//! scan's `groom_rect` off: the whole screen, as the paper's deferred
//! shading does).
//!
//! The WGSL gives each pixel two threads, one per G-buffer layer: a far
//! groom covers a few tiles, too few threads to hide the latency of a
//! sample's shading (dependent loads of the maps and the probe, Chiang's
//! transcendentals), which then sets the pass's time.
//!
//! Position is reconstructed from the 24-bit depth at the pixel centre ("we
//! use the common approach in deferred engines and reconstruct it from the
//! depth value", §3.1.2); the tangent is the octahedral one; the material is
//! the groom's (`models[model_index]`, one groom per pass in the graph's
//! per-model block) colour and roughness, varied per strand by its (u, v).
//!
//! Single scattering is Chiang et al. 2016 (R, TT, TRT) in the compact form
//! of [`super::chiang`]: pbrt-v4's `HairBxDF` averaged over the fibre width,
//! checked against a transcription of it (per-lobe albedo within 1.5%,
//! relative L1 over the sphere within 7.4%).
//!
//! Multiple scattering is the Kajiya-Kay-like diffuse term Lipp uses
//! ("a Lambertian term similar to Kajiya-Kay's"): colour · sin(T, L) / π.
//! Lights are directional and point lights, shadowed by the deep opacity
//! maps of `lipp.dom_depth` / `lipp.dom_opacity` (`dom_shadows`), looked up
//! Δ = −log β layers nearer the light (Lipp Eq. 8, `lod_depth_correction`;
//! β = drawn / all strands of the groom in the camera's view, from the
//! groom's `raster_args`, since a G-buffer pixel does not know its bundle).
//! The paper builds its maps from "the full geometry set" and shifts the
//! lookups of the strands the camera's LOD kept; ours are built from the
//! shadow LOD's strands with their opacity scaled up to stand for the whole
//! groom (`lipp.dom_opacity`'s density compensation), so the shift is the
//! paper's, for the camera's β. The head casts no shadow on the hair: the
//! maps hold hair only (Yuksel and Keyser 2008), as in the paper.
//!
//! Probe lighting (Lipp §3.4, [`super::probe`]), times the hair mesh's baked
//! AO: the diffuse part is `env.sh`'s irradiance (L2 SH, Ramamoorthi and
//! Hanrahan 2001) at the fibre normal facing the viewer, times colour / π;
//! the specular part (`probe_specular`) is one GGX lobe standing in for
//! R + TRT, looked up in `env.prefiltered` (Karis 2013's prefiltered
//! environment) along the specular cone and weighted by A_R + A_TRT
//! ([`super::probe::specular_lobe`] says how the lobe is chosen).

pub use super::chiang::{FibrePaths, Material, chiang, sigma_a};
use super::dom::{LightFrame, NO_HIT, OPACITY_SCALE, light_frames};
use super::payload::{EMPTY, Sample, unpack};
use super::probe;
use super::rect::{ARGS_RECT_HI, ARGS_RECT_LO, ARGS_RUNS, FILTER_RECT_HI, FILTER_RECT_LO, Rect};
use super::shaded::{HIT, pixel_flags, read_by_filter, record};
use super::tiles;
use super::{ARGS_ALL, ARGS_KEPT, add, dot, frame, normalize, pcg, scale, sub, transform, unit};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::layout::{FrameData, LightData, ModelData, read};
use crate::params::{Invalid, PassParams, in_range};
use strandgraph_graph::Quantities;

pub const SHADE_GROUP: u32 = tiles::TILE;
const PI: f32 = std::f32::consts::PI;

crate::string_enum! {
    /// The hair scattering model (only Chiang 2016 so far).
    pub enum HairModel {
        Chiang16,
    }
}

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShadeParams {
    pub model: HairModel,
    pub multiple_scattering: bool,
    pub probe_lighting: bool,
    /// With `probe_lighting`: the prefiltered GGX lookup for R + TRT.
    pub probe_specular: bool,
    /// Scales the single-scattering lobes (1 = Chiang).
    pub specular: f32,
    /// Volumetric shadows from the deep opacity maps (`lipp.dom_*`).
    pub dom_shadows: bool,
    /// Lipp Eq. 8: look the maps up Δ = −log β layers nearer the light.
    pub lod_depth_correction: bool,
    /// The maps' geometry, as the `lipp.dom_*` passes were given it.
    pub dom_resolution: u32,
    pub dom_layers: u32,
    pub dom_layer_thickness: f32,
    /// The groom shaded (its material), in the graph's per-model block.
    pub model_index: u32,
    /// Ours: list only the tiles with hair for `lipp.filter` ([`super::tiles`]);
    /// off, every tile.
    pub hair_tiles: bool,
    /// Metres of linear depth a conservative sample must lie in front of
    /// the centre one to be blended over it by `lipp.filter` as a flyaway
    /// (§3.3.2; the records' [`super::shaded::FRONT`] flag; filter.rs says why
    /// metres).
    pub front_threshold: f32,
    /// Ours (the paper does not say which samples it shades): shade a
    /// conservative sample only where `lipp.filter` reads its colour
    /// ([`read_by_filter`]: no centre sample, or a flyaway in front); off,
    /// every sample. The pictures are the same.
    pub read_layers_only: bool,
    /// Ours: lanes the dispatch of `lipp.filter` that this pass lists tiles
    /// for is sized to fill ([`super::tiles::filter_groups`]): a groom of
    /// few tiles gets up to sixteen lanes a pixel, its windows split over
    /// them; 0: a workgroup a tile, two lanes a pixel. The default, 2^19,
    /// is about twice what an H100 or H200 holds in flight (132 SMs of
    /// 2,048 lanes): on the H200 the mid view's filter took 0.047 ms with
    /// 2^18 and 0.041 with 2^19.
    pub filter_lane_budget: u32,
}

impl Default for ShadeParams {
    fn default() -> Self {
        Self {
            model: HairModel::Chiang16,
            multiple_scattering: true,
            probe_lighting: true,
            probe_specular: true,
            specular: 1.0,
            dom_shadows: true,
            lod_depth_correction: true,
            dom_resolution: 512,
            dom_layers: 4,
            dom_layer_thickness: 0.02,
            model_index: 0,
            hair_tiles: true,
            front_threshold: 0.01,
            read_layers_only: true,
            filter_lane_budget: 1 << 19,
        }
    }
}

impl PassParams for ShadeParams {
    const READS_MODEL_INDEX: bool = true;

    fn validate(&self) -> Result<(), Invalid> {
        in_range("dom_resolution", self.dom_resolution, 16..=4096)?;
        in_range("dom_layers", self.dom_layers, 1..=8)?;
        if !(self.dom_layer_thickness.is_finite() && self.dom_layer_thickness > 0.0) {
            return Err(Invalid::new("dom_layer_thickness", "must be positive"));
        }
        if !(self.front_threshold.is_finite() && self.front_threshold >= 0.0) {
            return Err(Invalid::new("front_threshold", "must be at least 0"));
        }
        Ok(())
    }
}

crate::gpu_block! {
    /// `ShadeParams` in shaders/lipp/shade.wgsl.
    pub struct ShadeGpu {
        multiple_scattering: u32,
        probe_lighting: u32,
        specular: f32,
        /// Scene quantities.
        width: u32,
        height: u32,
        lights: u32,
        dom_shadows: u32,
        lod_depth_correction: u32,
        dom_resolution: u32,
        dom_layers: u32,
        dom_layer_thickness: f32,
        model_index: u32,
        probe_specular: u32,
        /// `lipp.reference_shade` only: point slots to shade (the mesh
        /// strands × [`super::reference::SLOTS`]); 0 here.
        slots: u32,
        /// `lipp.shade` only: list only the tiles with hair.
        hair_tiles: u32,
        /// `lipp.shade` only: [`ShadeParams::front_threshold`].
        front_threshold: f32,
        /// `lipp.shade` only: [`ShadeParams::read_layers_only`].
        read_layers_only: u32,
        /// `lipp.shade` only: [`ShadeParams::filter_lane_budget`].
        filter_lane_budget: u32,
        reserved_b: u32,
        reserved_c: u32,
    }
}

/// The shading parameters as both shading passes' shaders read them.
pub fn shade_gpu(p: &ShadeParams, q: &Quantities, slots: u32) -> ShadeGpu {
    ShadeGpu {
        multiple_scattering: flag(p.multiple_scattering),
        probe_lighting: flag(p.probe_lighting),
        specular: p.specular,
        width: q.width,
        height: q.height,
        lights: count(q.lights),
        dom_shadows: flag(p.dom_shadows),
        lod_depth_correction: flag(p.lod_depth_correction),
        dom_resolution: p.dom_resolution,
        dom_layers: p.dom_layers,
        dom_layer_thickness: p.dom_layer_thickness,
        model_index: p.model_index,
        probe_specular: flag(p.probe_specular),
        slots,
        hair_tiles: flag(p.hair_tiles),
        front_threshold: p.front_threshold,
        read_layers_only: flag(p.read_layers_only),
        filter_lane_budget: p.filter_lane_budget,
        reserved_b: 0,
        reserved_c: 0,
    }
}

pub static SHADE: PassKind<ShadeParams, ShadeGpu> = PassKind {
    kind: "lipp.shade",
    summary: "deferred shading: Chiang 2016 R/TT/TRT, Kajiya-Kay multiple scattering, DOM shadows, probe lighting",
    source: "Lipp §3.4",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("lights"),
        Binding::read("env.sh"),
        Binding::read("gbuffer"),
        Binding::read("raster_args"),
        Binding::read("dom_depth"),
        Binding::read("dom_layers"),
        Binding::write("shaded"),
        Binding::read("env.prefiltered"),
        Binding::write("filter_tiles"),
        // The filter's dispatch and the shaded rectangle (rect.rs).
        Binding::atomic("filter_args").at_least(super::rect::FILTER_RECT_HI as u32 + 1),
    ]),
    // Threads: two a pixel, one per layer (shaders/lipp/shade.wgsl).
    workgroup_size: 2 * SHADE_GROUP,
    // A workgroup per run of the groom's rectangle (rect::Rect::runs).
    dispatch: Dispatch::Indirect {
        binding: "raster_args",
        word: ARGS_RUNS,
    },
    shader: Shader::compute("lipp/shade.wgsl", "shade"),
    kernel: |p| Box::new(ShadeKernel(*p)),
    gpu: |p, q| shade_gpu(p, q, 0),
    raster: None,
};

/// Irradiance from L2 SH radiance coefficients at unit normal `n`
/// (Ramamoorthi and Hanrahan 2001, Eq. 13).
pub fn sh_irradiance(sh: &[[f32; 3]; 9], n: [f32; 3]) -> [f32; 3] {
    let (x, y, z) = (n[0], n[1], n[2]);
    let (c1, c2, c3, c4, c5) = (0.429_043, 0.511_664, 0.743_125, 0.886_227, 0.247_708);
    std::array::from_fn(|k| {
        let l = |i: usize| sh[i][k];
        c1 * l(8) * (x * x - y * y) + c3 * l(6) * z * z + c4 * l(0) - c5 * l(6)
            + 2.0 * c1 * (l(4) * x * y + l(7) * x * z + l(5) * y * z)
            + 2.0 * c2 * (l(3) * x + l(1) * y + l(2) * z)
    })
}

/// World position of pixel (x, y) at NDC depth z.
pub fn world_position(f: &FrameData, x: u32, y: u32, z: f32) -> [f32; 3] {
    let ndc_x = (x as f32 + 0.5) * f.screen[2] * 2.0 - 1.0;
    let ndc_y = 1.0 - (y as f32 + 0.5) * f.screen[3] * 2.0;
    let p = transform(&f.inv_view_proj, [ndc_x, ndc_y, z, 1.0]);
    [p[0] / p[3], p[1] / p[3], p[2] / p[3]]
}

/// Everything the shading of one sample reads.
pub struct Inputs<'a> {
    pub f: &'a FrameData,
    pub model: &'a ModelData,
    pub lights: &'a [LightData],
    pub sh: [[f32; 3]; 9],
    /// `env.prefiltered` ([`super::probe`]'s layout).
    pub prefiltered: Words<'a>,
    pub params: &'a ShadeParams,
    /// The deep opacity maps and their light views (one per mapped light).
    pub dom: Option<Dom<'a>>,
}

impl<'a> Inputs<'a> {
    /// What the shading passes' bindings hold (`lipp.shade`'s, which
    /// `lipp.reference_shade` shares), looking the maps up `delta` layers
    /// nearer the light (Lipp Eq. 8).
    pub fn load(
        ctx: &Ctx<'a>,
        f: &'a FrameData,
        model: &'a ModelData,
        lights: &'a [LightData],
        params: &'a ShadeParams,
        delta: f32,
    ) -> Self {
        Inputs {
            f,
            model,
            lights,
            sh: load_sh(&ctx.words("env.sh")),
            prefiltered: ctx.words("env.prefiltered"),
            params,
            dom: params.dom_shadows.then(|| {
                let depth = ctx.words("dom_depth");
                Dom {
                    frames: light_frames(ctx, Some((params.dom_resolution, depth.len()))),
                    depth,
                    layers: ctx.words("dom_layers"),
                    delta,
                }
            }),
        }
    }
}

/// Deep opacity maps as `lipp.shade` reads them.
pub struct Dom<'a> {
    pub frames: Vec<LightFrame>,
    pub depth: Words<'a>,
    pub layers: Words<'a>,
    /// Lipp Eq. 8's Δ = −log β, in layers (0 without the correction).
    pub delta: f32,
}

/// Lipp Eq. 8: Δ = −log β, β = the strands the LOD kept / all strands.
pub fn depth_correction(kept: u32, all: u32) -> f32 {
    if kept == 0 || all == 0 {
        return 0.0;
    }
    -(kept.min(all) as f32 / all as f32).ln()
}

impl Dom<'_> {
    /// Transmittance towards light `l` at `pos` (Yuksel and Keyser 2008):
    /// the opacity of the layers in front of the point's depth behind the
    /// first hit, the layer it is in counted in proportion.
    pub fn transmittance(&self, p: &ShadeParams, l: usize, pos: [f32; 3]) -> f32 {
        let Some(lf) = self.frames.get(l) else {
            return 1.0;
        };
        let res = p.dom_resolution;
        let q = lf.project(pos);
        let (x, y) = ((q[0] * res as f32).floor(), (q[1] * res as f32).floor());
        if !(x >= 0.0 && y >= 0.0 && x < res as f32 && y < res as f32) {
            return 1.0;
        }
        let texel = (y as u32 * res + x as u32) as usize;
        let plane = (res * res) as usize;
        let first = self.depth.load(l * plane + texel);
        if first == NO_HIT {
            return 1.0;
        }
        let d =
            (q[2] - f32::from_bits(first)) * lf.depth_extent / p.dom_layer_thickness - self.delta;
        let mut optical = 0.0;
        for k in 0..p.dom_layers {
            let part = (d - k as f32).clamp(0.0, 1.0);
            let o = self
                .layers
                .load((l * p.dom_layers as usize + k as usize) * plane + texel);
            optical += part * o as f32 / OPACITY_SCALE;
        }
        (-optical).exp()
    }
}

/// Radiance towards the camera of one G-buffer sample at pixel (x, y).
pub fn shade_sample(inp: &Inputs<'_>, s: &Sample, x: u32, y: u32) -> [f32; 3] {
    let pos = world_position(inp.f, x, y, s.depth);
    let q = |x: f32| (x * 63.0 + 0.5).floor() as u32;
    let point = Point {
        pos,
        tangent: s.tangent,
        strand: [q(s.uvw[0]), q(s.uvw[1])],
        ao: s.ao,
    };
    shade_point(inp, inp.model, &point)
}

/// A point of a strand as the shading sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    pub pos: [f32; 3],
    pub tangent: [f32; 3],
    /// The strand's (u, v) in 1/63 steps: its colour variation (the
    /// G-buffer keeps 6 bits of each).
    pub strand: [u32; 2],
    pub ao: f32,
}

/// Radiance towards the camera from `p` on a strand of `model`: Chiang's
/// lobes and Kajiya-Kay multiple scattering per light, shadowed by the
/// deep opacity maps, then the probe's diffuse and specular times AO.
pub fn shade_point(inp: &Inputs<'_>, model: &ModelData, p: &Point) -> [f32; 3] {
    let pos = p.pos;
    let cam = [
        inp.f.camera_pos[0],
        inp.f.camera_pos[1],
        inp.f.camera_pos[2],
    ];
    let v = normalize(sub(cam, pos));
    let t = p.tangent;
    // Per-strand variation from (u, v) (Lipp: shading parameters from uvw).
    let vary = 0.85 + 0.3 * unit(pcg(p.strand[0] | (p.strand[1] << 6)));
    let c = model.color;
    let m = Material {
        color: [c[0] * vary, c[1] * vary, c[2] * vary].map(|x| x.clamp(0.0, 1.0)),
        roughness: c[3],
        alpha: model.highlight_shift,
    };
    // What the fibre's lobes need of the view, for every light and the probe.
    let paths = FibrePaths::new(dot(t, v), &m);
    let mut out = [0.0f32; 3];
    for (li, light) in inp.lights.iter().enumerate() {
        let pd = light.position_or_direction;
        let (l, atten) = if pd[3] == 0.0 {
            (normalize([-pd[0], -pd[1], -pd[2]]), 1.0)
        } else {
            let d = sub([pd[0], pd[1], pd[2]], pos);
            (normalize(d), 1.0 / dot(d, d).max(1e-4))
        };
        let rad = scale(
            [light.radiance[0], light.radiance[1], light.radiance[2]],
            atten,
        );
        let shadow = match &inp.dom {
            Some(dom) => dom.transmittance(inp.params, li, pos),
            None => 1.0,
        };
        let rad = scale(rad, shadow);
        let single = scale(chiang(t, l, v, &m, &paths), inp.params.specular);
        let mut f = single;
        if inp.params.multiple_scattering {
            let sin_tl = (1.0 - dot(t, l) * dot(t, l)).max(0.0).sqrt();
            f = add(f, scale(m.color, sin_tl / PI));
        }
        for k in 0..3 {
            out[k] += f[k] * rad[k];
        }
    }
    if inp.params.probe_lighting {
        // Lipp §3.4: "Ramamoorthi's irradiance expansion centered at a normal
        // of the fiber oriented towards the view direction".
        let n = probe::view_facing_normal(t, v);
        let e = sh_irradiance(&inp.sh, n);
        let spec = if inp.params.probe_specular {
            probe::specular(&inp.prefiltered, t, v, n, &m, &paths)
        } else {
            [0.0; 3]
        };
        for k in 0..3 {
            let diffuse = e[k].max(0.0) / PI * m.color[k];
            out[k] += (diffuse + spec[k] * inp.params.specular) * p.ao;
        }
    }
    out
}

struct ShadeKernel(ShadeParams);

impl ShadeKernel {
    /// The pixels this pass shades ([`super::rect`]): the groom's screen
    /// rectangle, which `lipp.lod_scan` wrote with the dispatch over its
    /// runs. Workgroup 0 tells `lipp.filter` (`filter_args` holds the
    /// words: the binding declares its size).
    fn shaded_rect(&self, ctx: &Ctx<'_>, group: u32) -> Rect {
        let (args, filter_args) = (ctx.words("raster_args"), ctx.words("filter_args"));
        let r = Rect::from_args(args.load(ARGS_RECT_LO), args.load(ARGS_RECT_HI));
        if group == 0 {
            let [lo, hi] = r.args();
            filter_args.store(FILTER_RECT_LO, lo);
            filter_args.store(FILTER_RECT_HI, hi);
        }
        r
    }
}

/// `env.sh` as 9 rgb coefficients.
pub fn load_sh(w: &Words<'_>) -> [[f32; 3]; 9] {
    std::array::from_fn(|i| {
        let v = w.load_vec4(i);
        [v[0], v[1], v[2]]
    })
}

impl CpuKernel for ShadeKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let f = frame(ctx);
        let w = ctx.quantities.width;
        let model: ModelData = read(&ctx.words("models"), self.0.model_index as usize);
        let lw = ctx.words("lights");
        let lights: Vec<LightData> = (0..f.light_count as usize).map(|i| read(&lw, i)).collect();
        let args = ctx.words("raster_args");
        let delta = if self.0.lod_depth_correction {
            depth_correction(args.load(ARGS_KEPT), args.load(ARGS_ALL))
        } else {
            0.0
        };
        let rect = self.shaded_rect(ctx, group);
        let inp = Inputs::load(ctx, &f, &model, &lights, &self.0, delta);
        for run in rect.runs_of_group(w, group, ctx.workgroups) {
            self.shade_run(ctx, &inp, run);
        }
    }
}

impl ShadeKernel {
    /// Run `run`'s 64 pixels (a workgroup of the WGSL).
    fn shade_run(&self, ctx: &Ctx<'_>, inp: &Inputs<'_>, run: u32) {
        let (w, h) = (ctx.quantities.width, ctx.quantities.height);
        let pixels = w * h;
        let (g, out) = (ctx.words("gbuffer"), ctx.words("shaded"));
        let layers = super::gbuffer_layers(&g, &out, pixels);
        let mut hair = false;
        let payload = |layer: u32, i: u32| {
            let slot = (layer * pixels + i) as usize;
            super::payload::from_words(g.load(2 * slot), g.load(2 * slot + 1))
        };
        let store = |slot: u32, r: [u32; 2]| {
            out.store(2 * slot as usize, r[0]);
            out.store(2 * slot as usize + 1, r[1]);
        };
        for i in run * SHADE_GROUP..((run + 1) * SHADE_GROUP).min(pixels) {
            let (x, y) = (i % w, i / w);
            let centre = payload(0, i);
            let flags = pixel_flags(inp.f, centre, payload(1, i), self.0.front_threshold);
            for layer in 0..layers {
                let p = payload(layer, i);
                // The centre layer's record for every pixel (the filter's
                // taps read its flags), the others where a sample is.
                if p == EMPTY {
                    if layer == 0 {
                        store(i, record([0.0; 3], 0, flags));
                    }
                    continue;
                }
                hair = true;
                if self.0.read_layers_only && !read_by_filter(layer, layers, centre != EMPTY, flags)
                {
                    continue;
                }
                let c = shade_sample(inp, &unpack(p), x, y);
                store(layer * pixels + i, record(c, (p >> 32) as u32, HIT | flags));
            }
        }
        if hair || !self.0.hair_tiles {
            let (args, listed) = (ctx.words("filter_args"), ctx.words("filter_tiles"));
            tiles::list(&args, &listed, run, self.0.filter_lane_budget);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_sh_gives_pi_times_radiance() {
        let mut sh = [[0.0; 3]; 9];
        let l00 = 4.0 * PI * 0.282_095;
        sh[0] = [l00; 3];
        let e = sh_irradiance(&sh, [0.0, 1.0, 0.0]);
        assert!((e[0] - PI).abs() < 1e-3, "{e:?}");
    }

    #[test]
    fn eq8_shift_is_zero_without_culling_and_grows_as_strands_go() {
        assert_eq!(depth_correction(100, 100), 0.0);
        assert!((depth_correction(50, 100) - std::f32::consts::LN_2).abs() < 1e-6);
        assert!(depth_correction(10, 100) > depth_correction(50, 100));
        assert_eq!(depth_correction(0, 100), 0.0);
        let v: ron::Value = ron::from_str(r#"{"dom_layers": 0}"#).unwrap();
        assert!(SHADE.params(&v).is_err());
    }
}
