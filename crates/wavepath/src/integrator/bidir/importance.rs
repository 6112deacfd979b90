//! The pinhole camera as light paths meet it: where a point lands on the film, and the
//! density with which camera rays draw the direction toward it.

use crate::integrator::camera::CameraTerms;
use glam::{Mat3, Vec3};

/// The render's pinhole camera, inverted: world points to pixels.
#[derive(Clone, Copy, Debug)]
pub struct Importance {
    pos: Vec3,
    w2c: Mat3,
    tan_half: (f32, f32),
    width: usize,
    height: usize,
    nclip: f32,
    fclip: f32,
    /// Pixels per unit area of the image plane at distance 1: a camera ray's direction
    /// density per pixel area is this over cos^3 (a pixel spans 4 tan tan / (w h)).
    pixels_per_area: f32,
}

/// A world point seen by the camera.
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    /// Row-major pixel index (bottom row first, as the film).
    pub pixel: usize,
    /// Unit direction from the point toward the camera.
    pub to_camera: Vec3,
    pub dist: f32,
    /// Cosine between the camera's axis and the direction to the point.
    pub cos_camera: f32,
}

impl Importance {
    /// `None` for a camera that is not a pinhole (a thin lens or a parallel projection has
    /// no single point light paths can connect to).
    pub fn new(terms: &CameraTerms, width: usize, height: usize) -> Option<Importance> {
        if !terms.pinhole() {
            return None;
        }
        let (tw, th) = terms.tan_half_fov;
        let c = &terms.camera;
        let w2c = c.c2w.inverse();
        let pixels_per_area = (width * height) as f32 / (4.0 * tw * th);
        (w2c.is_finite() && pixels_per_area.is_finite() && pixels_per_area > 0.0).then_some(Importance {
            pos: c.position,
            w2c,
            tan_half: (tw, th),
            width,
            height,
            nclip: c.nclip,
            fclip: c.fclip,
            pixels_per_area,
        })
    }

    /// The camera ray density (solid angle, per pixel area of the film) of a direction at
    /// `cos` to the camera's axis.
    #[inline]
    pub fn pdf_w(&self, cos: f32) -> f32 {
        self.pixels_per_area / (cos * cos * cos)
    }

    /// The cosine between a camera ray's direction and the camera's axis.
    #[inline]
    pub fn cos_of(&self, dir: Vec3) -> f32 {
        -(self.w2c * dir).z
    }

    /// Where `q` lands on the film, if the camera sees it (in front, within the clipping
    /// distances, inside the image).
    pub fn project(&self, q: Vec3) -> Option<Projection> {
        let d = q - self.pos;
        let dist = d.length();
        if !(dist > self.nclip && dist < self.fclip) {
            return None;
        }
        let c = self.w2c * d;
        if c.z >= 0.0 {
            return None;
        }
        let (x, y) = (c.x / -c.z, c.y / -c.z);
        let px = (x / (2.0 * self.tan_half.0) + 0.5) * self.width as f32;
        let py = (y / (2.0 * self.tan_half.1) + 0.5) * self.height as f32;
        if !(px >= 0.0 && py >= 0.0 && px < self.width as f32 && py < self.height as f32) {
            return None;
        }
        let (ix, iy) = ((px as usize).min(self.width - 1), (py as usize).min(self.height - 1));
        Some(Projection { pixel: iy * self.width + ix, to_camera: -d / dist, dist, cos_camera: -c.z / c.length() })
    }
}
