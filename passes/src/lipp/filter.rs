//! `lipp.filter`: Lipp §3.3 and Appendix B Code 2, the single-pass
//! reconnection and opacity-reconstruction filter, blended over the scene.
//!
//! Per pixel P with a centre or conservative sample:
//! - the screen tangent T_P is the projected G-buffer tangent (centre sample
//!   if any, else conservative);
//! - elliptical bilateral filter over a (2r+1)² window (§3.3.1, Eq. 9-10):
//!   d_∥ = d·T_P, d_⊥ = |d − d_∥ T_P|, w = exp(−d_∥²/σ_∥² − d_⊥²/σ_⊥²) ·
//!   exp(−|C_P − C_Q|²/σ_c²), σ_∥ = r s_∥, σ_⊥ = r s_⊥, σ_c = 0.9; only
//!   centre-hit neighbours contribute colour; neighbours whose depth differs
//!   by more than `depth_threshold` are rejected;
//! - strand connection (§3.3.2): conservative-only pixels are *promoted* and
//!   borrow the filtered colour of centre-hit neighbours, with w_color = 1;
//!   where a conservative strand lies in front of the centre hit (depth
//!   mismatch ≥ `lipp.shade`'s `front_threshold`, the records' `FRONT`
//!   flag), its reconstruction is blended over the centre colour and the
//!   output opacity is 1;
//! - alpha (§3.3.3): α_P = H_center / (H_center + H_cons) over the
//!   tangent-aligned strip of width `strip_width` (Code 2 line 45; the text's
//!   H_center / H_cons counts the centre hits among the conservative ones).
//!
//! - hair depth (§3.5, multiple grooms): where the output is at least
//!   `depth_alpha` opaque, the pixel's hair depth goes into `hair_depth`
//!   (in place, min), which the next groom's rasterizer tests against.
//!
//! - true width (ours, `true_width`): the hit ratio above measures the
//!   coverage of lines `centre_diameter` pixels wide (the raster's centre
//!   test), over-covering strands thinner than that by their width ratio
//!   (70 µm is 0.15 px at the close view, 0.03 px at the far). Reading the
//!   ratio f as the coverage 1 − (1 − d)^N of N such lines, the strands'
//!   own coverage is 1 − (1 − w)^N = 1 − (1 − f)^k, k = ln(1 − w) / ln(1 − d),
//!   with w the groom's thickness in pixels at the sample's depth: one
//!   isolated strand gets its width, dense hair (f = 1) stays opaque.
//!   A flyaway in front is then blended with its own opacity rather than
//!   forcing 1.
//!
//! Deviations: depths are compared as linear view depth in metres
//! (`depth_threshold` 0.05, and `lipp.shade`'s `front_threshold` 0.01). The paper's 1.45e-3 and
//! 5e-4 are read here as differences of the payload's NDC depth (the only
//! depth its G-buffer holds): z_ndc = f(z − n) / (z(f − n)) changes by
//! n f / ((f − n) z²) ≈ n / z² per metre, so with our near plane (0.02 m)
//! they are 3.6 cm and 1.2 cm at the close view (0.7 m), 45 and 16 cm at
//! the mid (2.5 m) and 7 and 2.5 m at the far (10 m), where they would
//! reject nothing. We keep the close view's values, rounded, at every
//! distance. Code 2 counts strip hits with P's own
//! flags (`isCenter`), which the text contradicts; we count Q's. A promoted
//! pixel with no centre-hit neighbour keeps its own conservative shading.
//! With `enabled: false` the centre layer is composited as is (SWR 1); with
//! `msaa` N the N sample layers of the raster's MSAA reference mode are
//! averaged, α = hits / N (SWR 2/4/8).

use super::payload::{EMPTY, Sample, from_words, unpack};
use super::rect::{FILTER_RECT_HI, FILTER_RECT_LO, Rect};
use super::shade::world_position;
use super::shaded;
use super::tiles::{self, MAX_FILTER_LANES, TILE};
use super::{add, frame, normalize, scale, transform};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, flag};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::kulikov::debug_resolve::{load_rgba16f, store_rgba16f};
use crate::layout::{FrameData, ModelData, read};
use crate::params::{Invalid, PassParams, in_range};

