//! Per-groom and per-mesh rigid transforms with uniform scale, as written in scene files.

use glam::{EulerRot, Mat4, Quat, Vec3};
use serde::{Deserialize, Serialize};

/// Translation (metres), rotation (Euler XYZ, degrees) and uniform scale.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Transform {
    pub translation: [f32; 3],
    pub rotation_deg: [f32; 3],
    pub scale: f32,
}

impl Default for Transform {
    fn default() -> Self {
        Transform::IDENTITY
    }
}

impl Transform {
    pub const IDENTITY: Transform = Transform {
        translation: [0.0; 3],
        rotation_deg: [0.0; 3],
        scale: 1.0,
    };

    pub fn from_translation(t: Vec3) -> Self {
        Transform {
            translation: t.to_array(),
            ..Transform::IDENTITY
        }
    }
    pub fn rotation(&self) -> Quat {
        let [x, y, z] = self.rotation_deg.map(f32::to_radians);
        Quat::from_euler(EulerRot::XYZ, x, y, z)
    }
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(
            Vec3::splat(self.scale),
            self.rotation(),
            Vec3::from_array(self.translation),
        )
    }
    /// The transform of a matrix made of a uniform scale, a rotation and a
    /// translation (what [`Transform::matrix`] makes).
    pub fn from_matrix(m: Mat4) -> Self {
        let (scale, rotation, translation) = m.to_scale_rotation_translation();
        let (x, y, z) = rotation.to_euler(EulerRot::XYZ);
        Transform {
            translation: translation.to_array(),
            rotation_deg: [x, y, z].map(f32::to_degrees),
            scale: scale.x,
        }
    }
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.matrix().transform_point3(p)
    }
    /// `self` applied after `inner`: the world transform of a child placed at `inner` in `self`.
    pub fn compose(&self, inner: &Transform) -> Mat4 {
        self.matrix() * inner.matrix()
    }
    pub fn is_finite(&self) -> bool {
        self.translation
            .iter()
            .chain(&self.rotation_deg)
            .all(|v| v.is_finite())
            && self.scale.is_finite()
            && self.scale > 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotates_then_translates() {
        let t = Transform {
            translation: [1.0, 0.0, 0.0],
            rotation_deg: [0.0, 90.0, 0.0],
            scale: 2.0,
        };
        let p = t.apply(Vec3::X);
        assert!((p - Vec3::new(1.0, 0.0, -2.0)).length() < 1e-5, "{p}");
        let back = Transform::from_matrix(t.matrix()).matrix();
        assert!(
            back.abs_diff_eq(t.matrix(), 1e-5),
            "{back} vs {}",
            t.matrix()
        );
    }
}
