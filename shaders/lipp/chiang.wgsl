// Chiang et al. 2016 single scattering (R, TT, TRT), the compact form
// lipp.shade evaluates per pixel: pbrt-v4's HairBxDF averaged over the fibre
// offset h. Port of passes/src/lipp/chiang.rs, operation for operation (the
// model, its sources and its measured error against pbrt are documented
// there). Composed with naga_oil:
//   #import strandgraph::chiang::{chiang, fibre_paths, FibrePaths}
#define_import_path strandgraph::chiang

#import strandgraph::lipp::{PI, safe_normalize}

const ETA: f32 = 1.55;

// chiang::tilt: sin, cos of the cuticle tilt of θ_o (R −2α, TT α, TRT 4α)
// and v_p / v_0.
fn tilt(alpha: f32) -> array<vec3<f32>, 3> {
    return array<vec3<f32>, 3>(
        vec3<f32>(sin(-2.0 * alpha), cos(-2.0 * alpha), 1.0),
        vec3<f32>(sin(alpha), cos(alpha), 0.25),
        vec3<f32>(sin(4.0 * alpha), cos(4.0 * alpha), 4.0),
    );
}

// chiang::H_NODES: (h, γ, cos γ).
const NODES: u32 = 5u;
const H_NODES: array<vec3<f32>, 5> = array<vec3<f32>, 5>(
    vec3<f32>(0.000000, 0.000000, 1.000000),
    vec3<f32>(0.495291, 0.518170, 0.868727),
    vec3<f32>(0.784684, 0.902186, 0.619896),
    vec3<f32>(0.948310, 1.247869, 0.317344),
    vec3<f32>(1.000000, 1.570796, 0.000000),
);

// chiang::PIECES.
const PIECES: array<vec2<f32>, 4> = array<vec2<f32>, 4>(
    vec2<f32>(0.253339, 0.241951),
    vec2<f32>(0.152679, 0.136714),
    vec2<f32>(0.090546, 0.073080),
    vec2<f32>(0.034400, 0.017290),
);

// chiang::sigma_a (Chiang 2016 Eq. 9 inverted).
fn sigma_a(color: vec3<f32>, b: f32) -> vec3<f32> {
    let d = 5.969 - 0.215 * b + 2.532 * b * b - 10.73 * pow(b, 3.0) + 5.574 * pow(b, 4.0)
        + 0.245 * pow(b, 5.0);
    let l = log(clamp(color, vec3<f32>(1e-4), vec3<f32>(1.0))) / d;
    return l * l;
}

fn logistic(x: f32, s: f32) -> f32 {
    let e = exp(-abs(x) / s);
    return e / (s * (1.0 + e) * (1.0 + e));
}

fn logistic_cdf(x: f32, s: f32) -> f32 {
    return 1.0 / (1.0 + exp(-x / s));
}

// chiang::fresnel (pbrt-v4 FrDielectric, from outside).
fn fresnel(cos_i: f32) -> f32 {
    let sin2_t = (1.0 - cos_i * cos_i) / (ETA * ETA);
    let cos_t = sqrt(max(1.0 - sin2_t, 0.0));
    let r_parl = (ETA * cos_i - cos_t) / (ETA * cos_i + cos_t);
    let r_perp = (cos_i - ETA * cos_t) / (cos_i + ETA * cos_t);
    return 0.5 * (r_parl * r_parl + r_perp * r_perp);
}

// chiang::log_i0 (Abramowitz and Stegun 9.8.1, 9.8.2).
fn log_i0(x: f32) -> f32 {
    if x < 3.75 {
        let t = (x / 3.75) * (x / 3.75);
        return log(1.0 + t * (3.5156229 + t * (3.0899424 + t * (1.2067492 + t * (0.2659732
            + t * (0.0360768 + t * 0.0045813))))));
    }
    let t = 3.75 / x;
    let p = 0.3989423 + t * (0.01328592 + t * (0.00225319 + t * (-0.00157565 + t * (0.00916281
        + t * (-0.02057706 + t * (0.02635537 + t * (-0.01647633 + t * 0.00392377)))))));
    return x - 0.5 * log(x) + log(p);
}

