//! Animation in scenes: rigid joints that move a mesh and the grooms parented
//! to it (a head turning, nodding, bobbing with a walk), and a camera path.
//!
//! Kulikov simulates hair "skinned to head joint (no blend shapes)": a joint
//! here is that head joint, a rigid transform about a pivot applied on top
//! of the mesh's rest placement. Keys are interpolated by cubic Hermite
//! splines with Catmull-Rom tangents (finite differences over the
//! neighbouring keys, so unevenly spaced keys stay smooth) and zero tangents
//! at the first and last key, so a motion eases in and out; before the first
//! key and after the last the pose holds.

use glam::{EulerRot, Mat4, Quat, Vec3};
use serde::{Deserialize, Serialize};

use super::{Camera, Scene, SceneDesc};
use crate::Transform;

#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Animation {
    /// Rigid joints, each moving one mesh and the grooms parented to it.
    #[serde(default)]
    pub joints: Vec<Joint>,
    /// Camera keys; none keeps the scene's camera.
    #[serde(default)]
    pub camera: Vec<CameraKey>,
}

/// A rigid joint: rotation about `pivot` (world space, rest pose), then a
/// translation, applied on top of the mesh's rest placement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Joint {
    /// The mesh it moves (by name).
    pub mesh: String,
    #[serde(default)]
    pub pivot: [f32; 3],
    pub keys: Vec<JointKey>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointKey {
    /// Seconds.
    pub time: f32,
    /// Euler XYZ in degrees (as [`crate::Transform`]): y turns, x nods.
    #[serde(default)]
    pub rotation_deg: [f32; 3],
    /// Metres.
    #[serde(default)]
    pub translation: [f32; 3],
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraKey {
    pub time: f32,
    pub position: [f32; 3],
    pub target: [f32; 3],
    /// Vertical field of view in degrees.
    pub fov_deg: f32,
}

/// Where everything that moves is at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct Pose {
    /// Per mesh of the scene, in scene order: the joint's world-space
    /// transform relative to the rest pose (identity for a mesh no joint moves).
    pub meshes: Vec<Mat4>,
    pub camera: Camera,
}

impl Animation {
    /// The pose at `time` seconds of the scene `desc` (whose meshes and camera
    /// are the rest pose). Joints naming no mesh of `desc` move nothing
    /// (`check` refuses them in scene files).
    pub fn pose(&self, desc: &SceneDesc, time: f32) -> Pose {
        let meshes = desc
            .meshes
            .iter()
            .map(|m| {
                self.joints
                    .iter()
                    .filter(|j| j.mesh == m.name)
                    .fold(Mat4::IDENTITY, |acc, j| j.at(time) * acc)
            })
            .collect();
        let camera = if self.camera.is_empty() {
            desc.camera
        } else {
            let times: Vec<f32> = self.camera.iter().map(|k| k.time).collect();
            let value = |k: &CameraKey| {
                let [px, py, pz] = k.position;
                let [tx, ty, tz] = k.target;
                [px, py, pz, tx, ty, tz, k.fov_deg]
            };
            let values: Vec<[f32; 7]> = self.camera.iter().map(value).collect();
            let v = hermite(&times, &values, time);
            Camera::LookAt {
                position: [v[0], v[1], v[2]],
                target: [v[3], v[4], v[5]],
                fov_deg: v[6],
            }
        };
        Pose { meshes, camera }
    }
}

impl Joint {
    /// The joint's world-space transform at `time`: translate · T(pivot) · R · T(−pivot).
    pub fn at(&self, time: f32) -> Mat4 {
        let times: Vec<f32> = self.keys.iter().map(|k| k.time).collect();
        let values: Vec<[f32; 6]> = self
            .keys
            .iter()
            .map(|k| {
                let [rx, ry, rz] = k.rotation_deg;
                let [x, y, z] = k.translation;
                [rx, ry, rz, x, y, z]
            })
            .collect();
        let v = hermite(&times, &values, time);
        let [rx, ry, rz] = [v[0], v[1], v[2]].map(f32::to_radians);
        let rotation = Quat::from_euler(EulerRot::XYZ, rx, ry, rz);
        let pivot = Vec3::from(self.pivot);
        Mat4::from_translation(Vec3::new(v[3], v[4], v[5]) + pivot)
            * Mat4::from_quat(rotation)
            * Mat4::from_translation(-pivot)
    }
}

