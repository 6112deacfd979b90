//! Renders of the MTL models whose answer is known without the renderer: a Phong sphere in
//! a white furnace, and a glass slab in front of an emitter against Fresnel's equations.

use crate::scene::{Bsdf, Camera, Environment, Material, Mesh, Scene, Sphere};
use crate::settings::Settings;
use crate::tests::common;
use crate::tests::common::meshgen::quad;
use glam::{Vec3, vec3};

/// Image mean of the pixels whose every sample hit the sphere (whole pixels inside its
/// outline) and the standard error of that mean from the per-pixel sample variances.
fn sphere_mean(acc: &crate::film::Accumulator, w: usize, h: usize, cam: &Camera) -> (f64, f64, usize) {
    let (mut sum, mut var, mut n) = (0.0f64, 0.0f64, 0usize);
    for y in 0..h {
        for x in 0..w {
            // All four corners of the pixel on the sphere: the pixel is all sphere.
            let inside = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].iter().all(|(dx, dy)| {
                let r = cam.generate_ray((x as f32 + dx) / w as f32, (y as f32 + dy) / h as f32);
                let b = r.origin.dot(r.dir);
                b * b - (r.origin.length_squared() - 1.0) > 1e-3
            });
            if !inside {
                continue;
            }
            let p = &acc.pixels[y * w + x];
            sum += p.mean().x as f64;
            var += p.variance_of_mean().x;
            n += 1;
        }
    }
    (sum / n as f64, var.sqrt() / n as f64, n)
}

/// A unit sphere of Phong material under a constant white environment reflects, from every
/// direction, its directional albedo: at most Kd + Ks, and Kd + Ks = 1 with a sharp lobe
/// reflects all but the ~1% single-scattering microfacets lose (a rough lobe loses more:
/// about a quarter of Ks at alpha 0.41 over the sphere; the BSDF tests pin it per direction). The sphere is convex, so
/// each path reflects once; the light comes through light sampling of the environment and
/// BSDF sampling, combined by MIS, in both integrators.
#[test]
fn phong_sphere_in_a_white_furnace() {
    let (w, h) = (24, 24);
    let camera = Camera::look_at(vec3(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 30.0, 1.0);
    for (kd, ks, ns, lo, hi) in
        [(0.7f32, 0.3f32, 1000.0f32, 0.995, 1.0), (0.5, 0.5, 10.0, 0.8, 1.0), (0.3, 0.3, 48.0, 0.5, 0.6)]
    {
        let scene = Scene {
            name: "phong furnace".into(),
            spheres: vec![Sphere { center: Vec3::ZERO, radius: 1.0, material: 0 }],
            materials: vec![Material {
                bsdf: Bsdf::Phong { diffuse: Vec3::splat(kd), specular: Vec3::splat(ks), shininess: ns },
                ..Material::diffuse("phong", Vec3::ONE)
            }],
            camera,
            env: Environment::Constant(Vec3::ONE),
            ..Scene::default()
        };
        let s: Settings = common::render::settings(w, h, 3, 256);
        for (which, (acc, st)) in
            [("wavefront", common::render::wavefront(&scene, &s)), ("recursive", common::render::recursive(&scene, &s))]
        {
            assert_eq!(st.invalid_samples, 0);
            let (mean, se, n) = sphere_mean(&acc, w, h, &camera);
            assert!(n > 150, "{n} pixels on the sphere");
            // 5 standard errors: a false failure about once in 3.5 million runs per case.
            assert!(
                mean >= lo - 5.0 * se && mean <= hi + 5.0 * se,
                "{which}: Kd {kd} Ks {ks} Ns {ns}: sphere mean {mean} +- {se}, expected in [{lo}, {hi}]"
            );
        }
    }
}

/// A glass slab (two parallel faces of a closed box) between the camera and an emitter of
/// radiance 1, seen at normal incidence (a 1-degree field), with a black environment: what
/// arrives is the light transmitted through both faces after any number of internal
/// reflections, Tf^2 (1 - R)^2 / (1 - R^2) with R = ((n - 1) / (n + 1))^2 (Fresnel at normal
/// incidence; the transmittance scales each crossing, as the MTL `Tf` does).
#[test]
fn glass_slab_transmits_as_fresnel_says() {
    let (w, h) = (8, 8);
    for (ior, tf) in [(1.5f32, 1.0f32), (2.5, 1.0), (1.5, 0.5)] {
        let mut mesh = Mesh::default();
        let s = 5.0;
        // The slab z in [-1, 0], outward normals (counter-clockwise seen from outside).
        let c = |x: f32, y: f32, z: f32| vec3(x, y, z);
        quad(&mut mesh, [c(-s, -s, 0.0), c(s, -s, 0.0), c(s, s, 0.0), c(-s, s, 0.0)], 0);
        quad(&mut mesh, [c(-s, -s, -1.0), c(-s, s, -1.0), c(s, s, -1.0), c(s, -s, -1.0)], 0);
        quad(&mut mesh, [c(-s, -s, -1.0), c(s, -s, -1.0), c(s, -s, 0.0), c(-s, -s, 0.0)], 0);
        quad(&mut mesh, [c(-s, s, -1.0), c(-s, s, 0.0), c(s, s, 0.0), c(s, s, -1.0)], 0);
        quad(&mut mesh, [c(-s, -s, -1.0), c(-s, -s, 0.0), c(-s, s, 0.0), c(-s, s, -1.0)], 0);
        quad(&mut mesh, [c(s, -s, -1.0), c(s, s, -1.0), c(s, s, 0.0), c(s, -s, 0.0)], 0);
        // The emitter behind it.
        quad(&mut mesh, [c(-s, -s, -2.0), c(s, -s, -2.0), c(s, s, -2.0), c(-s, s, -2.0)], 1);
        let glass = Bsdf::Glass { reflectance: Vec3::ONE, transmittance: Vec3::splat(tf), roughness: 0.0, ior };
        let mut scene = common::meshgen::scene_of(mesh, vec![]);
        scene.materials = vec![
            Material { bsdf: glass, ..Material::diffuse("glass", Vec3::ONE) },
            Material::emitter("light", Vec3::ONE),
        ];
        scene.camera = Camera::look_at(vec3(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 1.0, 1.0);
        scene.env = Environment::None;
        let r = ((ior - 1.0) / (ior + 1.0)).powi(2) as f64;
        let want = (tf * tf) as f64 * (1.0 - r).powi(2) / (1.0 - r * r);
        let mut st = common::render::settings(w, h, 64, 1024);
        st.paths.roulette.continue_prob = 1.0;
        for (which, (acc, stats)) in [
            ("wavefront", common::render::wavefront(&scene, &st)),
            ("recursive", common::render::recursive(&scene, &st)),
        ] {
            assert_eq!(stats.invalid_samples, 0);
            let n = acc.pixels.len() as f64;
            let mean = acc.pixels.iter().map(|p| p.mean().x as f64).sum::<f64>() / n;
            let se = acc.pixels.iter().map(|p| p.variance_of_mean().x).sum::<f64>().sqrt() / n;
            // 5 standard errors (false failure ~3e-7 per case), plus the 0.5-degree rays'
            // departure from normal incidence (R changes by < 1e-5).
            assert!(
                (mean - want).abs() < 5.0 * se + 1e-4,
                "{which}: ior {ior} Tf {tf}: transmitted {mean} +- {se}, Fresnel says {want}"
            );
        }
    }
}