// chiang::mp (d'Eon et al. 2011's M_p in log form).
fn mp(cos_i: f32, cos_o: f32, sin_i: f32, sin_o: f32, v: f32) -> f32 {
    let a = cos_i * cos_o / v;
    let b = sin_i * sin_o / v;
    return exp(log_i0(a) - b - 1.0 / v - log(v) - log(1.0 - exp(-2.0 / v)));
}

// chiang::n_r (d'Eon 2011's far-field N_R times A_R).
fn n_r(phi: f32, cos_o: f32) -> f32 {
    let c = abs(cos(0.5 * phi));
    return 0.25 * c * fresnel(cos_o * c);
}

// chiang::Offset: the light path at one offset of H_NODES.
struct Offset {
    f: f32,
    tr: vec3<f32>,
    sin_gt: f32,
}

// The view's modified index η' and cos θ_t (pbrt-v4 HairBxDF::f), once per
// view for offset_at.
fn refraction(sin_o: f32, cos_o: f32) -> vec2<f32> {
    let sin_t = sin_o / ETA;
    return vec2<f32>(sqrt(ETA * ETA - sin_o * sin_o) / max(cos_o, 1e-4), sqrt(max(1.0 - sin_t * sin_t, 1e-4)));
}

// chiang::offsets, one node j at a time; rc = refraction(sin θ_o, cos θ_o).
fn offset_at(j: u32, cos_o: f32, rc: vec2<f32>, sa: vec3<f32>) -> Offset {
    var nodes = H_NODES;
    let node = nodes[j];
    let sin_gt = node.x / rc.x;
    let cos_gt = sqrt(max(1.0 - sin_gt * sin_gt, 0.0));
    return Offset(fresnel(cos_o * node.z), exp(-2.0 * sa * cos_gt / rc.y), sin_gt);
}

// chiang::R_ALBEDO_FIT: R's directional albedo, a polynomial in cos θ_o
// fitted to its 4-point Gauss-Legendre rule in γ (attenuation.rs).
const R_ALBEDO_FIT: array<f32, 8> = array<f32, 8>(
    0.998711, -4.4404744, 11.730038, -21.808463, 28.510157, -24.327722, 11.955967, -2.5427854,
);

// chiang::r_albedo, by Horner's rule with constant indices.
fn r_albedo(cos_o: f32) -> f32 {
    let c = R_ALBEDO_FIT;
    return c[0] + cos_o * (c[1] + cos_o * (c[2] + cos_o * (c[3] + cos_o * (c[4] + cos_o * (c[5] + cos_o * (c[6]
        + cos_o * c[7]))))));
}

// chiang::FibrePaths: A_p and Φ_p − pπ of TT and TRT at each node (TT
// then TRT), and R's (x) and TRT's (yzw) directional albedo: what the lobes
// need of the view, once per shaded point for every light and the probe.
struct FibrePaths {
    ap: array<array<vec3<f32>, 5>, 2>,
    dphi: array<array<f32, 5>, 2>,
    albedo: vec4<f32>,
}

