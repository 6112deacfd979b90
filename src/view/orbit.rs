//! The viewer's camera moves, as the CS184 program makes them: orbit about a target point,
//! pan the camera and its target together, zoom toward the target. The camera keeps its
//! fields of view, clip planes and lens; only its position and frame change.

use glam::{Mat3, Vec3};
use wavepath::Camera;

/// A camera and the point it orbits about.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub camera: Camera,
    pub target: Vec3,
}

/// The closest an orbit gets to looking straight up or down (|cos| of the angle between the
/// view and the vertical): beyond it the frame's up vector would flip.
const MAX_VERTICAL: f32 = 0.995;

impl Orbit {
    /// `camera` orbiting the point it looks at at the distance of `center` (the scene's
    /// centre) along its view; a camera that faces away from the centre orbits at the centre's
    /// distance in front of it.
    pub fn new(camera: Camera, center: Vec3) -> Self {
        let forward = -camera.c2w.z_axis;
        let along = (center - camera.position).dot(forward);
        let d = if along > 0.0 { along } else { (center - camera.position).length().max(1e-3) };
        Orbit { camera, target: camera.position + forward * d }
    }

    fn distance(&self) -> f32 {
        (self.camera.position - self.target).length()
    }

    /// Turns the camera about the target by `yaw` radians about the world's vertical and
    /// `pitch` radians about the camera's right axis (stopping short of the poles).
    pub fn orbit(&mut self, yaw: f32, pitch: f32) {
        let back = self.camera.c2w.z_axis;
        let right = self.camera.c2w.x_axis;
        let turn = Mat3::from_axis_angle(Vec3::Y, yaw);
        let tilted = Mat3::from_axis_angle(right, pitch) * back;
        let back = turn * if tilted.y.abs() <= MAX_VERTICAL { tilted } else { back };
        let d = self.distance();
        self.set_view(back.normalize(), d);
    }

    /// Moves camera and target together by `dx`, `dy` times the distance to the target along
    /// the camera's right and up axes.
    pub fn pan(&mut self, dx: f32, dy: f32) {
        let d = self.distance();
        let shift = (self.camera.c2w.x_axis * dx + self.camera.c2w.y_axis * dy) * d;
        self.camera.position += shift;
        self.target += shift;
    }

    /// Multiplies the distance to the target by `factor` (< 1: closer).
    pub fn zoom(&mut self, factor: f32) {
        let d = (self.distance() * factor).max(1e-6);
        self.set_view(self.camera.c2w.z_axis, d);
    }

    /// Places the camera at distance `d` from the target along `back`, looking at it with
    /// the world's vertical as up.
    fn set_view(&mut self, back: Vec3, d: f32) {
        let up_hint = if Vec3::Y.cross(back).length_squared() < 1e-8 { self.camera.c2w.y_axis } else { Vec3::Y };
        let right = up_hint.cross(back).normalize();
        let up = back.cross(right).normalize();
        self.camera.c2w = Mat3::from_cols(right, up, back);
        self.camera.position = self.target + back * d;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4 * (1.0 + b.length())
    }

    #[test]
    fn orbit_keeps_the_target_in_view_at_its_distance() {
        let cam = Camera::look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 40.0, 1.5);
        let mut o = Orbit::new(cam, Vec3::new(0.3, 1.0, 0.0));
        assert!(close(o.target, Vec3::new(0.0, 1.0, 0.0)));
        for (yaw, pitch) in [(0.5, 0.0), (0.0, 0.3), (-1.0, -0.7), (3.0, 2.0)] {
            o.orbit(yaw, pitch);
            assert!((o.distance() - 5.0).abs() < 1e-3);
            // The view still goes through the target; the frame stays orthonormal and upright.
            assert!(close(o.camera.position - o.camera.c2w.z_axis * 5.0, o.target));
            assert!(o.camera.c2w.x_axis.y.abs() < 1e-5 && o.camera.c2w.y_axis.y > 0.0);
            assert!(o.camera.c2w.z_axis.y.abs() <= MAX_VERTICAL + 1e-4);
        }
        // A quarter turn of yaw from +Z looks from +X.
        let mut o = Orbit::new(cam, Vec3::new(0.0, 1.0, 0.0));
        o.orbit(std::f32::consts::FRAC_PI_2, 0.0);
        assert!(close(o.camera.position, Vec3::new(5.0, 1.0, 0.0)), "{}", o.camera.position);
    }

    #[test]
    fn pan_moves_both_and_zoom_scales_the_distance() {
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 40.0, 1.0);
        let mut o = Orbit::new(cam, Vec3::ZERO);
        o.pan(0.25, -0.5);
        assert!(close(o.target, Vec3::new(1.0, -2.0, 0.0)) && close(o.camera.position, Vec3::new(1.0, -2.0, 4.0)));
        o.zoom(0.5);
        assert!(close(o.camera.position, Vec3::new(1.0, -2.0, 2.0)));
        assert_eq!(o.camera.vfov_deg, cam.vfov_deg);
    }
}
