//! Renders whose answer is known in closed form: the white furnace, a plane under a point
//! and a directional light, a plane under the hemisphere light, and a plane under an
//! emissive rectangle (form factor), by light sampling and by hemisphere sampling.

use crate::accel::BruteForce;
use crate::film::Accumulator;
use crate::scene::{Camera, Environment, Light, Material, Mesh, Scene, Sphere};
use crate::settings::IntegratorKind;
use crate::settings::Settings;
use crate::tests::common::meshgen::quad;
use crate::tests::common::render::sums_with;
use crate::tests::common::{agree, render};
use glam::{Vec3, vec3};
use std::f32::consts::PI;

const W: usize = 32;
const H: usize = 24;

/// A square on y = `y`, side 2 `half`, centred on the y axis.
fn floor(mesh: &mut Mesh, half: f32, y: f32, m: u32) {
    quad(mesh, [vec3(-half, y, -half), vec3(-half, y, half), vec3(half, y, half), vec3(half, y, -half)], m);
}

fn settings(max_depth: u32, spp: u32) -> Settings {
    render::settings(W, H, max_depth, spp)
}

fn render(scene: &Scene, s: &Settings) -> Accumulator {
    let (acc, st) = sums_with(IntegratorKind::Wavefront, scene, &BruteForce::new(scene), s, &|_| {});
    assert_eq!(st.invalid_samples, 0);
    acc
}

/// Every 8x8 region agrees with the expected pixel values (the shared z-test; 1e-4 of
/// slack for f32 against the f64 formulas).
fn assert_regions(acc: &Accumulator, expected: impl Fn(usize, usize) -> Option<Vec3>, what: &str) {
    agree::assert_regions_match(acc, 8, |x, y| expected(x, y).map(|e| e.as_dvec3()), 1e-4, what);
}

/// The point of y = 0 seen through the centre of pixel (x, y), if it is on the square of half-side `half`.
fn floor_point(cam: &Camera, x: usize, y: usize, half: f32) -> Option<Vec3> {
    let r = cam.generate_ray((x as f32 + 0.5) / W as f32, (y as f32 + 0.5) / H as f32);
    let t = -r.origin.y / r.dir.y;
    let p = r.origin + t * r.dir;
    (t > 0.0 && p.x.abs() < half * 0.999 && p.z.abs() < half * 0.999).then_some(p)
}

fn look_down(height: f32, vfov: f32) -> Camera {
    let mut cam = Camera::look_at(vec3(0.0, height, 0.5), Vec3::ZERO, Vec3::Y, vfov, W as f32 / H as f32);
    cam.nclip = 0.01;
    cam
}

#[test]
fn white_furnace_converges_to_the_environment() {
    let mut mesh = Mesh::default();
    floor(&mut mesh, 2.0, -1.0, 0);
    let scene = Scene {
        name: "furnace".into(),
        mesh,
        spheres: vec![Sphere { center: Vec3::ZERO, radius: 1.0, material: 0 }],
        materials: vec![Material::diffuse("white", Vec3::ONE)],
        camera: Camera::look_at(vec3(0.0, 2.0, 5.0), vec3(0.0, -0.5, 0.0), Vec3::Y, 50.0, W as f32 / H as f32),
        env: Environment::Constant(Vec3::splat(0.5)),
        ..Scene::default()
    };
    for rr in [0.65, 1.0] {
        let mut s = settings(64, 32);
        s.paths.roulette.continue_prob = rr;
        s.sampling.light_samples = 1;
        let acc = render(&scene, &s);
        assert_regions(&acc, |_, _| Some(Vec3::splat(0.5)), &format!("furnace --rr {rr}"));
        // Also per pixel, loosely: no pixel is far from 0.5.
        for p in &acc.pixels {
            let m = p.mean();
            let sd = p.variance_of_mean().x.sqrt() as f32;
            assert!((m.x - 0.5).abs() <= 6.0 * sd + 1e-4, "pixel {m} sd {sd}");
        }
    }
}

fn plane_scene(light: Light, albedo: f32) -> Scene {
    let mut mesh = Mesh::default();
    floor(&mut mesh, 10.0, 0.0, 0);
    Scene {
        name: "plane".into(),
        mesh,
        materials: vec![Material::diffuse("grey", Vec3::splat(albedo))],
        lights: vec![light],
        camera: look_down(6.0, 60.0),
        ..Scene::default()
    }
}

