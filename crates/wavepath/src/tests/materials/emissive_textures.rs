//! Emission through a texture (glTF `emissiveTexture`): a point emits factor x texel, seen by
//! the camera and found by light sampling alike; triangles whose texels are all black are
//! left out of light sampling. Expected values: the texels themselves and the closed-form
//! form factor of the part of the emitter that glows.

use crate::lights::EmissiveTriangles;
use crate::scene::texture::{Filter, Texture, TextureImage, Wrap};
use crate::scene::{Camera, Material, Mesh, Scene};
use crate::tests::common::{self, agree, meshgen::quad, render};
use glam::{DVec3, Vec2, Vec3, vec3};
use std::sync::Arc;

const W: usize = 32;
const H: usize = 24;
/// The emitter: x in [-HALF_X, HALF_X], z in [-HALF_Z, HALF_Z], at height HEIGHT, facing down.
const HALF_X: f32 = 0.5;
const HALF_Z: f32 = 0.4;
const HEIGHT: f32 = 1.0;
const FACTOR: f32 = 2.0;

/// `image` as an emission texture under a grey `factor`: nearest texel, clamped, uv as is.
fn emission_texture(image: TextureImage, factor: f32) -> Texture {
    Texture {
        path: "emission.png".into(),
        image: Some(Arc::new(image)),
        wrap: [Wrap::ClampToEdge; 2],
        filter: Filter::Nearest,
        flip_v: false,
        factor: Vec3::splat(factor),
        transform: glam::Affine2::IDENTITY,
    }
}

/// A floor of albedo 0.5, and an emitter made of two quads (left x < 0, right x > 0) that
/// map to the two halves of a 4x1 texture: red, red, black, black (nearest, clamped).
fn scene() -> Scene {
    let mut mesh = Mesh::default();
    let h = 10.0;
    quad(&mut mesh, [vec3(-h, 0.0, -h), vec3(-h, 0.0, h), vec3(h, 0.0, h), vec3(h, 0.0, -h)], 0);
    let mut uvs = vec![Vec2::ZERO; 4];
    for (x0, x1, u0, u1) in [(-HALF_X, 0.0, 0.0, 0.5), (0.0, HALF_X, 0.5, 1.0)] {
        let (z0, z1) = (-HALF_Z, HALF_Z);
        quad(&mut mesh, [vec3(x0, HEIGHT, z0), vec3(x1, HEIGHT, z0), vec3(x1, HEIGHT, z1), vec3(x0, HEIGHT, z1)], 1);
        uvs.extend([Vec2::new(u0, 0.0), Vec2::new(u1, 0.0), Vec2::new(u1, 1.0), Vec2::new(u0, 1.0)]);
    }
    mesh.uvs = Some(uvs);
    let red = vec3(1.0, 0.0, 0.0);
    let image = TextureImage { width: 4, height: 1, texels: vec![red, red, Vec3::ZERO, Vec3::ZERO] };
    let texture = emission_texture(image, FACTOR);
    let light = Material { emission_texture: Some(texture), ..Material::emitter("light", Vec3::splat(FACTOR)) };
    let mut camera = Camera::look_at(vec3(0.0, 0.9, 0.5), Vec3::ZERO, Vec3::Y, 20.0, W as f32 / H as f32);
    camera.nclip = 0.01;
    Scene {
        name: "textured emitter".into(),
        mesh,
        materials: vec![Material::diffuse("floor", Vec3::splat(0.5)), light],
        camera,
        ..Scene::default()
    }
}

#[test]
fn light_sampling_follows_the_emission_texture() {
    let scene = scene();
    // The black half's two triangles are left out.
    assert_eq!(EmissiveTriangles::new(&scene).map(|e| e.len()), Some(2));
    // A floor point under the emitter: albedo / pi x Le x pi F = 0.5 x 2 x F(red half), red only.
    let expect = |x: usize, y: usize| {
        let r = scene.camera.generate_ray((x as f32 + 0.5) / W as f32, (y as f32 + 0.5) / H as f32);
        let p = r.at(-r.origin.y / r.dir.y);
        let f = common::rect_form_factor(
            (-HALF_X - p.x) as f64,
            (0.0 - p.x) as f64,
            (-HALF_Z - p.z) as f64,
            (HALF_Z - p.z) as f64,
            HEIGHT as f64,
        );
        Some(DVec3::new(0.5 * FACTOR as f64 * f, 0.0, 0.0))
    };
    let light = render::wavefront(&scene, &render::settings(W, H, 1, 16).with(|s| s.sampling.light_samples = 4)).0;
    agree::assert_regions_match(&light, 8, expect, 1e-4, "textured emitter, light sampling");
    let hemi = render::wavefront(
        &scene,
        &render::settings(W, H, 1, 64).with(|s| {
            s.paths.hemisphere = true;
            s.sampling.light_samples = 8
        }),
    )
    .0;
    agree::assert_regions_match(&hemi, 8, expect, 1e-4, "textured emitter, hemisphere sampling");
}