/// Lanes a workgroup on the GPU: 128, a tile at two lanes a pixel
/// ([`FilterParams::lanes`]). The CPU kernel filters a tile a workgroup.
pub use super::tiles::FILTER_GROUP;
pub const MAX_RADIUS: u32 = 8;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct FilterParams {
    pub enabled: bool,
    pub reconnect: bool,
    pub opacity_reconstruction: bool,
    pub radius: u32,
    pub s_parallel: f32,
    pub s_perp: f32,
    pub sigma_c: f32,
    pub strip_width: f32,
    pub depth_threshold: f32,
    /// MSAA reference resolve: average the N sample layers, α = hits / N
    /// (0: the single-sample filter above).
    pub msaa: u32,
    /// Pixels at least this opaque write their hair depth to `hair_depth`,
    /// which the next groom's rasterizer tests against (Lipp §3.5).
    pub depth_alpha: f32,
    /// Convert the hit ratio to the strands' own width (ours; see above).
    pub true_width: bool,
    /// Pixels; `lipp.raster`'s `centre_diameter`, the line width the hit
    /// ratio measures (a test in passes/src/lib.rs checks the graphs agree).
    pub centre_diameter: f32,
    /// The groom being filtered (set by the graph's per-model repeat).
    pub model_index: u32,
    /// Ours: a tap reads the neighbour's centre-layer record in `shaded`
    /// (8 bytes) rather than both G-buffer layers and then its colour
    /// ([`super::shaded`] says why). The output is the same.
    pub packed_taps: bool,
    /// Ours: the most lanes a pixel on the GPU (1, 2, 4, 8 or 16, and at
    /// most the subgroup's, for the shuffles), each taking
    /// every `lanes`-th row of the window, their sums added through subgroup
    /// shuffles. A far groom lists a few tiles, a workgroup or two an SM, and
    /// each lane's chain of taps then sets the pass's time. The filter takes
    /// as many as its dispatch holds ([`super::tiles::filter_lanes`]:
    /// `lipp.shade`'s `filter_lane_budget` sizes it), at least two. The sums
    /// are the same up to the order of the additions. 1: a lane a pixel, a
    /// workgroup of the same 128 lanes taking two tiles.
    pub lanes: u32,
    /// Ours: pixels; only the window's taps within `band` of the line
    /// through the pixel along its screen tangent are read (0: every tap,
    /// as published). Across the strand the spatial Gaussian has
    /// σ⊥ = radius · s_perp (0.5 px by default), so a tap 2.5 px off the
    /// line weighs at most e^-25 of one on it; the opacity strip
    /// (`strip_width`) lies inside the band. At least `strip_width`.
    pub band: f32,
}

impl Default for FilterParams {
    fn default() -> Self {
        Self {
            enabled: true,
            reconnect: true,
            opacity_reconstruction: true,
            radius: 5,
            s_parallel: 0.5,
            s_perp: 0.1,
            sigma_c: 0.9,
            strip_width: 0.5,
            depth_threshold: 0.05,
            msaa: 0,
            depth_alpha: 0.5,
            true_width: true,
            centre_diameter: 0.5,
            model_index: 0,
            packed_taps: true,
            lanes: MAX_FILTER_LANES,
            band: 2.5,
        }
    }
}

impl PassParams for FilterParams {
    fn validate(&self) -> Result<(), Invalid> {
        if !(self.lanes.is_power_of_two() && self.lanes <= MAX_FILTER_LANES) {
            return Err(Invalid::new(
                "lanes",
                format!("{} is not 1, 2, 4, 8 or 16", self.lanes),
            ));
        }
        if ![0, 1, 2, 4, 8].contains(&self.msaa) {
            return Err(Invalid::new(
                "msaa",
                format!("{} is not 0, 1, 2, 4 or 8", self.msaa),
            ));
        }
        in_range("radius", self.radius, 1..=MAX_RADIUS)?;
        if !(self.centre_diameter > 0.0 && self.centre_diameter < 1.0) {
            return Err(Invalid::new(
                "centre_diameter",
                format!("{} is not in (0, 1) pixels", self.centre_diameter),
            ));
        }
        for (name, v) in [
            ("s_parallel", self.s_parallel),
            ("s_perp", self.s_perp),
            ("sigma_c", self.sigma_c),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Invalid::new(name, format!("{v} must be positive")));
            }
        }
        if !(self.band == 0.0 || (self.band.is_finite() && self.band >= self.strip_width)) {
            return Err(Invalid::new(
                "band",
                format!(
                    "{} is neither 0 (off) nor at least strip_width ({})",
                    self.band, self.strip_width
                ),
            ));
        }
        Ok(())
    }
}

crate::gpu_block! {
    /// `FilterParams` in shaders/lipp/filter.wgsl.
    pub struct FilterGpu {
        enabled: u32,
        reconnect: u32,
        opacity_reconstruction: u32,
        radius: u32,
        s_parallel: f32,
        s_perp: f32,
        sigma_c: f32,
        strip_width: f32,
        depth_threshold: f32,
        /// Scene quantities.
        width: u32,
        height: u32,
        msaa: u32,
        depth_alpha: f32,
        true_width: u32,
        centre_diameter: f32,
        model_index: u32,
        packed_taps: u32,
        band: f32,
        lanes: u32,
        _pad: u32,
    }
}

