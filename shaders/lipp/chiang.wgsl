// Chiang et al. 2016 single scattering (R, TT, TRT), the compact form
// lipp.shade evaluates per pixel. Port of passes/src/lipp/chiang.rs.
// Composed with naga_oil:
//   #import strandgraph::chiang::{chiang}
#define_import_path strandgraph::chiang

#import strandgraph::lipp::{PI, safe_normalize}

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

fn trimmed_logistic(x: f32, s: f32) -> f32 {
    return logistic(x, s) / (logistic_cdf(PI, s) - logistic_cdf(-PI, s));
}

fn wrap_angle(phi: f32) -> f32 {
    var p = phi;
    while p > PI {
        p -= 2.0 * PI;
    }
    while p < -PI {
        p += 2.0 * PI;
    }
    return p;
}

// chiang::chiang: R + TT + TRT times cos θ_i.
fn chiang(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, color: vec3<f32>, roughness: f32) -> vec3<f32> {
    let sin_i = clamp(dot(t, l), -1.0, 1.0);
    let sin_o = clamp(dot(t, v), -1.0, 1.0);
    let cos_i = sqrt(max(1.0 - sin_i * sin_i, 0.0));
    let cos_o = sqrt(max(1.0 - sin_o * sin_o, 0.0));
    let lp = safe_normalize(l - t * sin_i);
    let vp = safe_normalize(v - t * sin_o);
    let phi = acos(clamp(dot(lp, vp), -1.0, 1.0));
    let bm = clamp(roughness, 0.02, 1.0);
    let x0 = 0.726 * bm + 0.812 * bm * bm + 3.7 * pow(bm, 20.0);
    let v0 = x0 * x0;
    let s = 0.626657 * (0.265 * bm + 1.194 * bm * bm + 5.372 * pow(bm, 22.0));
    let alpha = radians(2.0);
    let eta = 1.55;
    let f0 = ((eta - 1.0) / (eta + 1.0)) * ((eta - 1.0) / (eta + 1.0));
    let f = f0 + (1.0 - f0) * pow(1.0 - cos_o, 5.0);
    let sin_t = sin_o / eta;
    let cos_t = sqrt(max(1.0 - sin_t * sin_t, 1e-4));
    let tr = exp(-2.0 * sigma_a(color, bm) / cos_t);
    var out = vec3<f32>(0.0);
    for (var p = 0u; p < 3u; p++) {
        var var_p = v0;
        var shift = -2.0 * alpha;
        var a = vec3<f32>(f);
        if p == 1u {
            var_p = 0.25 * v0;
            shift = alpha;
            a = (1.0 - f) * (1.0 - f) * tr;
        } else if p == 2u {
            var_p = 4.0 * v0;
            shift = 4.0 * alpha;
            a = (1.0 - f) * (1.0 - f) * tr * tr * f;
        }
        let x = sin_i + sin_o - shift;
        let mp = exp(-x * x / (2.0 * var_p)) / sqrt(2.0 * PI * var_p);
        let np = trimmed_logistic(wrap_angle(phi - f32(p) * PI), s);
        out += mp * a * np;
    }
    return out * cos_i;
}
