//! Thin-lens depth of field (CS184 `-b R -d D`): the camera-space plane z = -D is in focus.
//!
//! A point at depth d is seen by the pixels whose focus points F satisfy F = P D/d +
//! L (1 - D/d) for lens points L on the disk of radius R: a disk of radius
//! c = R |d - D| / d on the focal plane (the circle of confusion), which is
//! c / (D tan(vfov/2)) * (H/2) pixels. The test renders a small emitting sphere on a black
//! background and measures its image's spread: the second moment about the centroid of a
//! sharp image convolved with a uniform disk of radius r grows by exactly r^2 / 2, so
//! r = sqrt(2 (M_R - M_0)) with M_0 the pinhole image's moment.

use crate::accel::BruteForce;
use crate::scene::{Camera, Material, Scene, Sphere};
use crate::settings::{Settings, Shading};
use glam::{DVec2, Vec3};

const N: usize = 48;
const VFOV: f32 = 10.0;

/// (centroid, second moment about it in pixels^2) of an emitter of radius `rho` at depth
/// `d`, rendered with lens radius `r` and focal distance `focus`.
fn image_moments(d: f32, rho: f32, r: f32, focus: f32) -> (DVec2, f64) {
    let mut camera = Camera::look_at(Vec3::ZERO, -Vec3::Z, Vec3::Y, VFOV, 1.0);
    camera.lens_radius = r;
    camera.focal_distance = focus;
    let scene = Scene {
        name: "lens".into(),
        spheres: vec![Sphere { center: Vec3::new(0.0, 0.0, -d), radius: rho, material: 0 }],
        materials: vec![Material::emitter("light", Vec3::ONE)],
        camera,
        ..Scene::default()
    };
    // Depth 0: emission seen by camera rays only.
    let mut s = Settings::default();
    s.image.width = N;
    s.image.height = N;
    s.sampling.spp = 1024;
    s.paths.max_depth = 0;
    s.paths.shading = Shading::Global;
    let (film, _) = crate::render::render(&scene, &BruteForce::new(&scene), &s).unwrap();
    let (mut sum, mut c) = (0.0f64, DVec2::ZERO);
    for y in 0..N {
        for x in 0..N {
            let i = film.get(x, y).y as f64;
            sum += i;
            c += i * DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
        }
    }
    assert!(sum > 0.0, "the emitter is not visible");
    c /= sum;
    let mut m = 0.0;
    for y in 0..N {
        for x in 0..N {
            let i = film.get(x, y).y as f64;
            m += i * (DVec2::new(x as f64 + 0.5, y as f64 + 0.5) - c).length_squared();
        }
    }
    (c, m / sum)
}

/// Circle-of-confusion radius in pixels for a point at depth `d`.
fn coc_pixels(d: f32, r: f32, focus: f32) -> f64 {
    let c = r as f64 * (d - focus).abs() as f64 / d as f64;
    c / (focus as f64 * ((VFOV as f64).to_radians() * 0.5).tan()) * (N as f64 / 2.0)
}

#[test]
fn points_on_the_focal_plane_stay_sharp() {
    let (d, rho) = (6.0, 0.03);
    let (c0, m0) = image_moments(d, rho, 0.0, d);
    for r in [0.1, 0.4] {
        let (c, m) = image_moments(d, rho, r, d);
        // The sphere's own depth (rho) defocuses its rim by at most R rho / d on the focal
        // plane: a fraction of a pixel here, so the footprint stays within 0.15 px^2.
        assert!((m - m0).abs() < 0.15, "R {r}: moment {m} vs pinhole {m0}");
        assert!((c - c0).length() < 0.05, "R {r}: centroid {c} vs {c0}");
    }
}

#[test]
fn points_off_the_focal_plane_blur_by_the_circle_of_confusion() {
    // (depth, emitter radius, lens radius, focal distance): behind and in front of the focal plane.
    for (d, rho, r, focus) in [(10.0, 0.07, 0.2, 5.0), (3.0, 0.02, 0.1, 5.0), (8.0, 0.05, 0.12, 4.0)] {
        let (c0, m0) = image_moments(d, rho, 0.0, focus);
        let (c, m) = image_moments(d, rho, r, focus);
        let measured = (2.0 * (m - m0)).max(0.0).sqrt();
        let expect = coc_pixels(d, r, focus);
        eprintln!("d {d}, R {r}, D {focus}: blur radius {measured:.3} px, circle of confusion {expect:.3} px");
        assert!(expect > 2.0, "the test needs a visible blur ({expect} px)");
        assert!(
            (measured - expect).abs() < 0.05 * expect,
            "d {d}, R {r}, D {focus}: blur radius {measured:.3} px vs circle of confusion {expect:.3} px"
        );
        // On the optical axis the blur is symmetric: the image does not move.
        assert!((c - c0).length() < 0.1, "centroid {c} vs {c0}");
    }
}

/// `thin-lens` is an effect only when the camera has an aperture.
#[test]
fn thin_lens_effect_follows_the_aperture() {
    let mut scene = crate::load::default_scene();
    let s = Settings::default();
    assert!(!crate::effects::Effects::of(&scene, &s).thin_lens);
    scene.camera.lens_radius = 0.1;
    let e = crate::effects::Effects::of(&scene, &s);
    assert!(e.thin_lens && e.names().contains(&"thin-lens"));
}