impl Scene {
    /// Moves the scene to `time` seconds of its animation: each joint's mesh
    /// and the grooms parented to it, and the camera when the animation has
    /// a path. Poses are computed from the rest pose in `desc`, so any time
    /// can follow any other. Does nothing for a scene without animation.
    pub fn pose_at(&mut self, time: f32) {
        let Some(animation) = &self.desc.animation else {
            return;
        };
        let pose = animation.pose(&self.desc, time);
        for ((mesh, rest), joint) in self
            .meshes
            .iter_mut()
            .zip(&self.desc.meshes)
            .zip(&pose.meshes)
        {
            mesh.mesh.transform = Transform::from_matrix(*joint * rest.transform.matrix());
        }
        for groom in &mut self.grooms {
            let joint = groom.parent.map_or(Mat4::IDENTITY, |p| pose.meshes[p]);
            groom.world = joint * groom.rest_world;
        }
        self.desc.camera = pose.camera;
    }
}

/// Cubic Hermite interpolation of `values` at strictly increasing `times`,
/// Catmull-Rom tangents inside, zero tangents at the ends; holds outside.
fn hermite<const N: usize>(times: &[f32], values: &[[f32; N]], t: f32) -> [f32; N] {
    let (Some(&first), Some(&last)) = (times.first(), times.last()) else {
        return [0.0; N];
    };
    if t <= first || times.len() == 1 {
        return values[0];
    }
    if t >= last {
        return values[values.len() - 1];
    }
    let k = times.partition_point(|&x| x <= t) - 1;
    let (t0, t1) = (times[k], times[k + 1]);
    let h = t1 - t0;
    let s = (t - t0) / h;
    let tangent = |i: usize, c: usize| {
        if i == 0 || i + 1 == times.len() {
            0.0
        } else {
            (values[i + 1][c] - values[i - 1][c]) / (times[i + 1] - times[i - 1])
        }
    };
    let (s2, s3) = (s * s, s * s * s);
    let (h00, h10, h01, h11) = (
        2.0 * s3 - 3.0 * s2 + 1.0,
        s3 - 2.0 * s2 + s,
        -2.0 * s3 + 3.0 * s2,
        s3 - s2,
    );
    std::array::from_fn(|c| {
        h00 * values[k][c]
            + h10 * h * tangent(k, c)
            + h01 * values[k + 1][c]
            + h11 * h * tangent(k + 1, c)
    })
}

/// What is wrong with the animation of `desc`, and the text to point at.
pub(super) fn check(a: &Animation, desc: &SceneDesc) -> Result<(), (String, String)> {
    for j in &a.joints {
        let needle = format!("mesh: {:?}", j.mesh);
        if !desc.meshes.iter().any(|m| m.name == j.mesh) {
            return Err((needle, format!("joint: no mesh named {:?}", j.mesh)));
        }
        if !j.pivot.iter().all(|v| v.is_finite()) {
            return Err((needle, "joint: pivot must be finite".into()));
        }
        let values = j
            .keys
            .iter()
            .flat_map(|k| k.rotation_deg.into_iter().chain(k.translation));
        if values.clone().any(|v| !v.is_finite()) {
            return Err((
                needle,
                "joint: rotations and translations must be finite".into(),
            ));
        }
        keys(j.keys.iter().map(|k| k.time)).map_err(|m| (needle, format!("joint: {m}")))?;
    }
    for k in &a.camera {
        let ok = k.position.iter().chain(&k.target).all(|v| v.is_finite());
        if !ok || k.position == k.target {
            return Err((
                "camera:".into(),
                "camera key: position and target must be finite and apart".into(),
            ));
        }
        if !(k.fov_deg > 0.0 && k.fov_deg < 180.0) {
            return Err((
                "fov_deg".into(),
                "camera key: fov_deg must be in (0, 180)".into(),
            ));
        }
    }
    keys(a.camera.iter().map(|k| k.time))
        .map_err(|m| ("camera:".into(), format!("camera path: {m}")))
}

