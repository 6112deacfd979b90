//! Output variables against what the scene says they are: a Lambertian plane's albedo is its
//! Kd, its normal the plane's, its depth the distance from the eye to the point each ray hit;
//! a mirror shows the albedo of what it reflects; the variance of a noiseless render is zero
//! and that of a known estimator its closed form; the same bits for any thread count and
//! instruction set; nothing kept, no stage run, when no variable is asked for.

use crate::accel::BruteForce;
use crate::choice::Choice;
use crate::cpu::Isa;
use crate::film::AovImage;
use crate::render::{RenderOutput, render_with_progress};
use crate::sampling::SamplerKind;
use crate::scene::Texture;
use crate::scene::texture::{Filter, TextureImage, Wrap};
use crate::scene::{Bsdf, Camera, Environment, Material, Mesh, Scene, Sphere};
use crate::settings::{Aov, AovSet, IntegratorKind, Settings};
use crate::tests::common::meshgen::quad;
use crate::tests::common::render::settings;
use glam::{Vec2, Vec3, vec3};
use std::sync::Arc;

const W: usize = 32;
const H: usize = 24;
const KD: Vec3 = vec3(0.2, 0.5, 0.7);

fn all() -> AovSet {
    Aov::ALL.iter().fold(AovSet::NONE, |s, &a| s.with(a))
}

fn render(scene: &Scene, s: &Settings) -> RenderOutput {
    let out = render_with_progress(scene, &BruteForce::new(scene), s, &|_| {}).expect("renders");
    assert_eq!(out.stats.invalid_samples, 0);
    for a in &out.aovs {
        assert!(a.data.iter().all(|v| v.is_finite()), "{:?} holds a NaN or Inf", a.aov);
    }
    out
}

fn aov(out: &RenderOutput, a: Aov) -> &AovImage {
    out.aovs.iter().find(|i| i.aov == a).expect("the variable asked for")
}

fn v3(p: &[f32]) -> Vec3 {
    Vec3::new(p[0], p[1], p[2])
}

/// The floor y = 0 (side 4, Kd `KD`) seen from above under a constant sky.
fn floor_scene() -> Scene {
    let mut mesh = Mesh::default();
    quad(&mut mesh, [vec3(-2.0, 0.0, -2.0), vec3(-2.0, 0.0, 2.0), vec3(2.0, 0.0, 2.0), vec3(2.0, 0.0, -2.0)], 0);
    let mut camera = Camera::look_at(vec3(0.0, 1.5, 0.5), Vec3::ZERO, Vec3::Y, 60.0, W as f32 / H as f32);
    camera.nclip = 0.01;
    Scene {
        name: "floor".into(),
        mesh,
        materials: vec![Material::diffuse("floor", KD)],
        camera,
        env: Environment::Constant(Vec3::ONE),
        ..Scene::default()
    }
}

/// The floor's point seen through (u, v) of the image, if on the floor.
fn floor_point(cam: &Camera, u: f32, v: f32) -> Option<Vec3> {
    let r = cam.generate_ray(u, v);
    let t = -r.origin.y / r.dir.y;
    let p = r.origin + t * r.dir;
    (t > 0.0 && p.x.abs() < 1.99 && p.z.abs() < 1.99).then_some(p)
}

/// The floor points at pixel (x, y)'s corners, when the whole pixel sees the floor.
fn pixel_corners(cam: &Camera, x: usize, y: usize) -> Option<Vec<Vec3>> {
    let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
    corners.iter().map(|(dx, dy)| floor_point(cam, (x as f32 + dx) / W as f32, (y as f32 + dy) / H as f32)).collect()
}

