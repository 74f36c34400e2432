//! The centre that "outward" points away from. Scheuermann 2004 sorts patches "inside to
//! outside" because "for a head with hair this is very similar to" back to front: inside
//! means near the head the roots sit on. A sphere fitted to the roots stands in for the
//! head, so its centre is where outward starts from for scalp hair, beards and fur alike.

use glam::{DVec3, Vec3};

use super::Strands;
use crate::bounds::Aabb;

/// The least-squares sphere centre of the strand roots, or, when the roots do not pin
/// one down (coplanar, collinear, too few) or it lies farther than 10 bounds diagonals
/// away (nearly flat roots), a point behind the roots: their centroid minus the mean
/// root direction times the bounds diagonal.
pub(super) fn head_centre(strands: &Strands) -> Vec3 {
    let roots: Vec<Vec3> = strands
        .valid
        .iter()
        .map(|&s| strands.points(s)[0])
        .collect();
    if roots.is_empty() {
        return Vec3::ZERO;
    }
    let bounds = strands
        .valid
        .iter()
        .flat_map(|&s| strands.points(s))
        .fold(Aabb::EMPTY, |b, &p| b.grow(p));
    let diagonal = bounds.size().length();
    let centroid = roots.iter().sum::<Vec3>() / roots.len() as f32;
    if let Some(c) = sphere_centre(&roots)
        && roots.iter().all(|r| r.distance(c) <= 10.0 * diagonal)
    {
        return c;
    }
    // Strands leave the skin outward, so their first segments point away from it.
    let dir = strands
        .valid
        .iter()
        .map(|&s| {
            let p = strands.points(s);
            (p[1] - p[0]).normalize_or_zero()
        })
        .sum::<Vec3>()
        .normalize_or_zero();
    centroid - dir * diagonal
}

/// Solves the normal equations of |p|² = 2 c·p + k for (c, k), in doubles about the
/// centroid. `None` when singular.
fn sphere_centre(points: &[Vec3]) -> Option<Vec3> {
    let mean = points.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / points.len() as f64;
    let mut m = [[0f64; 5]; 4];
    let mut scale = 0f64;
    for p in points {
        let d = p.as_dvec3() - mean;
        let row = [2.0 * d.x, 2.0 * d.y, 2.0 * d.z, 1.0];
        let rhs = d.length_squared();
        for i in 0..4 {
            for j in 0..4 {
                m[i][j] += row[i] * row[j];
            }
            m[i][4] += row[i] * rhs;
        }
        scale = scale.max(d.length_squared());
    }
    // Relative pivot threshold: the 3x3 block scales with extent², the k column with 1.
    let x = solve4(m, 1e-9 * scale.max(1e-30) * points.len() as f64)?;
    let c = mean + DVec3::new(x[0], x[1], x[2]);
    c.is_finite().then(|| c.as_vec3())
}

/// Gaussian elimination with partial pivoting on an augmented 4x5 matrix.
fn solve4(mut m: [[f64; 5]; 4], eps: f64) -> Option<[f64; 4]> {
    for col in 0..4 {
        let pivot = (col..4).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        let size = m[pivot][col].abs();
        if size.is_nan() || size <= eps {
            return None;
        }
        m.swap(col, pivot);
        let p = m[col];
        for (r, row) in m.iter_mut().enumerate() {
            if r != col {
                let f = row[col] / p[col];
                row.iter_mut()
                    .zip(p)
                    .skip(col)
                    .for_each(|(x, y)| *x -= f * y);
            }
        }
    }
    Some([0, 1, 2, 3].map(|i| m[i][4] / m[i][i]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::groom::Groom;

    fn strands_from(strands: Vec<Vec<Vec3>>) -> Strands {
        Strands::new(&Groom::from_strands(strands, 1e-4))
    }

    #[test]
    fn fits_the_sphere_the_roots_sit_on() {
        let c = Vec3::new(0.3, 1.6, -0.2);
        let strands = (0..200)
            .map(|i| {
                // Roots on the upper half of a sphere of radius 0.1.
                let (a, b) = (i as f32 * 2.4, 0.2 + (i % 17) as f32 * 0.08);
                let d = Vec3::new(a.cos() * b.sin(), b.cos(), a.sin() * b.sin());
                vec![c + d * 0.1, c + d * 0.1 + Vec3::NEG_Y * 0.2]
            })
            .collect();
        let got = head_centre(&strands_from(strands));
        assert!(got.distance(c) < 1e-4, "{got}");
    }

    #[test]
    fn flat_roots_fall_back_behind_them() {
        // Fur on a plane: roots at y = 0, growing up.
        let strands = (0..50)
            .map(|i| {
                let r = Vec3::new((i % 7) as f32 * 0.01, 0.0, (i / 7) as f32 * 0.01);
                vec![r, r + Vec3::Y * 0.02]
            })
            .collect();
        let got = head_centre(&strands_from(strands));
        assert!(got.y < -0.05 && got.is_finite(), "{got}");
        // One strand, and none.
        let one = head_centre(&strands_from(vec![vec![Vec3::ONE, Vec3::ONE]]));
        assert!(one.is_finite());
        assert_eq!(head_centre(&strands_from(vec![])), Vec3::ZERO);
    }
}
