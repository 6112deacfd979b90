//! The camera's terms a camera ray reads, computed once per render.

use crate::geometry::Ray;
use crate::sampling::{Sampler, warp};
use crate::scene::Camera;
use glam::Vec3;

/// The render's camera (the scene's fitted to the image) and its pinhole terms.
#[derive(Clone, Copy, Debug)]
pub struct CameraTerms {
    pub camera: Camera,
    /// tan(hfov / 2), tan(vfov / 2): the pinhole camera's image-plane half extents, computed
    /// once instead of per camera ray (the same values `Camera::generate_ray` computes).
    pub tan_half_fov: (f32, f32),
}

impl CameraTerms {
    pub fn new(camera: &Camera) -> CameraTerms {
        CameraTerms {
            camera: *camera,
            tan_half_fov: ((camera.hfov_deg.to_radians() * 0.5).tan(), (camera.vfov_deg.to_radians() * 0.5).tan()),
        }
    }

    /// The camera ray through pixel (x, y) drawing from `rng`, the path's stream at depth 0:
    /// jittered inside the pixel (its centre when there is one sample per pixel, as the
    /// reference does), through the thin lens when the camera has an aperture.
    #[inline]
    pub fn ray(&self, x: u32, y: u32, width: usize, height: usize, mut rng: Sampler, spp: u32) -> Ray {
        let (jx, jy) = if spp <= 1 { (0.5, 0.5) } else { rng.next_2d() };
        let cam = &self.camera;
        if cam.lens_radius > 0.0 || cam.orthographic {
            let (px, py) = ((x as f32 + jx) / width as f32, (y as f32 + jy) / height as f32);
            let mut lr = rng.at(2);
            let (a, b) = lr.next_2d();
            cam.generate_lens_ray(px, py, warp::concentric_disk(a, b))
        } else {
            self.pinhole_ray(x, y, width, height, jx, jy)
        }
    }

    /// Whether camera rays are [`pinhole_ray`](Self::pinhole_ray)s (no aperture, not
    /// orthographic).
    #[inline]
    pub fn pinhole(&self) -> bool {
        self.camera.lens_radius <= 0.0 && !self.camera.orthographic
    }

    /// The pinhole camera's ray through (x + jx, y + jy): `Camera::generate_ray` with the
    /// field of view's tangents precomputed. Branch-free, so a loop over lanes vectorises.
    #[inline(always)]
    pub fn pinhole_ray(&self, x: u32, y: u32, width: usize, height: usize, jx: f32, jy: f32) -> Ray {
        let (px, py) = ((x as f32 + jx) / width as f32, (y as f32 + jy) / height as f32);
        let cam = &self.camera;
        let (tw, th) = self.tan_half_fov;
        let d = Vec3::new((px - 0.5) * 2.0 * tw, (py - 0.5) * 2.0 * th, -1.0);
        Ray { origin: cam.position, dir: (cam.c2w * d).normalize(), tmin: cam.nclip, tmax: cam.fclip }
    }
}
