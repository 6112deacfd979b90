//! The standard ray sets of a scene (what `wavepath rays dump` writes): their diffuse
//! bounces follow the cosine density.

use crate::tests::common::meshgen::scene_of;
use crate::{Bvh, diffuse_rays, primary_rays};
use glam::Vec3;

/// The diffuse rays of a plane facing the camera: directions by chi-square against
/// cos(theta) / pi about its normal (p-value threshold 1e-3 of `common::chi2`, fixed seed).
#[test]
fn diffuse_rays_follow_the_cosine_density() {
    let mut mesh = wavepath::Mesh::default();
    let h = 10.0;
    crate::tests::common::meshgen::quad(
        &mut mesh,
        [Vec3::new(-h, -h, 0.0), Vec3::new(h, -h, 0.0), Vec3::new(h, h, 0.0), Vec3::new(-h, h, 0.0)],
        0,
    );
    let mut scene = scene_of(mesh, vec![]);
    scene.camera = wavepath::Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 40.0, 1.0);
    let bvh = Bvh::build(&scene);
    let primary = primary_rays(&scene, 640, 640);
    let diffuse = diffuse_rays(&scene, &bvh, &primary, 11);
    assert_eq!(diffuse.len(), primary.len(), "the plane fills the view");
    let mut dirs = diffuse.iter().map(|r| r.dir.normalize().as_dvec3());
    crate::tests::common::chi2::chi_square("diffuse rays", 0, |_| dirs.next(), &|d| {
        d.z.max(0.0) / std::f64::consts::PI
    });
}
