//! Standard ray sets of a scene, as `wavepath rays dump` writes them for the peers' harness: the renderer's own camera rays or first diffuse
//! bounces.
use crate::accel::{Intersector, TraceCounters};
use crate::geometry::Ray;
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::settings::ImageSettings;
use glam::Vec3;
use rayon::prelude::*;

/// Camera rays through pixel centres, row-major from the bottom-left (as the renderer
/// generates them), through the camera a render of a `w x h` image with the default
/// field-of-view rule sees through ([`ImageSettings::camera`]).
pub fn primary_rays(scene: &Scene, w: usize, h: usize) -> Vec<Ray> {
    let image = ImageSettings { width: w, height: h, ..ImageSettings::default() };
    let cam = image.camera(&scene.camera);
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            cam.generate_ray((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32)
        })
        .collect()
}

/// Moves a surface point off the surface along `n` by 1e-5 of the point's magnitude: the
/// simple rule of the peers' own ray generator, kept so dumped ray files stay comparable
/// (the renderer uses the error-bound offsets of `geometry::offset`).
fn relative_offset(p: Vec3, n: Vec3) -> Vec3 {
    let scale = p.abs().max_element().max(1e-6);
    p + n * (scale * 1e-5)
}

/// A cosine-distributed direction about the unit normal `n`.
pub fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    let (t, b) = n.any_orthonormal_pair();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()).normalize()
}

/// One diffuse bounce for every primary ray that hits, in primary order: cosine-distributed
/// about the geometric normal turned toward the incoming ray; random numbers from
/// `Sampler::for_sample(seed, primary ray index, 0)`.
pub fn diffuse_rays(scene: &Scene, accel: &dyn Intersector, primary: &[Ray], seed: u64) -> Vec<Ray> {
    primary
        .par_iter()
        .enumerate()
        .filter_map(|(i, ray)| {
            let mut c = TraceCounters::default();
            let hit = accel.closest_hit(ray, &mut c)?;
            let sp = scene.surface_point(ray, &hit);
            let mut n = sp.geometric_normal;
            if n.dot(ray.dir) > 0.0 {
                n = -n;
            }
            let (u1, u2) = Sampler::for_sample(seed, i as u64, 0).next_2d();
            Some(Ray::new(relative_offset(sp.position, n), cosine_direction(n, u1, u2)))
        })
        .collect()
}
