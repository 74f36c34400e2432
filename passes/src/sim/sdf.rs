//! Sampling a baked collision field ([`strandgraph_assets::mesh_sdf`]):
//! trilinear distance and its analytic gradient. `shaders/sim/pbd.wgsl`
//! ports it operation for operation.

pub use strandgraph_assets::mesh_sdf::SDF_RES;

/// Words of one field in `sim.sdf`.
pub const FIELD_WORDS: usize = SDF_RES * SDF_RES * SDF_RES;

/// `a + (b − a) · t`, in this order on every backend.
pub fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// The distance at groom-local `q` and its gradient (in grid units, not
/// normalised), from the field whose grid point 0 is `min.xyz` with
/// `min.w` grid points per unit, its values `fetch(0..FIELD_WORDS)`;
/// `None` outside the grid, where nothing collides.
pub fn sample(fetch: impl Fn(usize) -> f32, min: [f32; 4], q: [f32; 3]) -> Option<(f32, [f32; 3])> {
    let last = (SDF_RES - 1) as f32;
    let f = [0, 1, 2].map(|k| (q[k] - min[k]) * min[3]);
    if !f.iter().all(|&v| v >= 0.0 && v <= last) {
        return None;
    }
    let i = f.map(|v| (v.floor() as usize).min(SDF_RES - 2));
    let t = [0, 1, 2].map(|k| f[k] - i[k] as f32);
    let c = |dx: usize, dy: usize, dz: usize| {
        fetch(i[0] + dx + SDF_RES * (i[1] + dy + SDF_RES * (i[2] + dz)))
    };
    let (c000, c100, c010, c110) = (c(0, 0, 0), c(1, 0, 0), c(0, 1, 0), c(1, 1, 0));
    let (c001, c101, c011, c111) = (c(0, 0, 1), c(1, 0, 1), c(0, 1, 1), c(1, 1, 1));
    let x00 = lerp(c000, c100, t[0]);
    let x10 = lerp(c010, c110, t[0]);
    let x01 = lerp(c001, c101, t[0]);
    let x11 = lerp(c011, c111, t[0]);
    let y0 = lerp(x00, x10, t[1]);
    let y1 = lerp(x01, x11, t[1]);
    let d = lerp(y0, y1, t[2]);
    let ex0 = lerp(c100 - c000, c110 - c010, t[1]);
    let ex1 = lerp(c101 - c001, c111 - c011, t[1]);
    let gradient = [
        lerp(ex0, ex1, t[2]),
        lerp(x10 - x00, x11 - x01, t[2]),
        y1 - y0,
    ];
    Some((d, gradient))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plane field d = 0.5 x − 0.25 y over the grid: trilinear is exact on it.
    #[test]
    fn a_linear_field_is_reproduced_with_its_gradient() {
        let min = [-1.0, -1.0, -1.0, 10.0];
        let value = |i: usize| {
            let (x, y) = (
                (i % SDF_RES) as f32 / 10.0 - 1.0,
                (i / SDF_RES % SDF_RES) as f32 / 10.0 - 1.0,
            );
            0.5 * x - 0.25 * y
        };
        let (d, g) = sample(value, min, [0.33, 0.71, 1.2]).unwrap();
        assert!((d - (0.5 * 0.33 - 0.25 * 0.71)).abs() < 1e-5, "{d}");
        // Per grid step (0.1 units).
        assert!(
            (g[0] - 0.05).abs() < 1e-5 && (g[1] + 0.025).abs() < 1e-5 && g[2].abs() < 1e-6,
            "{g:?}"
        );
        assert!(sample(value, min, [-1.01, 0.0, 0.0]).is_none());
        assert!(sample(value, min, [0.0, 2.91, 0.0]).is_none());
        // The far faces of the grid are inside it.
        assert!(sample(value, min, [2.9, 2.9, 2.9]).is_some());
    }
}