/// The reference's point light has no distance falloff: L = albedo / pi * I * cos(theta).
#[test]
fn plane_under_a_point_light() {
    let pos = vec3(0.3, 2.0, -0.2);
    let scene =
        plane_scene(Light::Point { position: pos, intensity: vec3(3.0, 2.0, 1.0), attenuation: [1.0, 0.0, 0.0] }, 0.5);
    let expect = |x, y| {
        floor_point(&scene.camera, x, y, 10.0).map(|p| {
            let cos = (pos.y - p.y) / (pos - p).length();
            0.5 / PI * vec3(3.0, 2.0, 1.0) * cos
        })
    };
    let acc = render(&scene, &settings(1, 1));
    let mut checked = 0;
    for y in 0..H {
        for x in 0..W {
            if let Some(e) = expect(x, y) {
                let got = acc.pixels[y * W + x].mean();
                assert!((got - e).abs().max_element() <= 2e-4 * e.max_element(), "({x},{y}): {got} vs {e}");
                checked += 1;
            }
        }
    }
    assert!(checked > W * H / 2);
    // Nothing can bounce twice off a single plane: -m 2 -o 0 is black, -m 2 -o 1 equals -m 1.
    let only_second = render(&scene, &settings(2, 4).with(|s| s.paths.accumulate = false));
    assert!(only_second.pixels.iter().all(|p| p.mean() == Vec3::ZERO));
    let both = render(&scene, &settings(2, 1));
    for (a, b) in both.pixels.iter().zip(&acc.pixels) {
        assert!((a.mean() - b.mean()).abs().max_element() <= 1e-5 * b.mean().max_element().max(1.0));
    }
}

#[test]
fn plane_under_a_directional_light() {
    let dir = vec3(0.6, -0.8, 0.0);
    let scene = plane_scene(Light::Directional { direction: dir, radiance: Vec3::splat(2.0) }, 0.5);
    let acc = render(&scene, &settings(1, 1));
    let e = 0.5 / PI * 2.0 * 0.8;
    for y in 0..H {
        for x in 0..W {
            if floor_point(&scene.camera, x, y, 10.0).is_some() {
                let got = acc.pixels[y * W + x].mean();
                assert!((got.x - e).abs() < 1e-5, "({x},{y}): {got} vs {e}");
            }
        }
    }
}

/// Upward plane under the hemisphere light: E = pi L, radiance albedo L, by both strategies;
/// the sky itself stays black to the camera, as in the reference.
#[test]
fn plane_under_the_hemisphere_light() {
    let scene = plane_scene(Light::Hemisphere { radiance: Vec3::splat(1.5) }, 0.6);
    let expect = |x, y| floor_point(&scene.camera, x, y, 10.0).map(|_| Vec3::splat(0.9));
    let importance = render(&scene, &settings(1, 16));
    assert_regions(&importance, expect, "hemisphere light, light sampling");
    let hemi = render(
        &scene,
        &settings(1, 64).with(|s| {
            s.paths.hemisphere = true;
            s.sampling.light_samples = 4
        }),
    );
    assert_regions(&hemi, expect, "hemisphere light, hemisphere sampling");
    // A camera looking at the sky sees black.
    let mut up = scene.clone();
    up.camera = Camera::look_at(vec3(0.0, 1.0, 0.0), vec3(0.0, 5.0, 0.3), Vec3::Y, 40.0, 4.0 / 3.0);
    assert!(render(&up, &settings(1, 1)).pixels.iter().all(|p| p.mean() == Vec3::ZERO));
}

/// A plane under an emissive rectangle (no area light: the emissive triangles are the
/// light): radiance = albedo * Le * F, with F the rectangle's form factor; light sampling and
/// hemisphere sampling both converge to it.
#[test]
fn plane_under_an_emissive_rectangle() {
    let (x0, x1, z0, z1, h, le, albedo) = (-0.5f32, 0.7f32, -0.4f32, 0.6f32, 1.0f32, 4.0f32, 0.8f32);
    let mut mesh = Mesh::default();
    floor(&mut mesh, 10.0, 0.0, 0);
    quad(&mut mesh, [vec3(x0, h, z0), vec3(x1, h, z0), vec3(x1, h, z1), vec3(x0, h, z1)], 1);
    let scene = Scene {
        name: "emitter".into(),
        mesh,
        materials: vec![Material::diffuse("grey", Vec3::splat(albedo)), Material::emitter("light", Vec3::splat(le))],
        camera: look_down(0.9, 20.0),
        ..Scene::default()
    };
    let expect = |x, y| {
        floor_point(&scene.camera, x, y, 10.0).map(|p| {
            let f = |cx: f32, cz: f32| {
                crate::tests::common::corner_form_factor((cx - p.x) as f64, (cz - p.z) as f64, h as f64)
            };
            let ff = f(x1, z1) - f(x0, z1) - f(x1, z0) + f(x0, z0);
            Vec3::splat(albedo * le * ff as f32)
        })
    };
    // The camera sits under the emitter, so every pixel sees the floor.
    assert!((0..H).all(|y| (0..W).all(|x| expect(x, y).is_some())));
    let importance = render(&scene, &settings(1, 16).with(|s| s.sampling.light_samples = 4));
    assert_regions(&importance, expect, "emitter, light sampling");
    let hemi = render(
        &scene,
        &settings(1, 64).with(|s| {
            s.paths.hemisphere = true;
            s.sampling.light_samples = 8
        }),
    );
    assert_regions(&hemi, expect, "emitter, hemisphere sampling");
    let reference = sums_with(
        IntegratorKind::Recursive,
        &scene,
        &BruteForce::new(&scene),
        &settings(1, 64).with(|s| {
            s.paths.hemisphere = true;
            s.sampling.light_samples = 8
        }),
        &|_| {},
    )
    .0;
    assert_regions(&reference, expect, "emitter, recursive hemisphere sampling");
}