#[test]
fn a_lambertian_plane_gives_its_albedo_normal_depth_and_position() {
    let scene = floor_scene();
    let cam = scene.camera;
    // One sample per pixel: each pixel's depth is then the distance to its own position.
    for spp in [1, 4] {
        let s = settings(W, H, 2, spp).with(|s| s.image.aovs = all());
        let out = render(&scene, &s);
        let mut seen = 0;
        for y in 0..H {
            for x in 0..W {
                let Some(corners) = pixel_corners(&cam, x, y) else { continue };
                seen += 1;
                assert_eq!(v3(aov(&out, Aov::Albedo).get(x, y)), KD, "albedo at ({x}, {y})");
                assert_eq!(v3(aov(&out, Aov::Normal).get(x, y)), Vec3::Y, "normal at ({x}, {y})");
                let p = v3(aov(&out, Aov::Position).get(x, y));
                let d = aov(&out, Aov::Depth).get(x, y)[0];
                assert!(p.y.abs() < 1e-5, "position {p} off the plane");
                let (lo, hi) = corners.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), c| (lo.min(*c), hi.max(*c)));
                let slack = Vec3::splat(1e-4);
                assert!(p.cmpge(lo - slack).all() && p.cmple(hi + slack).all(), "({x}, {y}): {p} outside {lo}..{hi}");
                let dists: Vec<f32> = corners.iter().map(|c| (*c - cam.position).length()).collect();
                let (dmin, dmax) = dists.iter().fold((f32::MAX, f32::MIN), |(a, b), &d| (a.min(d), b.max(d)));
                assert!(d >= dmin * 0.999 && d <= dmax * 1.001, "({x}, {y}): depth {d} outside {dmin}..{dmax}");
                if spp == 1 {
                    let e = (p - cam.position).length();
                    assert!((d - e).abs() <= 1e-5 * e, "({x}, {y}): depth {d}, distance to the hit {e}");
                }
            }
        }
        assert!(seen > W * H / 2, "the floor fills most of the image ({seen} pixels)");
    }
}

#[test]
fn a_mirror_shows_the_albedo_and_normal_of_what_it_reflects() {
    // The camera at z = 2 looks at a mirror on z = 0; behind the camera, on z = 5, a textured
    // wall: a 2x1 image, red on the left (x < 0) and blue on the right, nearest texel. Each
    // pixel's reflected ray reaches the half on its own side, so its albedo is that texel's.
    let (red, blue) = (vec3(0.9, 0.1, 0.1), vec3(0.1, 0.2, 0.8));
    let mut mesh = Mesh::default();
    quad(&mut mesh, [vec3(-3.0, -3.0, 0.0), vec3(3.0, -3.0, 0.0), vec3(3.0, 3.0, 0.0), vec3(-3.0, 3.0, 0.0)], 0);
    quad(
        &mut mesh,
        [vec3(-20.0, -20.0, 5.0), vec3(20.0, -20.0, 5.0), vec3(20.0, 20.0, 5.0), vec3(-20.0, 20.0, 5.0)],
        1,
    );
    mesh.uvs = Some(vec![
        Vec2::ZERO,
        Vec2::ZERO,
        Vec2::ZERO,
        Vec2::ZERO,
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ]);
    let image = TextureImage { width: 2, height: 1, texels: vec![red, blue] };
    let texture = Texture {
        path: "wall.png".into(),
        image: Some(Arc::new(image)),
        wrap: [Wrap::ClampToEdge; 2],
        filter: Filter::Nearest,
        flip_v: false,
        factor: Vec3::ONE,
        transform: glam::Affine2::IDENTITY,
    };
    let wall = Material { albedo_texture: Some(texture), ..Material::diffuse("wall", Vec3::splat(0.5)) };
    let mirror = Material { bsdf: Bsdf::Mirror { reflectance: Vec3::ONE }, ..Material::diffuse("mirror", Vec3::ONE) };
    let mut camera = Camera::look_at(vec3(0.0, 0.0, 2.0), Vec3::ZERO, Vec3::Y, 50.0, W as f32 / H as f32);
    camera.nclip = 0.01;
    let scene = Scene {
        name: "mirror".into(),
        mesh,
        materials: vec![mirror, wall],
        camera,
        env: Environment::Constant(Vec3::ONE),
        ..Scene::default()
    };
    let s = settings(W, H, 3, 4).with(|s| s.image.aovs = all());
    let out = render(&scene, &s);
    for y in 0..H {
        for x in (0..W).filter(|&x| x + 1 < W / 2 || x > W / 2) {
            let want = if x < W / 2 { red } else { blue };
            assert_eq!(v3(aov(&out, Aov::Albedo).get(x, y)), want, "albedo at ({x}, {y})");
            assert_eq!(v3(aov(&out, Aov::Normal).get(x, y)), -Vec3::Z, "normal at ({x}, {y})");
            // Depth and position are the mirror's, the camera ray's own hit.
            let p = v3(aov(&out, Aov::Position).get(x, y));
            assert!(p.z.abs() < 1e-5, "({x}, {y}): position {p} is not on the mirror");
            let d = aov(&out, Aov::Depth).get(x, y)[0];
            // 2 on the axis, 2 / cos at the corners (1.25 for this field of view).
            assert!((2.0..2.0 * 1.3).contains(&d), "({x}, {y}): depth {d}");
        }
    }
}