pub static FILTER: PassKind<FilterParams, FilterGpu> = PassKind {
    kind: "lipp.filter",
    summary: "reconnection and opacity reconstruction filter over centre and conservative layers",
    source: "Lipp §3.3, Appendix B Code 2",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("gbuffer"),
        Binding::read("shaded"),
        Binding::write("output"),
        Binding::write("hair_depth"),
        Binding::read("models"),
        Binding::read("filter_tiles"),
        // The dispatch (words 0-3) and the shaded rectangle (rect.rs).
        Binding::read("filter_args").at_least(super::rect::FILTER_RECT_HI as u32 + 1),
    ]),
    workgroup_size: FILTER_GROUP,
    // A workgroup per tile lipp.shade listed (super::tiles).
    dispatch: Dispatch::Indirect {
        binding: "filter_args",
        word: 0,
    },
    shader: Shader::compute("lipp/filter.wgsl", "filter_pixels"),
    kernel: |p| Box::new(FilterKernel(*p)),
    gpu: |p, q| FilterGpu {
        enabled: flag(p.enabled),
        reconnect: flag(p.reconnect),
        opacity_reconstruction: flag(p.opacity_reconstruction),
        radius: p.radius,
        s_parallel: p.s_parallel,
        s_perp: p.s_perp,
        sigma_c: p.sigma_c,
        strip_width: p.strip_width,
        depth_threshold: p.depth_threshold,
        width: q.width,
        height: q.height,
        msaa: p.msaa,
        depth_alpha: p.depth_alpha,
        true_width: flag(p.true_width),
        centre_diameter: p.centre_diameter,
        model_index: p.model_index,
        packed_taps: flag(p.packed_taps),
        band: p.band,
        lanes: p.lanes,
        _pad: 0,
    },
    raster: None,
};

/// The taps `dx` of window row `dy` within `band` pixels of the line along
/// unit screen tangent `tp` (`FilterParams::band`; 0: the whole row): the
/// distance of (dx, dy) from it is |dx · ty − dy · tx|.
pub fn band_span(band: f32, dy: f32, tp: [f32; 2], r: i32) -> (i32, i32) {
    let c = dy * tp[0];
    if band == 0.0 {
        return (-r, r);
    }
    if tp[1].abs() < 1e-6 {
        return if c.abs() <= band { (-r, r) } else { (1, 0) };
    }
    let (a, b) = ((c - band) / tp[1], (c + band) / tp[1]);
    let lo = (a.min(b).ceil() as i32).max(-r);
    let hi = (a.max(b).floor() as i32).min(r);
    (lo, hi)
}

/// Linear view depth of NDC depth `z` (glam's `perspective_rh`, z in [0, 1]).
pub fn linear_depth(f: &FrameData, z: f32) -> f32 {
    f.near * f.far / (f.far - z * (f.far - f.near))
}

/// NDC depth at linear depth `d` > 0: [`linear_depth`]'s inverse,
/// increasing in `d`, so a window of linear depths is a window of NDC depths.
pub fn ndc_depth(f: &FrameData, d: f32) -> f32 {
    f.far * (d - f.near) / (d * (f.far - f.near))
}

/// The screen-space direction of world tangent `t` at pixel (x, y), depth z.
pub fn screen_tangent(f: &FrameData, x: u32, y: u32, s: &Sample) -> [f32; 2] {
    let p = world_position(f, x, y, s.depth);
    let d = linear_depth(f, s.depth);
    let q = add(p, scale(s.tangent, 0.01 * d));
    let a = transform(&f.view_proj, [p[0], p[1], p[2], 1.0]);
    let b = transform(&f.view_proj, [q[0], q[1], q[2], 1.0]);
    if a[3] <= 0.0 || b[3] <= 0.0 {
        return [1.0, 0.0];
    }
    // y down in pixels.
    let dx = b[0] / b[3] - a[0] / a[3];
    let dy = -(b[1] / b[3] - a[1] / a[3]);
    let (dx, dy) = (dx * f.screen[0], dy * f.screen[1]);
    let n = normalize([dx, dy, 0.0]);
    if n[0] == 0.0 && n[1] == 0.0 {
        [1.0, 0.0]
    } else {
        [n[0], n[1]]
    }
}

/// The two layers and shaded colours of every pixel, read through words.
pub struct View<'a> {
    pub f: &'a FrameData,
    /// G-buffer layers ([`super::gbuffer_layers`]).
    pub layers: u32,
    pub width: u32,
    pub height: u32,
    pub gbuffer: Words<'a>,
    pub shaded: Words<'a>,
    /// The groom's strand thickness, metres.
    pub thickness: f32,
    /// The pixels `lipp.shade` wrote records for ([`shaded_rect`]).
    pub rect: Rect,
}

impl View<'_> {
    pub fn payload(&self, layer: u32, i: u32) -> u64 {
        let slot = (layer * self.width * self.height + i) as usize;
        from_words(self.gbuffer.load(2 * slot), self.gbuffer.load(2 * slot + 1))
    }
    /// A layer's shaded colour ([`shaded`]'s record, word 0).
    pub fn color(&self, layer: u32, i: u32) -> [f32; 3] {
        let slot = (layer * self.width * self.height + i) as usize;
        shaded::unpack_rgb9e5(self.shaded.load(2 * slot))
    }
    /// Pixel i's flags ([`shaded::pixel_flags`]), from its centre record.
    pub fn flags(&self, i: u32) -> u32 {
        self.shaded.load(2 * i as usize + 1) & 0xFF
    }
    /// What a tap needs of neighbour `q`: the centre layer's record, whose
    /// colour word is read only once the tap passes its tests. With
    /// `packed_taps` off, its flags and depth come from both G-buffer
    /// layers, as before the records held them (the same bits).
    fn tap(&self, q: u32, packed_taps: bool) -> [u32; 2] {
        if packed_taps {
            return [
                self.shaded.load(2 * q as usize),
                self.shaded.load(2 * q as usize + 1),
            ];
        }
        let (g, a) = (self.payload(0, q), self.payload(1, q));
        let flag = |p: u64, f: u32| if p == EMPTY { 0 } else { f };
        let depth = (g >> 32) as u32 & !0xFF;
        [0, depth | flag(g, shaded::HIT) | flag(a, shaded::CONS_HIT)]
    }
}