/// Key times: finite, at least 0, strictly increasing; at most 10,000 keys.
fn keys(times: impl Iterator<Item = f32> + Clone) -> Result<(), String> {
    if times.clone().count() > 10_000 {
        return Err("more than 10000 keys".into());
    }
    let mut last = f32::NEG_INFINITY;
    for t in times {
        if !(0.0..=1e6).contains(&t) {
            return Err(format!("key time {t} must be in 0..=1e6 seconds"));
        }
        if t <= last {
            return Err(format!("key times must increase ({last} then {t})"));
        }
        last = t;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(time: f32, yaw: f32) -> JointKey {
        JointKey {
            time,
            rotation_deg: [0.0, yaw, 0.0],
            translation: [0.0; 3],
        }
    }

    fn turn() -> Joint {
        Joint {
            mesh: "head".into(),
            pivot: [0.0, 1.5, 0.0],
            keys: vec![key(0.0, 0.0), key(0.5, 60.0), key(1.0, -30.0)],
        }
    }

    #[test]
    fn keys_are_hit_and_held_outside() {
        let j = turn();
        let yaw = |t: f32| {
            let (_, r, _) = j.at(t).to_scale_rotation_translation();
            r.to_euler(EulerRot::YXZ).0.to_degrees()
        };
        for (t, want) in [
            (-1.0, 0.0),
            (0.0, 0.0),
            (0.5, 60.0),
            (1.0, -30.0),
            (3.0, -30.0),
        ] {
            assert!(
                (yaw(t) - want).abs() < 1e-3,
                "t = {t}: {} vs {want}",
                yaw(t)
            );
        }
        // Between keys the spline moves monotonically here, and eases in.
        assert!(yaw(0.05) > 0.0 && yaw(0.05) < 6.0, "{}", yaw(0.05));
    }

    #[test]
    fn the_pivot_stays_put() {
        let j = turn();
        let p = j.at(0.3).transform_point3(Vec3::new(0.0, 1.5, 0.0));
        assert!(p.distance(Vec3::new(0.0, 1.5, 0.0)) < 1e-5, "{p}");
    }

    #[test]
    fn interpolation_is_smooth_across_keys() {
        // The slopes just before and just after the middle key agree (C1).
        let times = [0.0, 0.4, 1.0];
        let values = [[0.0], [1.0], [0.5]];
        let f = |t: f32| hermite(&times, &values, t)[0];
        let h = 1e-4;
        let (left, right) = ((f(0.4) - f(0.4 - h)) / h, (f(0.4 + h) - f(0.4)) / h);
        assert!((left - right).abs() < 0.02, "{left} vs {right}");
        // The Catmull-Rom tangent there: (0.5 - 0) / (1 - 0).
        assert!((left - 0.5).abs() < 0.02, "{left}");
    }

    #[test]
    fn checks_name_what_is_wrong() {
        let desc: SceneDesc = ron::from_str(
            "Scene(resolution: (8, 8), camera: LookAt(position: (0.0, 0.0, 1.0), target: (0.0, 0.0, 0.0), fov_deg: 30.0), graph: \"g.ron\")",
        )
        .unwrap();
        let mut a = Animation {
            joints: vec![turn()],
            camera: vec![],
        };
        assert!(
            check(&a, &desc)
                .unwrap_err()
                .1
                .contains("no mesh named \"head\"")
        );
        a.joints[0].mesh = "x".into();
        let mut desc = desc;
        desc.meshes.push(super::super::MeshDesc {
            name: "x".into(),
            source: super::super::MeshSource::Head(Default::default()),
            transform: Default::default(),
        });
        assert_eq!(check(&a, &desc), Ok(()));
        a.joints[0].keys[2].time = 0.5;
        assert!(check(&a, &desc).unwrap_err().1.contains("must increase"));
        a.joints[0].keys[2].time = f32::NAN;
        assert!(check(&a, &desc).unwrap_err().1.contains("key time"));
    }
}