#[test]
fn variance_is_zero_without_noise_and_matches_a_known_estimator() {
    // Only the sky: every sample is the same.
    let mut sky = floor_scene();
    sky.mesh = Mesh::default();
    sky.env = Environment::Constant(Vec3::splat(0.7));
    let s = settings(W, H, 2, 16).with(|s| s.image.aovs = AovSet::NONE.with(Aov::Variance));
    let out = render(&sky, &s);
    assert!(aov(&out, Aov::Variance).data.iter().all(|&v| v == 0.0));
    assert!(out.stats.stages.aov.is_none(), "the variance needs no first-hit stage");

    // The floor under a unit sky by uniform hemisphere samples, direct light only: each
    // sample is 2 Kd cos(theta) with cos(theta) uniform on [0, 1], so the samples' variance
    // is Kd^2 / 3 and that of an n-sample mean Kd^2 / (3 n).
    let n = 64u32;
    let s = settings(W, H, 1, n).with(|s| {
        s.image.aovs = AovSet::NONE.with(Aov::Variance);
        s.paths.hemisphere = true;
        s.sampling.sampler = SamplerKind::Independent;
    });
    let scene = floor_scene();
    let out = render(&scene, &s);
    let want = KD * KD / (3.0 * n as f32);
    // The sample variance of n independent samples of 2 U (kurtosis 9/5) has relative standard
    // deviation sqrt((9/5 - 1) / n + 2 / (n (n - 1))) per pixel.
    let rel_sd = (0.8 / n as f32 + 2.0 / (n * (n - 1)) as f32).sqrt();
    let (mut sum, mut count) = (Vec3::ZERO, 0);
    for y in 0..H {
        for x in 0..W {
            if pixel_corners(&scene.camera, x, y).is_none() {
                continue;
            }
            let v = v3(aov(&out, Aov::Variance).get(x, y));
            let z = ((v - want) / (want * rel_sd)).abs();
            assert!(z.max_element() < 6.0, "({x}, {y}): variance {v}, expected {want} (z {z})");
            sum += v;
            count += 1;
        }
    }
    let mean = sum / count as f32;
    let z = ((mean - want) / (want * rel_sd / (count as f32).sqrt())).abs();
    assert!(z.max_element() < 5.0, "mean variance {mean} over {count} pixels, expected {want} (z {z})");
}

