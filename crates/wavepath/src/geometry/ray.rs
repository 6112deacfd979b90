//! Rays and hits: the vocabulary shared by the camera, the accelerators and the stages.

use glam::Vec3;

/// A ray segment `origin + t * dir` for `t` in `[tmin, tmax]`.
///
/// `dir` need not be normalised: `t` is always in units of `dir`, as in the ray-file format.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub tmin: f32,
    pub tmax: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Ray { origin, dir, tmin: 0.0, tmax: f32::INFINITY }
    }

    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// The closest intersection found along a ray.
///
/// `prim` numbers triangles first (their index in `Mesh::triangles`), then spheres
/// (`triangle_count + sphere index`). `u`, `v` are the barycentric coordinates of the hit
/// on a triangle (weights of corners 1 and 2); unused for spheres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}