#[test]
fn the_camera_sees_factor_times_texel() {
    let mut scene = scene();
    scene.camera = Camera::look_at(vec3(0.0, 0.0, 0.0), vec3(0.0, 1.0, 0.001), Vec3::Z, 40.0, W as f32 / H as f32);
    let acc = render::wavefront(&scene, &render::settings(W, H, 1, 4)).0;
    let (mut red, mut black) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            // Where the pixel's centre ray meets the emitter's plane.
            let r = scene.camera.generate_ray((x as f32 + 0.5) / W as f32, (y as f32 + 0.5) / H as f32);
            let q = r.at((HEIGHT - r.origin.y) / r.dir.y);
            let px = acc.pixels[y * W + x].mean();
            let inside = q.z.abs() < HALF_Z - 0.05;
            if inside && (-HALF_X + 0.05..-0.05).contains(&q.x) {
                assert_eq!(px, vec3(FACTOR, 0.0, 0.0), "pixel ({x},{y}) on the red half");
                red += 1;
            } else if inside && (0.05..HALF_X - 0.05).contains(&q.x) {
                assert_eq!(px, Vec3::ZERO, "pixel ({x},{y}) on the black half");
                black += 1;
            }
        }
    }
    assert!(red > 20 && black > 20, "{red} red, {black} black pixels");
}

/// Emitters of equal area seen from one point: plain radiance 1, plain radiance 9, and two
/// under a texture (white, black; factor 4) whose uvs fall inside its white texel and its
/// black one. Light samples land on each in proportion to its power, 1 : 9 : 4 : 0
/// (binomial bounds, false failures below 1e-6), and the density a sample reports equals
/// the one MIS evaluates for a ray that hits the same point.
#[test]
fn emissive_triangles_are_drawn_in_proportion_to_their_power() {
    use crate::lights::{SampledLight, Seen};
    let mut mesh = Mesh::default();
    // Four triangles in the plane y = 1, facing down; x offsets 0, 2, 4, 6.
    for k in 0..4 {
        let x = 2.0 * k as f32;
        let base = mesh.positions.len() as u32;
        mesh.positions.extend([vec3(x, 1.0, 0.0), vec3(x, 1.0, 1.0), vec3(x + 1.0, 1.0, 0.0)]);
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.material_ids.push(k.min(2));
    }
    let (lo, hi) = (0.1, 0.4);
    let uv = |u0: f32| [Vec2::new(u0, 0.0), Vec2::new(u0, 1.0), Vec2::new(u0 + hi - lo, 0.0)];
    mesh.uvs = Some([uv(lo), uv(lo), uv(lo), uv(1.0 - hi)].concat());
    let white = Vec3::ONE;
    let image = TextureImage { width: 2, height: 1, texels: vec![white, Vec3::ZERO] };
    let texture = emission_texture(image, 4.0);
    let materials = vec![
        Material::emitter("one", Vec3::ONE),
        Material::emitter("nine", Vec3::splat(9.0)),
        Material { emission_texture: Some(texture), ..Material::emitter("textured", Vec3::splat(4.0)) },
    ];
    let scene = Scene { mesh, materials, ..Scene::default() };
    let e = EmissiveTriangles::new(&scene).expect("emitters");
    assert_eq!(e.len(), 3, "the triangle on black texels is left out");
    let light = SampledLight::Emissive(e);
    let p = vec3(2.5, 0.0, 0.3);
    let n = Vec3::Y;
    let mut counts = [0usize; 4];
    let mut r = crate::sampling::Sampler::for_sample(11, 0, 0);
    let total = 300_000;
    for _ in 0..total {
        let u = [r.next_f32(), r.next_f32(), r.next_f32()];
        let Some((ls, pdf)) = light.sample_pdf(p, n, u) else { continue };
        let q = ls.target.expect("a point on the emitter");
        let k = (q.x / 2.0).floor() as usize;
        counts[k] += 1;
        let emission = ls.weight * pdf;
        let seen = Seen::Hit { t: q.distance(p), emitter: Some((emission, -Vec3::Y, k as u32)) };
        let (_, pdf_hit) = light.radiance_pdf(p, n, ls.wi, seen).expect("the ray reaches the emitter");
        assert!((pdf_hit - pdf).abs() <= 1e-3 * pdf, "sampled density {pdf}, evaluated {pdf_hit}");
    }
    assert_eq!(counts[3], 0);
    for (k, share) in [1.0 / 14.0, 9.0 / 14.0, 4.0 / 14.0].into_iter().enumerate() {
        let sd = (total as f64 * share * (1.0 - share)).sqrt();
        let z = (counts[k] as f64 - total as f64 * share) / sd;
        assert!(z.abs() < 5.3, "emitter {k}: {} samples, expected {:.0} (z = {z:.2})", counts[k], total as f64 * share);
    }
}
