//! The viewer's orbit camera: yaw and pitch about a target, a distance,
//! and a vertical field of view, as a scene's `LookAt` camera writes them.
//! Dragging orbits, dragging with the middle button (or Shift) pans in the
//! view plane, scrolling zooms toward the target.

use glam::Vec3;

/// The closest the eye comes to the target, in metres: ten near planes, so
/// the target never crosses the near plane (`strandgraph_passes::upload::NEAR`).
const MIN_DISTANCE: f32 = 10.0 * strandgraph_passes::upload::NEAR;
/// Pitch stays short of the poles, where `look_at` has no up direction.
const MAX_PITCH: f32 = 1.54;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    pub target: Vec3,
    /// Radians about +Y, 0 looking down −Z.
    pub yaw: f32,
    /// Radians above the horizon.
    pub pitch: f32,
    pub distance: f32,
    /// Vertical field of view in degrees.
    pub fov: f32,
}

impl Orbit {
    /// The orbit whose eye is `eye`, looking at `target`.
    pub fn look_at(eye: Vec3, target: Vec3, fov: f32) -> Orbit {
        let d = eye - target;
        let distance = d.length().max(MIN_DISTANCE);
        let dir = if d.length() > 0.0 {
            d / d.length()
        } else {
            Vec3::Z
        };
        Orbit {
            target,
            yaw: dir.x.atan2(dir.z),
            pitch: dir.y.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH),
            distance,
            fov,
        }
    }

    /// Unit vector from the target to the eye.
    fn back(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(sy * cp, sp, cy * cp)
    }

    pub fn eye(&self) -> Vec3 {
        self.target + self.back() * self.distance
    }

    /// Orbits by `dx`, `dy` radians (right and up drags turn the head
    /// the other way, as in every DCC viewport).
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw = (self.yaw - dx).rem_euclid(std::f32::consts::TAU);
        self.pitch = (self.pitch + dy).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the target (and the eye with it) by a drag of `dx`, `dy`
    /// pixels in a viewport `height` pixels tall, so the point under the
    /// cursor at the target's depth follows the cursor.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let back = self.back();
        let right = Vec3::Y.cross(back).normalize_or_zero();
        let up = back.cross(right);
        let metres_per_pixel =
            2.0 * self.distance * (self.fov.to_radians() * 0.5).tan() / height.max(1.0);
        self.target += (-dx * right + dy * up) * metres_per_pixel;
    }

    /// Zooms by `steps` (positive: closer), 10% of the distance a step.
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * 0.9f32.powf(steps)).max(MIN_DISTANCE);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4
    }

    #[test]
    fn look_at_puts_the_eye_back_where_it_was() {
        for eye in [
            Vec3::new(0.42, 1.62, 0.78),
            Vec3::new(-2.0, 0.5, -1.0),
            Vec3::new(0.0, 1.0, 3.0),
        ] {
            let target = Vec3::new(0.0, 1.6, 0.0);
            let o = Orbit::look_at(eye, target, 30.0);
            assert!(close(o.eye(), eye), "{eye} -> {}", o.eye());
        }
    }

    #[test]
    fn a_full_turn_of_yaw_comes_back_and_keeps_the_distance() {
        let mut o = Orbit::look_at(Vec3::new(0.0, 1.7, 1.0), Vec3::new(0.0, 1.6, 0.0), 30.0);
        let start = o.eye();
        for _ in 0..8 {
            o.orbit(std::f32::consts::FRAC_PI_4, 0.0);
            assert!(((o.eye() - o.target).length() - o.distance).abs() < 1e-5);
        }
        assert!(close(o.eye(), start));
    }

    #[test]
    fn pitch_stops_short_of_the_poles() {
        let mut o = Orbit::look_at(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 30.0);
        o.orbit(0.0, 10.0);
        assert!(o.pitch <= MAX_PITCH);
        assert!(
            o.eye().x.abs() + o.eye().z.abs() > 0.0,
            "never straight above"
        );
    }

    #[test]
    fn panning_moves_eye_and_target_together_across_the_view() {
        let mut o = Orbit::look_at(Vec3::new(0.0, 1.6, 2.0), Vec3::new(0.0, 1.6, 0.0), 30.0);
        let (eye, target) = (o.eye(), o.target);
        o.pan(100.0, 0.0, 1000.0);
        // Dragging right moves the scene right: the camera moves left (−X here).
        assert!(o.target.x < target.x && o.target.y == target.y && o.target.z == target.z);
        assert!(close(o.eye() - eye, o.target - target));
        // 100 of 1000 pixels at 2 m with a 30° field: 0.1 × 2 × 2 tan 15°.
        let expected = 0.1 * 2.0 * 2.0 * 15f32.to_radians().tan();
        assert!((target.x - o.target.x - expected).abs() < 1e-5);
    }

    #[test]
    fn zoom_approaches_the_target_but_not_past_the_near_planes() {
        let mut o = Orbit::look_at(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 30.0);
        o.zoom(1.0);
        assert!((o.distance - 0.9).abs() < 1e-6);
        o.zoom(1000.0);
        assert_eq!(o.distance, MIN_DISTANCE);
    }
}
