//! Rendered behaviour of the non-diffuse materials: a glass sphere in a uniform environment
//! is invisible, a mirror shows the mirrored scene, and the wavefront integrator agrees with
//! the recursive reference for every material.

use crate::film::Accumulator;
use crate::load::default_scene;
use crate::scene::{Bsdf, Camera, Environment, Light, Material, Mesh, Scene, Sphere};
use crate::settings::{Settings, Shading};
use crate::tests::common;
use crate::tests::common::agree::assert_regions_agree;
use crate::tests::common::meshgen::quad;
use glam::{Vec3, vec3};

fn wavefront(scene: &Scene, s: &Settings) -> Accumulator {
    let (acc, st) = common::render::wavefront(scene, s);
    assert_eq!(st.invalid_samples, 0);
    acc
}

fn recursive(scene: &Scene, s: &Settings) -> Accumulator {
    let (acc, st) = common::render::recursive(scene, s);
    assert_eq!(st.invalid_samples, 0);
    acc
}

fn settings(w: usize, h: usize, spp: u32, max_depth: u32) -> Settings {
    common::render::small_settings(w, h, max_depth, spp)
}

fn glass(ior: f32) -> Bsdf {
    Bsdf::Glass { reflectance: Vec3::ONE, transmittance: Vec3::ONE, roughness: 0.0, ior }
}

/// Every path through clear glass reflects or refracts with weight 1 (the 1 / eta^2 of
/// entering is undone by eta^2 on leaving), so in a uniform environment every sample that
/// escapes sees exactly the environment's radiance: the sphere vanishes.
#[test]
fn glass_sphere_in_a_uniform_environment_is_invisible() {
    let c = vec3(0.3, 0.5, 0.7);
    for bsdf in [glass(1.5), glass(2.4)] {
        let scene = Scene {
            name: "glass furnace".into(),
            spheres: vec![Sphere { center: Vec3::ZERO, radius: 1.0, material: 0 }],
            materials: vec![Material { bsdf: bsdf.clone(), ..Material::diffuse("glass", Vec3::ONE) }],
            camera: Camera::look_at(vec3(0.0, 0.5, 3.0), Vec3::ZERO, Vec3::Y, 50.0, 1.0),
            env: Environment::Constant(c),
            ..Scene::default()
        };
        let mut s = settings(24, 24, 8, 64);
        s.paths.roulette.continue_prob = 1.0;
        for acc in [wavefront(&scene, &s), recursive(&scene, &s)] {
            for p in &acc.pixels {
                // A path still inside after 64 bounces would be dark; allow a few.
                assert!((p.mean() - c).abs().max_element() < 0.03, "{bsdf:?}: pixel {}", p.mean());
            }
            let mean: Vec3 = acc.pixels.iter().map(|p| p.mean()).sum::<Vec3>() / acc.pixels.len() as f32;
            assert!((mean - c).abs().max_element() < 1e-3, "{bsdf:?}: image mean {mean}");
        }
    }
}