// chiang::FibrePaths::new at sin θ_o = sin_o_in (T · V).
fn fibre_paths(sin_o_in: f32, color: vec3<f32>, roughness: f32) -> FibrePaths {
    let sin_o = clamp(sin_o_in, -1.0, 1.0);
    let cos_o = sqrt(max(1.0 - sin_o * sin_o, 0.0));
    let sa = sigma_a(color, clamp(roughness, 0.02, 1.0));
    let rc = refraction(sin_o, cos_o);
    var nodes = H_NODES;
    var pieces = PIECES;
    var paths: FibrePaths;
    var trt = vec3<f32>(0.0);
    for (var j = 0u; j < NODES; j++) {
        let node = nodes[j];
        let o = offset_at(j, cos_o, rc, sa);
        let gamma_t = asin(o.sin_gt);
        let f = o.f;
        let tr = o.tr;
        let t1 = (1.0 - f) * (1.0 - f);
        paths.ap[0][j] = t1 * tr;
        paths.ap[1][j] = t1 * tr * tr * f;
        paths.dphi[0][j] = 2.0 * gamma_t - 2.0 * node.y;
        paths.dphi[1][j] = 4.0 * gamma_t - 2.0 * node.y;
        // TRT's albedo: A_p linear in γ over each piece, as the lobe
        // integrates it.
        if j > 0u {
            let w = pieces[j - 1u];
            trt += w.x * paths.ap[1][j - 1u] + w.y * paths.ap[1][j];
        }
    }
    // R's: its own rule.
    paths.albedo = vec4<f32>(r_albedo(cos_o), trt);
    return paths;
}

// chiang::chiang: R + TT + TRT, pbrt's f · |cos| averaged over h; `paths`
// are the view's (fibre_paths(dot(t, v), ...)).
fn chiang(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, paths: FibrePaths, roughness: f32, alpha: f32) -> vec3<f32> {
    let sin_i = clamp(dot(t, l), -1.0, 1.0);
    let sin_o = clamp(dot(t, v), -1.0, 1.0);
    let cos_i = sqrt(max(1.0 - sin_i * sin_i, 0.0));
    let cos_o = sqrt(max(1.0 - sin_o * sin_o, 0.0));
    let lp = safe_normalize(l - t * sin_i);
    let vp = safe_normalize(v - t * sin_o);
    let cos_phi = clamp(dot(lp, vp), -1.0, 1.0);
    let phi = acos(cos_phi);
    let b = clamp(roughness, 0.02, 1.0);
    let x0 = 0.726 * b + 0.812 * b * b + 3.7 * pow(b, 20.0);
    let v0 = x0 * x0;
    let s = 0.626657 * (0.265 * b + 1.194 * b * b + 5.372 * pow(b, 22.0));
    var tilts = tilt(alpha);
    var mps = array<f32, 3>(0.0, 0.0, 0.0);
    for (var p = 0u; p < 3u; p++) {
        let k = tilts[p];
        let sin_p = sin_o * k.y + cos_o * k.x;
        let cos_p = abs(cos_o * k.y - sin_o * k.x);
        mps[p] = mp(cos_i, cos_p, sin_i, sin_p, k.z * v0);
    }
    let a = 3.717 * s;
    let r = (0.7619 * n_r(phi, cos_o) + 0.1190 * (n_r(phi - a, cos_o) + n_r(phi + a, cos_o)))
        * mps[0];
    var pieces = PIECES;
    var ap = paths.ap;
    var dphi = paths.dphi;
    var x = array<f32, 2>(phi - PI, phi);
    let trim = 1.0 / (logistic_cdf(PI, s) - logistic_cdf(-PI, s));
    var out = vec3<f32>(r);
    for (var p = 0u; p < 2u; p++) {
        var lobe = vec3<f32>(0.0);
        for (var side = 0u; side < 2u; side++) {
            let xs = select(-x[p], x[p], side == 0u);
            var cdf = logistic_cdf(xs - dphi[p][0], s);
            for (var j = 0u; j < NODES - 1u; j++) {
                let next = logistic_cdf(xs - dphi[p][j + 1u], s);
                let width = dphi[p][j + 1u] - dphi[p][j];
                var n: f32;
                if abs(width) < 1e-3 * s {
                    n = logistic(xs - 0.5 * (dphi[p][j] + dphi[p][j + 1u]), s);
                } else {
                    n = (cdf - next) / width;
                }
                cdf = next;
                let w = pieces[j];
                lobe += 0.5 * n * (w.x * ap[p][j] + w.y * ap[p][j + 1u]);
            }
        }
        out += lobe * (mps[p + 1u] * trim);
    }
    return out;
}
