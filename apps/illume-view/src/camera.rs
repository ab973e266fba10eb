//! The viewer's camera controls: orbit about a target, pan, dolly, fly; each produces
//! the camera's `world_from_camera` (looking down −Z, +Y up, as `look_from` places it).

use glam::{Affine3A, Vec3};

/// Orbit/fly camera state.
#[derive(Clone, Copy, Debug)]
pub struct OrbitCamera {
    /// The point orbited \[m\].
    pub target: Vec3,
    /// Distance from the eye to the target \[m\].
    pub distance: f32,
    /// Angle about +Y \[rad\].
    pub yaw: f32,
    /// Angle above the horizon \[rad\], within ±89°.
    pub pitch: f32,
}

impl OrbitCamera {
    /// The orbit that reproduces `world_from_camera`, orbiting a point `distance` ahead.
    pub fn from_transform(world_from_camera: Affine3A, distance: f32) -> Self {
        let eye = Vec3::from(world_from_camera.translation);
        let forward = world_from_camera
            .transform_vector3(-Vec3::Z)
            .normalize_or(-Vec3::Z);
        let distance = if distance.is_finite() && distance > 1e-3 {
            distance
        } else {
            1.0
        };
        // The eye sits at target - forward · distance; forward = -(dir from target to eye).
        let back = -forward;
        Self {
            target: eye + forward * distance,
            distance,
            yaw: back.x.atan2(back.z),
            pitch: back.y.clamp(-1.0, 1.0).asin(),
        }
    }

    /// The eye position \[m\].
    pub fn eye(&self) -> Vec3 {
        self.target + self.back() * self.distance
    }

    /// Unit vector from the target to the eye.
    fn back(&self) -> Vec3 {
        Vec3::new(
            self.pitch.cos() * self.yaw.sin(),
            self.pitch.sin(),
            self.pitch.cos() * self.yaw.cos(),
        )
    }

    /// The camera's placement.
    pub fn world_from_camera(&self) -> Affine3A {
        Affine3A::look_at_rh(self.eye(), self.target, Vec3::Y).inverse()
    }

    /// Turns about the target by mouse motion \[rad\].
    pub fn orbit(&mut self, d_yaw: f32, d_pitch: f32) {
        self.yaw -= d_yaw;
        self.pitch = (self.pitch + d_pitch).clamp(-1.55, 1.55);
    }

    /// Moves target and eye across the view by fractions of the distance.
    pub fn pan(&mut self, right: f32, up: f32) {
        let m = self.world_from_camera();
        let r = m.transform_vector3(Vec3::X);
        let u = m.transform_vector3(Vec3::Y);
        self.target += (r * right + u * up) * self.distance;
    }

    /// Moves towards the target: the distance is multiplied by `factor`.
    pub fn dolly(&mut self, factor: f32) {
        self.distance = (self.distance * factor).clamp(1e-3, 1e6);
    }

    /// Fly mode: turns the view about the eye (the eye stays).
    pub fn look(&mut self, d_yaw: f32, d_pitch: f32) {
        let eye = self.eye();
        self.yaw -= d_yaw;
        self.pitch = (self.pitch - d_pitch).clamp(-1.55, 1.55);
        self.target = eye - self.back() * self.distance;
    }

    /// Fly mode: moves eye and target along the view (`forward`, `right`, `up`) \[m\].
    pub fn fly(&mut self, forward: f32, right: f32, up: f32) {
        let m = self.world_from_camera();
        let f = m.transform_vector3(-Vec3::Z);
        let r = m.transform_vector3(Vec3::X);
        self.target += f * forward + r * right + Vec3::Y * up;
    }

    /// Orbits `point` from the current direction (focus on a clicked point).
    pub fn focus(&mut self, point: Vec3) {
        let eye = self.eye();
        self.target = point;
        self.distance = (eye - point).length().max(1e-3);
        let back = (eye - point) / self.distance;
        self.yaw = back.x.atan2(back.z);
        self.pitch = back.y.clamp(-1.0, 1.0).asin();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_a_placement() {
        let m = Affine3A::look_at_rh(Vec3::new(1.0, 2.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y)
            .inverse();
        let o = OrbitCamera::from_transform(m, 3.0);
        let back = o.world_from_camera();
        assert!((Vec3::from(back.translation) - Vec3::new(1.0, 2.0, 5.0)).length() < 1e-4);
        let f0 = m.transform_vector3(-Vec3::Z);
        let f1 = back.transform_vector3(-Vec3::Z);
        assert!((f0 - f1).length() < 1e-4, "{f0} vs {f1}");
    }

    #[test]
    fn orbit_keeps_the_distance_and_target() {
        let mut o = OrbitCamera {
            target: Vec3::ONE,
            distance: 2.0,
            yaw: 0.0,
            pitch: 0.0,
        };
        o.orbit(0.5, 0.3);
        assert!(((o.eye() - o.target).length() - 2.0).abs() < 1e-5);
        assert_eq!(o.target, Vec3::ONE);
    }
}