/// The sample a pixel is filtered around.
#[derive(Debug, Clone, Copy)]
pub struct Reference {
    /// NDC depth.
    pub z: f32,
    /// Screen tangent.
    pub tp: [f32; 2],
    /// The pixel's own shaded colour.
    pub cp: [f32; 3],
    /// A conservative-only pixel borrowing colour (w_color = 1).
    pub promoted: bool,
}

impl Reference {
    fn of(v: &View<'_>, x: u32, y: u32, s: &Sample, cp: [f32; 3], promoted: bool) -> Self {
        Self {
            z: s.depth,
            tp: screen_tangent(v.f, x, y, s),
            cp,
            promoted,
        }
    }
}

/// The filtered colour and alpha of pixel (x, y) around a reference sample.
pub fn reconstruct(
    p: &FilterParams,
    v: &View<'_>,
    x: u32,
    y: u32,
    re: &Reference,
) -> ([f32; 3], f32) {
    let (z_ref, tp, cp, promoted) = (re.z, re.tp, re.cp, re.promoted);
    let r = p.radius as i32;
    let sp = p.radius as f32 * p.s_parallel;
    let sq = p.radius as f32 * p.s_perp;
    // Per pixel, so that a tap divides by nothing and takes one exp: the
    // Gaussians' denominators as factors, the strip test on squares, the
    // depth window as NDC bounds (the payload's own depth).
    let (k_par, k_perp) = (1.0 / (sp * sp), 1.0 / (sq * sq));
    let k_c = if promoted {
        0.0
    } else {
        1.0 / (p.sigma_c * p.sigma_c)
    };
    let strip2 = p.strip_width * p.strip_width;
    let (mut sum, mut wsum) = ([0.0f32; 3], 0.0f32);
    let (mut hc, mut hcons) = (0.0f32, 0.0f32);
    let d_ref = linear_depth(v.f, z_ref);
    // Within the threshold of the camera, every nearer depth is in the window.
    let near = d_ref - p.depth_threshold;
    let z_near = if near > 0.0 {
        ndc_depth(v.f, near)
    } else {
        f32::MIN
    };
    let z_far = ndc_depth(v.f, d_ref + p.depth_threshold);
    for dy in -r..=r {
        let (lo, hi) = band_span(p.band, dy as f32, tp, r);
        for dx in lo..=hi {
            let (qx, qy) = (x as i32 + dx, y as i32 + dy);
            let r = &v.rect;
            if qx < r.x0 as i32 || qy < r.y0 as i32 || qx >= r.x1 as i32 || qy >= r.y1 as i32 {
                continue;
            }
            let q = qy as u32 * v.width + qx as u32;
            let (fx, fy) = (dx as f32, dy as f32);
            let dpar = fx * tp[0] + fy * tp[1];
            let (ox, oy) = (fx - dpar * tp[0], fy - dpar * tp[1]);
            let perp2 = ox * ox + oy * oy;
            let t = v.tap(q, p.packed_taps);
            let hit = t[1] & shaded::HIT != 0;
            if perp2 <= strip2 {
                if hit {
                    hc += 1.0;
                } else if t[1] & shaded::CONS_HIT != 0 {
                    hcons += 1.0;
                }
            }
            if !hit {
                continue;
            }
            let zq = shaded::depth(t[1]);
            if zq < z_near || zq > z_far {
                continue;
            }
            let cq = if p.packed_taps {
                shaded::unpack_rgb9e5(t[0])
            } else {
                v.color(0, q)
            };
            let dc2 = (0..3)
                .map(|k| (cp[k] - cq[k]) * (cp[k] - cq[k]))
                .sum::<f32>();
            let w = (-(dpar * dpar) * k_par - perp2 * k_perp - dc2 * k_c).exp();
            for k in 0..3 {
                sum[k] += cq[k] * w;
            }
            wsum += w;
        }
    }
    let c = if wsum > 0.0 {
        [sum[0] / wsum, sum[1] / wsum, sum[2] / wsum]
    } else {
        cp
    };
    let alpha = if !p.opacity_reconstruction || hc + hcons == 0.0 {
        1.0
    } else if p.true_width {
        let width = v.thickness * v.f.pixels_per_unit / d_ref;
        true_width_alpha(hc / (hc + hcons), p.centre_diameter, width)
    } else {
        hc / (hc + hcons)
    };
    (c, alpha)
}