#[test]
fn output_variables_are_the_same_bits_for_any_thread_count_and_instruction_set() {
    // Glass, a mirror, a glossy, a metallic-roughness and a rough conductor sphere on a diffuse
    // floor: delta chains of both kinds, and every model the lanes record from their points.
    let mut scene = floor_scene();
    scene.materials.extend([
        Material {
            bsdf: Bsdf::Glass { reflectance: Vec3::ONE, transmittance: Vec3::ONE, ior: 1.5, roughness: 0.0 },
            ..Material::diffuse("glass", Vec3::ONE)
        },
        Material { bsdf: Bsdf::Mirror { reflectance: Vec3::splat(0.9) }, ..Material::diffuse("mirror", Vec3::ONE) },
        Material {
            bsdf: Bsdf::Phong { diffuse: KD, specular: Vec3::splat(0.3), shininess: 40.0 },
            ..Material::diffuse("glossy", Vec3::ONE)
        },
        Material {
            bsdf: Bsdf::MetallicRoughness { base: KD, metallic: 0.4, roughness: 0.3 },
            ..Material::diffuse("pbr", Vec3::ONE)
        },
        Material {
            bsdf: Bsdf::Microfacet { alpha: 0.2, eta: vec3(0.2, 0.9, 1.1), k: vec3(3.9, 2.4, 2.2) },
            ..Material::diffuse("gold", Vec3::ONE)
        },
    ]);
    scene.spheres = vec![
        Sphere { center: vec3(-0.6, 0.3, 0.0), radius: 0.3, material: 1 },
        Sphere { center: vec3(0.0, 0.3, -0.3), radius: 0.3, material: 2 },
        Sphere { center: vec3(0.6, 0.3, 0.0), radius: 0.3, material: 3 },
        Sphere { center: vec3(-0.3, 0.2, 0.5), radius: 0.2, material: 4 },
        Sphere { center: vec3(0.3, 0.2, 0.5), radius: 0.2, material: 5 },
    ];
    let base = settings(W, H, 6, 8).with(|s| s.image.aovs = all());
    let first = render(&scene, &base);
    let albedo = aov(&first, Aov::Albedo);
    assert!(albedo.data.chunks(3).any(|p| v3(p) == KD), "the floor is seen");
    for isa in [Isa::Scalar, Isa::Sse, Isa::Avx2, Isa::Avx512] {
        for threads in [1, 3] {
            let s = base.clone().with(|s| {
                s.execution.isa = isa;
                s.execution.threads = threads;
            });
            let out = crate::render::with_threads(threads, || render(&scene, &s)).expect("a pool");
            assert_eq!(out.aovs, first.aovs, "{isa:?}, {threads} threads");
            assert_eq!(out.film, first.film, "{isa:?}, {threads} threads");
        }
    }
}

#[test]
fn without_output_variables_nothing_is_kept_and_no_stage_runs() {
    let scene = floor_scene();
    let s = settings(W, H, 2, 2);
    let (acc, stats) = crate::tests::common::render::wavefront(&scene, &s);
    assert!(acc.aovs.is_empty() && stats.stages.aov.is_none());
    let with = s.clone().with(|s| s.image.aovs = AovSet::NONE.with(Aov::Depth));
    let (acc, stats) = crate::tests::common::render::wavefront(&scene, &with);
    assert_eq!(acc.aovs.len(), W * H);
    assert!(stats.stages.aov.is_some());
    // The picture is the same bits with or without them.
    assert_eq!(acc.pixels, crate::tests::common::render::wavefront(&scene, &s).0.pixels);
}

#[test]
fn the_recursive_reference_and_the_normals_view_refuse_first_hit_variables() {
    let scene = floor_scene();
    let s = settings(W, H, 2, 1).with(|s| {
        s.image.aovs = AovSet::NONE.with(Aov::Albedo);
        s.execution.integrator = IntegratorKind::Recursive;
    });
    let e = render_with_progress(&scene, &BruteForce::new(&scene), &s, &|_| {}).err().expect("refused").to_string();
    assert!(e.contains("albedo") && e.contains("wavefront") && !e.contains('\n'), "{e}");
    let s = s.with(|s| {
        s.execution.integrator = IntegratorKind::Wavefront;
        s.paths.shading = crate::settings::Shading::Normals;
    });
    let e = render_with_progress(&scene, &BruteForce::new(&scene), &s, &|_| {}).err().expect("refused").to_string();
    assert!(e.contains("normals") && !e.contains('\n'), "{e}");
}