/// A camera looking straight down at a mirror floor sees exactly what the same camera sees
/// with the mirror removed and the scene above it reflected below y = 0: a diffuse sphere lit
/// by a point light (deterministic direct light, one sample at the pixel centre) and an
/// emissive sphere (emission seen through the mirror).
#[test]
fn mirror_shows_the_mirrored_scene() {
    let flip = |v: Vec3| vec3(v.x, -v.y, v.z);
    let (diffuse_c, emit_c, light_p) = (vec3(0.5, 3.0, 0.3), vec3(-0.6, 2.5, -0.2), vec3(0.3, 1.5, -0.5));
    let materials = vec![
        Material { bsdf: Bsdf::Mirror { reflectance: Vec3::ONE }, ..Material::diffuse("mirror", Vec3::ONE) },
        Material::diffuse("grey", vec3(0.7, 0.5, 0.3)),
        Material::emitter("glow", vec3(2.0, 1.0, 0.5)),
    ];
    let camera = Camera::look_at(vec3(0.0, 1.0, 0.0), Vec3::ZERO, Vec3::Z, 60.0, 1.0);
    let scene = |mirrored: bool| {
        let m = |v: Vec3| if mirrored { flip(v) } else { v };
        let mut mesh = Mesh::default();
        if !mirrored {
            let s = 20.0;
            quad(&mut mesh, [vec3(-s, 0.0, -s), vec3(-s, 0.0, s), vec3(s, 0.0, s), vec3(s, 0.0, -s)], 0);
        }
        Scene {
            name: "mirror".into(),
            mesh,
            spheres: vec![
                Sphere { center: m(diffuse_c), radius: 0.4, material: 1 },
                Sphere { center: m(emit_c), radius: 0.3, material: 2 },
            ],
            materials: materials.clone(),
            lights: vec![Light::Point {
                position: m(light_p),
                intensity: Vec3::splat(3.0),
                attenuation: [1.0, 0.0, 0.0],
            }],
            camera,
            ..Scene::default()
        }
    };
    // Through the mirror the sphere is one bounce further: -m 2 against -m 1.
    let a = wavefront(&scene(false), &settings(48, 48, 1, 2).with(|s| s.paths.shading = Shading::Global));
    let b = wavefront(&scene(true), &settings(48, 48, 1, 1));
    let (mut lit, mut glowing, mut off) = (0, 0, 0);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let (p, q) = (p.mean(), q.mean());
        if (p - q).abs().max_element() > 1e-3 * q.max_element().max(1.0) {
            off += 1;
        }
        if q.x > 1.9 {
            glowing += 1;
        } else if q.x > 0.0 {
            lit += 1;
        }
    }
    assert!(lit > 20 && glowing > 20, "the test sees both spheres ({lit} lit, {glowing} glowing pixels)");
    // Sphere silhouettes may differ by rounding in a pixel or two.
    assert!(off <= 4, "{off} pixels differ between the mirror and the mirrored scene");
    // The same through the recursive reference.
    let c = recursive(&scene(false), &settings(48, 48, 1, 2).with(|s| s.paths.shading = Shading::Global));
    let off = c.pixels.iter().zip(&a.pixels).filter(|(p, q)| (p.mean() - q.mean()).abs().max_element() > 1e-5).count();
    assert_eq!(off, 0);
}

/// The default Cornell box with its two spheres made of `m` (and `m2`).
fn box_with(m: Bsdf, m2: Bsdf) -> Scene {
    let mut scene = default_scene();
    let id = scene.materials.len() as u32;
    scene.materials.push(Material { bsdf: m, ..Material::diffuse("a", Vec3::ONE) });
    scene.materials.push(Material { bsdf: m2, ..Material::diffuse("b", Vec3::ONE) });
    scene.spheres[0].material = id;
    scene.spheres[1].material = id + 1;
    scene
}

fn compare(scene: &Scene, s: &Settings, what: &str) {
    let a = wavefront(scene, s);
    let b = recursive(scene, &s.clone().with(|t| t.sampling.seed = s.sampling.seed + 1000));
    let z = assert_regions_agree(&a, &b, 8, 0.0, what);
    eprintln!("{what}: worst |z| = {z:.2}");
}

#[test]
fn wavefront_agrees_with_recursive_for_every_material() {
    let mirror = Bsdf::Mirror { reflectance: vec3(0.9, 0.9, 0.8) };
    let refraction = Bsdf::Refraction { transmittance: Vec3::ONE, roughness: 0.0, ior: 1.5 };
    let metal = |alpha| Bsdf::Microfacet { alpha, eta: vec3(0.2, 0.9, 1.1), k: vec3(3.9, 2.4, 2.2) };
    let phong = |ks, ns| Bsdf::Phong { diffuse: vec3(0.6, 0.4, 0.3), specular: Vec3::splat(ks), shininess: ns };
    let cases = [
        ("mirror + glass", box_with(mirror, glass(1.5))),
        ("refraction + rough metal", box_with(refraction, metal(0.25))),
        ("smooth + rough metal", box_with(metal(0.05), metal(0.5))),
        ("sharp + rough Phong", box_with(phong(0.3, 1000.0), phong(0.5, 10.0))),
    ];
    for (what, scene) in &cases {
        for (depth, spp) in [(1, 32), (4, 64)] {
            compare(scene, &settings(32, 24, spp, depth), &format!("{what} -m {depth}"));
        }
        let mut s = settings(32, 24, 64, 3);
        s.paths.accumulate = false;
        compare(scene, &s, &format!("{what} -m 3 -o 0"));
        let mut s = settings(32, 24, 64, 3);
        s.paths.hemisphere = true;
        compare(scene, &s, &format!("{what} -H -m 3"));
    }
}

/// `--all-effects` forces the non-diffuse kernel onto a Lambertian scene: same image.
#[test]
fn all_effects_keep_a_lambertian_image() {
    let scene = default_scene();
    let s = settings(32, 24, 4, 4);
    let a = wavefront(&scene, &s);
    let b = wavefront(&scene, &s.clone().with(|s| s.execution.all_effects = true));
    assert_eq!(a.to_film(), b.to_film());
}