/// The coverage of strands `width` pixels wide where lines `line` pixels
/// wide cover `f` of the pixels (`true_width` in the module comment).
pub fn true_width_alpha(f: f32, line: f32, width: f32) -> f32 {
    if f >= 1.0 {
        return 1.0;
    }
    let k = (1.0 - width.clamp(0.0, 0.99)).ln() / (1.0 - line).ln();
    1.0 - (1.0 - f).powf(k)
}

/// What the filter puts over one pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hair {
    pub color: [f32; 3],
    pub alpha: f32,
    /// NDC depth of the nearest sample the colour came from.
    pub depth: f32,
}

impl Hair {
    /// This colour blended over `scene`, alpha included (`output`'s alpha
    /// is the hair's coverage).
    pub fn over(&self, scene: [f32; 4]) -> [f32; 4] {
        let a = self.alpha;
        let c = self.color;
        [
            c[0] * a + scene[0] * (1.0 - a),
            c[1] * a + scene[1] * (1.0 - a),
            c[2] * a + scene[2] * (1.0 - a),
            a + scene[3] * (1.0 - a),
        ]
    }
}

/// The hair over pixel (x, y), or `None` where no strand is.
pub fn filter_pixel(p: &FilterParams, v: &View<'_>, x: u32, y: u32) -> Option<Hair> {
    let i = y * v.width + x;
    let (g, a) = (v.payload(0, i), v.payload(1, i));
    let (centre, cons) = (g != EMPTY, a != EMPTY);
    let hair = |color: [f32; 3], alpha: f32, depth: f32| {
        Some(Hair {
            color,
            alpha,
            depth,
        })
    };
    if p.msaa > 1 {
        // MSAA reference resolve (Lipp Fig. 5, "MSAA 8").
        let (mut sum, mut hits, mut depth) = ([0.0f32; 3], 0u32, 1.0f32);
        for s in 0..p.msaa.min(v.layers) {
            let q = v.payload(s, i);
            if q != EMPTY {
                let c = v.color(s, i);
                for k in 0..3 {
                    sum[k] += c[k];
                }
                hits += 1;
                depth = depth.min(unpack(q).depth);
            }
        }
        if hits == 0 {
            return None;
        }
        let n = hits as f32;
        return hair(
            [sum[0] / n, sum[1] / n, sum[2] / n],
            n / p.msaa as f32,
            depth,
        );
    }
    if !p.enabled {
        if !centre {
            return None;
        }
        return hair(v.color(0, i), 1.0, unpack(g).depth);
    }
    if !(centre || cons && p.reconnect) {
        return None;
    }
    if centre {
        let sg = unpack(g);
        let cp = v.color(0, i);
        let (c, alpha) = reconstruct(p, v, x, y, &Reference::of(v, x, y, &sg, cp, false));
        // lipp.shade's decision (shaded::pixel_flags), which told it to
        // shade the conservative sample.
        let front = p.reconnect && v.flags(i) & shaded::FRONT != 0;
        if front {
            // A flyaway in front of the centre hit: its reconstruction over
            // the centre colour, opacity 1 (§3.3.3).
            let sa = unpack(a);
            let ca = v.color(1, i);
            let (f, fa) = reconstruct(p, v, x, y, &Reference::of(v, x, y, &sa, ca, true));
            if !p.true_width {
                let mixed = [0, 1, 2].map(|k| f[k] * fa + c[k] * (1.0 - fa));
                return hair(mixed, 1.0, sa.depth);
            }
            // Both strands with their own opacity: the flyaway over the centre.
            let a = fa + alpha * (1.0 - fa);
            let mixed = [0, 1, 2].map(|k| (f[k] * fa + c[k] * alpha * (1.0 - fa)) / a);
            return hair(mixed, a, sa.depth);
        }
        return hair(c, alpha, sg.depth);
    }
    // Promoted conservative-only pixel (§3.3.2).
    let sa = unpack(a);
    let ca = v.color(1, i);
    let (c, alpha) = reconstruct(p, v, x, y, &Reference::of(v, x, y, &sa, ca, true));
    hair(c, alpha, sa.depth)
}

/// The pixels `lipp.shade` wrote records for this frame (`filter_args`
/// words [`FILTER_RECT_LO`], [`FILTER_RECT_HI`], which the binding's
/// declared size guarantees): outside, a tap reads no hair ([`super::rect`]).
pub fn shaded_rect(args: &Words<'_>) -> Rect {
    Rect::from_args(args.load(FILTER_RECT_LO), args.load(FILTER_RECT_HI))
}

struct FilterKernel(FilterParams);

