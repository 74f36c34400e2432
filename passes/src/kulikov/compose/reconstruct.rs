//! Kulikov: coverage reconstruction from the 3 front layers and the total.
//!
//! "Calculate coverage from front 3 samples: C_front = 1 − (1 − C1)(1 − C2)(1 − C3).
//! Take C_total from visibility atlas: C_total = C_front + C_missing.
//! Approximate lighting for missing coverage from front samples:
//! L_missing = C_missing Σ w_i L_i / Σ w_i, w_i = C_i · 0.25^(3−i).
//! Calc front samples lighting with simple alpha blend."
//!
//! The quadratic fit can fall below C_front where only a few strands cover
//! the pixel (one strand of coverage 0.5 has x = 0.5, fit 0.44), so the
//! missing coverage is clamped at 0 and the pixel's coverage is
//! max(C_front, C_total).

/// One visibility layer: its coverage of the pixel and its radiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layer {
    pub coverage: f32,
    pub lighting: [f32; 3],
}

/// Premultiplied hair radiance and coverage of a pixel from its front layers
/// (nearest first, at most 3) and the total coverage; with `missing` false
/// only the front layers count (the talk's "3 front fragments only").
pub fn reconstruct(layers: &[Layer], c_total: f32, missing: bool) -> ([f32; 3], f32) {
    let mut front = [0.0f32; 3];
    let mut transmit = 1.0;
    let (mut wsum, mut wl) = (0.0f32, [0.0f32; 3]);
    let n = layers.len().min(3);
    for (i, l) in layers.iter().take(3).enumerate() {
        let c = l.coverage.clamp(0.0, 1.0);
        for (f, x) in front.iter_mut().zip(l.lighting) {
            *f += transmit * c * x;
        }
        transmit *= 1.0 - c;
        // Kulikov: w_i = C_i · 0.25^(3−i) (i from 1): favour samples further back.
        // With fewer than 3 layers the last one present gets weight C_i.
        let w = c * 0.25f32.powi((n - 1 - i) as i32);
        wsum += w;
        for (a, x) in wl.iter_mut().zip(l.lighting) {
            *a += w * x;
        }
    }
    let c_front = 1.0 - transmit;
    if !missing || wsum <= 0.0 {
        return (front, c_front);
    }
    let c_missing = (c_total.clamp(0.0, 1.0) - c_front).max(0.0);
    let hair = [0, 1, 2].map(|k| front[k] + c_missing * wl[k] / wsum);
    (hair, c_front + c_missing)
}
