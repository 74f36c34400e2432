//! Octahedral unit-vector encoding packed into a u32 (two 16-bit snorm values), and
//! barycentric packing (two 16-bit unorm values; the third is reconstructed).
//! Kulikov: hairRootSkinningInfo_t stores "packed x and y, octahedral encoding".

use glam::{Vec2, Vec3};

fn sign_not_zero(v: Vec2) -> Vec2 {
    Vec2::new(
        if v.x >= 0.0 { 1.0 } else { -1.0 },
        if v.y >= 0.0 { 1.0 } else { -1.0 },
    )
}

/// Maps a unit vector to the [-1, 1]² octahedral square (Cigolle et al. 2014).
pub fn oct_encode(n: Vec3) -> Vec2 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if l1 <= 0.0 || !l1.is_finite() {
        return Vec2::new(0.0, 0.0);
    }
    let p = Vec2::new(n.x, n.y) / l1;
    if n.z < 0.0 {
        (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * sign_not_zero(p)
    } else {
        p
    }
}

pub fn oct_decode(e: Vec2) -> Vec3 {
    let z = 1.0 - e.x.abs() - e.y.abs();
    let xy = if z < 0.0 {
        (Vec2::ONE - Vec2::new(e.y.abs(), e.x.abs())) * sign_not_zero(e)
    } else {
        e
    };
    Vec3::new(xy.x, xy.y, z).normalize_or_zero()
}

fn snorm16(v: f32) -> u32 {
    ((v.clamp(-1.0, 1.0) * 32767.0).round() as i32 as i16 as u16) as u32
}
fn unsnorm16(v: u32) -> f32 {
    ((v as u16 as i16) as f32 / 32767.0).max(-1.0)
}

/// Packs a unit vector into a u32: x in the low 16 bits, y in the high 16 bits.
pub fn pack_unit_vector(n: Vec3) -> u32 {
    let e = oct_encode(n);
    snorm16(e.x) | (snorm16(e.y) << 16)
}

pub fn unpack_unit_vector(p: u32) -> Vec3 {
    oct_decode(Vec2::new(unsnorm16(p & 0xffff), unsnorm16(p >> 16)))
}

/// Packs barycentrics (x, y; z = 1 - x - y is reconstructed) as two 16-bit unorms.
pub fn pack_barycentrics(b: Vec3) -> u32 {
    let q = |v: f32| (v.clamp(0.0, 1.0) * 65535.0).round() as u32;
    q(b.x) | (q(b.y) << 16)
}

pub fn unpack_barycentrics(p: u32) -> Vec3 {
    let x = (p & 0xffff) as f32 / 65535.0;
    let y = (p >> 16) as f32 / 65535.0;
    Vec3::new(x, y, (1.0 - x - y).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn unit_vectors_round_trip(x in -1.0f32..1.0, y in -1.0f32..1.0, z in -1.0f32..1.0) {
            let n = Vec3::new(x, y, z);
            prop_assume!(n.length() > 1e-3);
            let n = n.normalize();
            let d = unpack_unit_vector(pack_unit_vector(n));
            prop_assert!(d.angle_between(n) < 1e-3, "{n} -> {d}");
        }

        #[test]
        fn barycentrics_round_trip(a in 0.0f32..1.0, b in 0.0f32..1.0) {
            let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
            let w = Vec3::new(a, b, 1.0 - a - b);
            let d = unpack_barycentrics(pack_barycentrics(w));
            prop_assert!((d - w).abs().max_element() < 2e-5);
        }
    }

    #[test]
    fn axes_exact() {
        for n in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
            assert!(unpack_unit_vector(pack_unit_vector(n)).distance(n) < 1e-4);
        }
    }
}