impl CpuKernel for FilterKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let f = frame(ctx);
        let (w, h) = (ctx.quantities.width, ctx.quantities.height);
        let (gbuffer, shaded) = (ctx.words("gbuffer"), ctx.words("shaded"));
        let (tiles, args) = (ctx.words("filter_tiles"), ctx.words("filter_args"));
        let v = View {
            f: &f,
            layers: super::gbuffer_layers(&gbuffer, &shaded, w * h),
            width: w,
            height: h,
            gbuffer,
            shaded,
            thickness: read::<ModelData>(&ctx.words("models"), self.0.model_index as usize)
                .thickness,
            rect: shaded_rect(&args),
        };
        let (out, depth) = (ctx.words("output"), ctx.words("hair_depth"));
        let count = tiles::listed(&args, &tiles);
        let mut t = group;
        while t < count {
            let first = tiles.load(t as usize) * TILE;
            for i in first..(first + TILE).min(w * h) {
                let Some(hair) = filter_pixel(&self.0, &v, i % w, i / w) else {
                    continue;
                };
                let i = i as usize;
                store_rgba16f(&out, i, hair.over(load_rgba16f(&out, i)));
                // Lipp §3.5: the depth later grooms are tested against.
                if hair.alpha >= self.0.depth_alpha {
                    depth.store_f32(i, depth.load_f32(i).min(hair.depth));
                }
            }
            t += ctx.workgroups.max(1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

    #[test]
    fn params_are_checked() {
        assert!(FILTER.params(&ron::Value::Unit).is_ok());
        let v: ron::Value = ron::from_str(r#"{"radius": 0}"#).unwrap();
        assert!(FILTER.params(&v).is_err());
        let v: ron::Value = ron::from_str(r#"{"sigma_c": 0.0}"#).unwrap();
        assert!(FILTER.params(&v).is_err());
        let v: ron::Value = ron::from_str(r#"{"centre_diameter": 1.0}"#).unwrap();
        assert!(FILTER.params(&v).is_err());
        // The band must hold the opacity strip.
        let v: ron::Value = ron::from_str(r#"{"band": 0.25}"#).unwrap();
        assert!(FILTER.params(&v).is_err());
    }

    #[test]
    fn a_band_row_holds_exactly_the_taps_near_the_line() {
        let r = 5;
        for k in 0..720 {
            let a = k as f32 * std::f32::consts::PI / 360.0;
            let tp = [a.cos(), a.sin()];
            for band in [0.5, 1.0, 2.5, 4.0] {
                for dy in -r..=r {
                    let (lo, hi) = band_span(band, dy as f32, tp, r);
                    for dx in -r..=r {
                        let d = (dx as f32 * tp[1] - dy as f32 * tp[0]).abs();
                        // Taps on the band's edge may go either way.
                        if (d - band).abs() > 1e-4 {
                            assert_eq!(
                                lo <= dx && dx <= hi,
                                d < band,
                                "{tp:?} band {band} ({dx}, {dy})"
                            );
                        }
                    }
                }
            }
        }
        assert_eq!(band_span(0.0, 3.0, [0.6, 0.8], r), (-r, r));
    }

    #[test]
    fn the_band_leaves_opacity_as_it_was_and_colour_within_a_rounding() {
        let (mut g, mut sh) = (Vec::new(), Vec::new());
        let (f, w, h) = scene(&mut g, &mut sh);
        let oob = AtomicU64::new(0);
        let v = test_view(&f, &g, &sh, &oob);
        // Largest colour difference and pixels changed, band against none.
        let compare = |band: FilterParams| {
            let whole = FilterParams { band: 0.0, ..band };
            let (mut worst, mut differ) = (0.0f32, 0);
            for (x, y) in (0..h).flat_map(|y| (0..w).map(move |x| (x, y))) {
                let (a, b) = (
                    filter_pixel(&band, &v, x, y),
                    filter_pixel(&whole, &v, x, y),
                );
                assert_eq!(a.is_some(), b.is_some());
                let (Some(a), Some(b)) = (a, b) else { continue };
                assert_eq!(a.alpha, b.alpha, "pixel ({x}, {y})");
                for k in 0..3 {
                    worst = worst.max((a.color[k] - b.color[k]).abs());
                }
                differ += usize::from(a.color != b.color);
            }
            (worst, differ)
        };
        // Taps off the band weigh e^-25 or less of the pixel's own.
        let (worst, _) = compare(FilterParams::default());
        assert!(worst < 1e-5, "{worst}");
        // Across a wider Gaussian they would count: the band does leave
        // them out.
        let (_, differ) = compare(FilterParams {
            s_perp: 0.5,
            ..FilterParams::default()
        });
        assert!(differ > 0, "the band read every tap");
    }

    /// A 96×64 frame of random samples in a 20 cm depth range (a quarter
    /// of centre pixels and half of conservative ones empty), shaded with
    /// colours from their hash, as lipp.shade would leave the records.
    fn scene(gbuffer: &mut Vec<AtomicU32>, records: &mut Vec<AtomicU32>) -> (FrameData, u32, u32) {
        use super::super::payload::pack;
        use super::super::raster::tests::frame;
        let mut f = frame();
        let (w, h) = (f.screen[0] as u32, f.screen[1] as u32);
        // The frame's fov is 0.8 rad.
        f.pixels_per_unit = h as f32 / (2.0 * 0.4f32.tan());
        let n = (w * h) as usize;
        let sample = |k: u32| {
            let u = |j: u32| super::super::unit(super::super::pcg(k * 7 + j));
            (
                u(0) < [0.25, 0.5][(k as usize) / n],
                Sample {
                    depth: ndc_depth(&f, 0.5 + 0.2 * u(1)),
                    tangent: normalize([u(2) - 0.5, u(3) - 0.5, u(4) - 0.5]),
                    uvw: [u(5), u(6), u(7)],
                    ao: u(8),
                },
            )
        };
        let words: Vec<u64> = (0..2 * n as u32)
            .map(|k| match sample(k) {
                (true, _) => EMPTY,
                (false, s) => pack(&s),
            })
            .collect();
        *gbuffer = words
            .iter()
            .flat_map(|&p| [p as u32, (p >> 32) as u32])
            .map(AtomicU32::new)
            .collect();
        *records = (0..4 * n).map(|_| AtomicU32::new(0)).collect();
        let out = |slot: usize, r: [u32; 2]| {
            records[2 * slot].store(r[0], Relaxed);
            records[2 * slot + 1].store(r[1], Relaxed);
        };
        for i in 0..n {
            let flags = shaded::pixel_flags(&f, words[i], words[n + i], 0.01);
            for layer in 0..2 {
                let p = words[layer * n + i];
                let c = [0, 1, 2]
                    .map(|j| super::super::unit(super::super::pcg((layer * n + i) as u32 * 3 + j)));
                match p {
                    EMPTY if layer == 0 => out(i, shaded::record([0.0; 3], 0, flags)),
                    EMPTY => {}
                    _ => out(
                        layer * n + i,
                        shaded::record(c, (p >> 32) as u32, shaded::HIT | flags),
                    ),
                }
            }
        }
        (f, w, h)
    }

    /// [`scene`]'s two layers and records over the whole screen.
    fn test_view<'a>(
        f: &'a FrameData,
        g: &'a [AtomicU32],
        sh: &'a [AtomicU32],
        oob: &'a AtomicU64,
    ) -> View<'a> {
        let (w, h) = (f.screen[0] as u32, f.screen[1] as u32);
        View {
            f,
            layers: 2,
            width: w,
            height: h,
            gbuffer: Words::new(g, oob),
            shaded: Words::new(sh, oob),
            thickness: 7e-5,
            rect: Rect::full(w, h),
        }
    }

    #[test]
    fn packed_taps_filter_the_same_as_taps_from_the_gbuffer() {
        let (mut g, mut sh) = (Vec::new(), Vec::new());
        let (f, w, h) = scene(&mut g, &mut sh);
        let oob = AtomicU64::new(0);
        let v = test_view(&f, &g, &sh, &oob);
        let on = FilterParams::default();
        let off = FilterParams {
            packed_taps: false,
            ..on
        };
        let mut filtered = 0;
        for (x, y) in (0..h).flat_map(|y| (0..w).map(move |x| (x, y))) {
            let a = filter_pixel(&on, &v, x, y);
            assert_eq!(a, filter_pixel(&off, &v, x, y), "pixel ({x}, {y})");
            filtered += usize::from(a.is_some_and(|a| a.alpha < 1.0));
        }
        assert_eq!(oob.load(Relaxed), 0);
        // The window did something: many pixels got a partial opacity.
        assert!(filtered > (w * h / 10) as usize, "{filtered}");
    }

    /// lipp.shade writes no records outside the groom's rectangle: there the
    /// filter must read no hair, whatever the records hold.
    #[test]
    fn taps_outside_the_shaded_rectangle_read_no_hair() {
        let (mut g, mut sh) = (Vec::new(), Vec::new());
        let (f, w, h) = scene(&mut g, &mut sh);
        // Hair only in the middle of the screen, as the shade leaves it.
        let hair = Rect {
            x0: w / 4,
            y0: h / 4,
            x1: 3 * w / 4,
            y1: 3 * h / 4,
        };
        let n = (w * h) as usize;
        let empty = shaded::record([0.0; 3], 0, 0);
        for i in (0..n).filter(|&i| !hair.contains(i as u32 % w, i as u32 / w)) {
            for slot in [i, n + i] {
                g[2 * slot].store(EMPTY as u32, Relaxed);
                g[2 * slot + 1].store((EMPTY >> 32) as u32, Relaxed);
            }
            sh[2 * i].store(empty[0], Relaxed);
            sh[2 * i + 1].store(empty[1], Relaxed);
        }
        let oob = AtomicU64::new(0);
        let full = test_view(&f, &g, &sh, &oob);
        let expect: Vec<Option<Hair>> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| filter_pixel(&FilterParams::default(), &full, x, y))
            .collect();
        // Stale records outside: a near, lit hit everywhere.
        let stale: Vec<AtomicU32> = (0..sh.len())
            .map(|k| {
                let (slot, word) = ((k / 2) as u32, k % 2);
                let (x, y) = ((slot % (w * h)) % w, (slot % (w * h)) / w);
                if hair.contains(x, y) {
                    AtomicU32::new(sh[k].load(Relaxed))
                } else if word == 0 {
                    AtomicU32::new(shaded::pack_rgb9e5([5.0, 0.0, 0.0]))
                } else {
                    AtomicU32::new(shaded::HIT | shaded::CONS_HIT | 0x100)
                }
            })
            .collect();
        let clipped = View {
            shaded: Words::new(&stale, &oob),
            rect: hair,
            ..full
        };
        for (x, y) in (0..h).flat_map(|y| (0..w).map(move |x| (x, y))) {
            let got = filter_pixel(&FilterParams::default(), &clipped, x, y);
            assert_eq!(got, expect[(y * w + x) as usize], "pixel ({x}, {y})");
        }
        assert_eq!(oob.load(Relaxed), 0);
    }

    /// With `lipp.shade`'s `read_layers_only`, a conservative record the
    /// shade skips holds last frame's words: the filter must not read it,
    /// and must read the flyaways' (the scene has both).
    #[test]
    fn the_filter_reads_no_conservative_record_the_shade_skips() {
        let (mut g, mut sh) = (Vec::new(), Vec::new());
        let (f, w, h) = scene(&mut g, &mut sh);
        let n = (w * h) as usize;
        // A lone flyaway 10 cm in front of its pixel's strand, nothing else
        // within the window: its reconstruction has no neighbour within the
        // depth threshold and keeps its own (conservative) colour.
        let (cx, cy) = (w / 2, h / 2);
        for (x, y) in (cy - 6..=cy + 6).flat_map(|y| (cx - 6..=cx + 6).map(move |x| (x, y))) {
            let i = (y * w + x) as usize;
            for (slot, word) in [(i, 0), (i, 1), (n + i, 0), (n + i, 1)] {
                g[2 * slot + word].store(u32::MAX, Relaxed);
            }
            let empty = shaded::record([0.0; 3], 0, 0);
            sh[2 * i].store(empty[0], Relaxed);
            sh[2 * i + 1].store(empty[1], Relaxed);
        }
        let i = (cy * w + cx) as usize;
        let at = |metres| shaded::tests::payload_at(&f, metres);
        let (centre, cons) = (at(0.7), at(0.6));
        let flags = shaded::pixel_flags(&f, centre, cons, 0.01);
        for (slot, p, c) in [
            (i, centre, [0.2, 0.1, 0.05]),
            (n + i, cons, [0.4, 0.3, 0.2]),
        ] {
            g[2 * slot].store(p as u32, Relaxed);
            g[2 * slot + 1].store((p >> 32) as u32, Relaxed);
            let r = shaded::record(c, (p >> 32) as u32, shaded::HIT | flags);
            sh[2 * slot].store(r[0], Relaxed);
            sh[2 * slot + 1].store(r[1], Relaxed);
        }
        let oob = AtomicU64::new(0);
        let filtered = |sh: &[AtomicU32]| -> Vec<Option<Hair>> {
            let v = test_view(&f, &g, sh, &oob);
            (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| filter_pixel(&FilterParams::default(), &v, x, y))
                .collect()
        };
        let expect = filtered(&sh);
        let stale = shaded::record([50.0, 0.0, 0.0], 0, shaded::HIT | shaded::CONS_HIT);
        let (mut skipped, mut fronts) = (0, 0);
        for i in 0..n {
            let word1 = sh[2 * i + 1].load(Relaxed);
            let (hit, flags) = (word1 & shaded::HIT != 0, word1 & 0xFF);
            fronts += usize::from(flags & shaded::FRONT != 0);
            if flags & shaded::CONS_HIT != 0 && !shaded::read_by_filter(1, 2, hit, flags) {
                sh[2 * (n + i)].store(stale[0], Relaxed);
                sh[2 * (n + i) + 1].store(stale[1], Relaxed);
                skipped += 1;
            }
        }
        assert!(
            skipped > n / 10 && fronts > n / 20,
            "{skipped} skipped, {fronts} in front"
        );
        let got = filtered(&sh);
        for (k, (a, b)) in got.iter().zip(&expect).enumerate() {
            assert_eq!(a, b, "pixel ({}, {})", k as u32 % w, k as u32 / w);
        }
        assert_eq!(oob.load(Relaxed), 0);
    }

    #[test]
    fn true_width_keeps_dense_hair_opaque_and_thins_one_strand() {
        // Dense: every strip pixel a centre hit.
        assert_eq!(true_width_alpha(1.0, 0.5, 0.03), 1.0);
        // Strands as wide as the line: the paper's estimate unchanged.
        assert!((true_width_alpha(0.3, 0.5, 0.5) - 0.3).abs() < 1e-6);
        // One isolated strand (f small): its coverage scales with its width.
        let a = true_width_alpha(0.1, 0.5, 0.05);
        let linear = 0.1 * (0.95f32.ln() / 0.5f32.ln());
        assert!((a - linear).abs() < 0.1 * linear, "{a} vs {linear}");
        // N lines of width d cover 1 − (1 − d)^N; strands of width w, 1 − (1 − w)^N.
        let n = 3;
        let f = 1.0 - 0.5f32.powi(n);
        let want = 1.0 - 0.85f32.powi(n);
        assert!((true_width_alpha(f, 0.5, 0.15) - want).abs() < 1e-5);
        // Monotonic in the hit ratio.
        let steps: Vec<f32> = (0..=10)
            .map(|i| true_width_alpha(i as f32 / 10.0, 0.5, 0.1))
            .collect();
        assert!(steps.windows(2).all(|w| w[0] < w[1]), "{steps:?}");
    }
}
