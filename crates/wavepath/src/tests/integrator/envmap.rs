//! Environment maps: irradiance against a brute-force integral of the map, importance
//! sampling against cosine sampling, and what camera rays that miss see.

use crate::accel::BruteForce;
use crate::lights::Infinite;
use crate::sampling::{Frame, Sampler, warp};
use crate::scene::EnvMap;
use crate::scene::{Camera, Environment, Material, Mesh, Scene, Sphere};
use crate::settings::{Settings, Shading};
use crate::tests::common;
use glam::{DVec3, Vec3};
use std::f64::consts::PI;
use std::sync::Arc;

fn uffizi() -> Arc<EnvMap> {
    let p = common::scene("cs184/exr/uffizi_1200x600.exr").expect("WAVEPATH_SCENES must point at the scenes");
    Arc::new(EnvMap::load(&p).unwrap())
}

/// Irradiance at normal `n` by a midpoint rule over every texel (k x k points per texel):
/// independent of the sampling code (it only reads texels).
fn brute_force_irradiance(m: &EnvMap, n: DVec3, k: usize) -> DVec3 {
    let (w, h) = (m.width, m.height);
    let mut e = DVec3::ZERO;
    for y in 0..h {
        for x in 0..w {
            let l = m.texel(x, y).as_dvec3();
            if l == DVec3::ZERO {
                continue;
            }
            let mut s = 0.0;
            for i in 0..k {
                for j in 0..k {
                    // CS184: theta from +Y, phi = atan2(-z, x) + pi, so
                    // dir = (cos(phi - pi) sin theta, cos theta, -sin(phi - pi) sin theta).
                    let theta = (y as f64 + (i as f64 + 0.5) / k as f64) / h as f64 * PI;
                    let phi = (x as f64 + (j as f64 + 0.5) / k as f64) / w as f64 * 2.0 * PI;
                    let d = DVec3::new((phi - PI).cos() * theta.sin(), theta.cos(), -(phi - PI).sin() * theta.sin());
                    s += n.dot(d).max(0.0) * theta.sin();
                }
            }
            e += l * s * (PI / h as f64) * (2.0 * PI / w as f64) / (k * k) as f64;
        }
    }
    e
}

/// Irradiance estimates (weight x cos) at normal `n` from the light's own sampling: the
/// per-channel mean and the variance of the green channel.
fn estimate(light: &Infinite, n: Vec3, samples: usize, seed: u64) -> (DVec3, f64) {
    let mut s = Sampler::for_sample(seed, 0, 0);
    let (mut sum, mut sum2) = (DVec3::ZERO, 0.0);
    for _ in 0..samples {
        let u = [s.next_f32(), s.next_f32()];
        let e = match light.sample(n, u) {
            Some(ls) => (ls.weight * ls.wi.dot(n).max(0.0)).as_dvec3(),
            None => DVec3::ZERO,
        };
        sum += e;
        sum2 += e.y * e.y;
    }
    let mean = sum / samples as f64;
    (mean, sum2 / samples as f64 - mean.y * mean.y)
}

#[test]
fn importance_sampling_matches_the_integral_of_the_map() {
    let map = uffizi();
    let light = Infinite { map: Some(map.clone()), ..Infinite::default() };
    for n in [Vec3::Y, Vec3::X, Vec3::new(1.0, 1.0, -1.0).normalize(), -Vec3::Z, -Vec3::Y] {
        let expect = brute_force_irradiance(&map, n.as_dvec3(), 2);
        let samples = 100_000;
        let (mean, var) = estimate(&light, n, samples, 11);
        let sigma = (var / samples as f64).sqrt();
        for c in 0..3 {
            let tol = (5.0 * sigma).max(1e-3 * expect[c]);
            assert!(
                (mean[c] - expect[c]).abs() < tol.max(0.01 * expect[c]),
                "n {n}: channel {c}: estimate {} vs integral {} (sigma {sigma})",
                mean[c],
                expect[c]
            );
        }
        // The mixture with a constant term (half cosine, half map) stays unbiased.
        let mixed = Infinite { map: Some(map.clone()), all: Vec3::splat(0.25), ..Infinite::default() };
        let (m2, v2) = estimate(&mixed, n, samples, 12);
        let e2 = expect.y + 0.25 * PI;
        let s2 = (v2 / samples as f64).sqrt();
        assert!((m2.y - e2).abs() < (5.0 * s2).max(0.01 * e2), "mixed n {n}: {} vs {e2}", m2.y);
    }
}

/// On a peaky map (the Uffizi's bright windows and sky) light sampling by luminance has a
/// much lower variance than cosine-weighted sampling of the same irradiance.
#[test]
fn importance_sampling_beats_cosine_sampling_on_a_peaky_map() {
    let map = uffizi();
    let light = Infinite { map: Some(map.clone()), ..Infinite::default() };
    let n = Vec3::Y;
    let samples = 50_000;
    let (m_is, v_is) = estimate(&light, n, samples, 21);
    let mut s = Sampler::for_sample(22, 0, 0);
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    let frame = Frame::new(n);
    for _ in 0..samples {
        let (a, b) = (s.next_f32(), s.next_f32());
        let wi = frame.to_world(warp::cosine_hemisphere(a, b));
        // L cos / (cos / pi) = pi L.
        let e = std::f64::consts::PI * map.radiance(wi).y as f64;
        sum += e;
        sum2 += e * e;
    }
    let m_cos = sum / samples as f64;
    let v_cos = sum2 / samples as f64 - m_cos * m_cos;
    // Both estimate the same irradiance...
    let sigma = ((v_is + v_cos) / samples as f64).sqrt();
    assert!((m_is.y - m_cos).abs() < 5.0 * sigma, "{} vs {m_cos}", m_is.y);
    // ...importance sampling with less than a quarter of the variance.
    assert!(v_is < 0.25 * v_cos, "variance: importance {v_is}, cosine {v_cos}");
}

fn white_plane() -> Scene {
    let mesh = Mesh {
        positions: vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(-1.0, 0.0, 1.0),
        ],
        normals: None,
        uvs: None,
        colors: None,
        tangents: None,
        triangles: vec![[0, 2, 1], [0, 3, 2]],
        material_ids: vec![0, 0].into(),
    };
    Scene {
        name: "white plane".into(),
        mesh,
        materials: vec![Material::diffuse("white", Vec3::ONE)],
        camera: Camera::look_at(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, Vec3::Z, 30.0, 1.0),
        ..Scene::default()
    }
}

/// A white Lambertian plane (normal +Y) under the map, rendered with direct light only:
/// every pixel estimates E / pi, with E the map's irradiance on an upward plane.
#[test]
fn white_plane_under_the_map_reflects_its_irradiance() {
    let map = uffizi();
    let expect = brute_force_irradiance(&map, glam::DVec3::Y, 2) / PI;
    let mut scene = white_plane();
    assert!(!crate::effects::Effects::of(&scene, &Settings::default()).environment_map);
    scene.env = Environment::Map(map);
    let e = crate::effects::Effects::of(&scene, &Settings::default());
    assert!(e.environment_map && e.environment && e.infinite_light, "{:?}", e.names());
    let mut s = Settings::default();
    s.image.width = 16;
    s.image.height = 16;
    s.sampling.spp = 4;
    s.sampling.light_samples = 16;
    s.paths.max_depth = 1;
    s.paths.shading = Shading::Direct;
    let (film, _) = crate::render::render(&scene, &BruteForce::new(&scene), &s).unwrap();
    let n = film.pixels.len() as f64;
    let mean = film.pixels.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / n;
    let var = film.pixels.iter().map(|p| (p.y as f64 - mean.y).powi(2)).sum::<f64>() / (n - 1.0);
    let sigma = (var / n).sqrt();
    for c in 0..3 {
        assert!(
            (mean[c] - expect[c]).abs() < (5.0 * sigma).max(0.005 * expect[c]),
            "channel {c}: rendered {} vs E/pi {} (sigma {sigma})",
            mean[c],
            expect[c]
        );
    }
}

/// Camera rays that miss see the texel in their direction: a 1x1 render looking exactly at
/// a texel's centre (direction from the CS184 formula) shows that texel.
#[test]
fn camera_misses_show_the_map_in_the_right_direction() {
    let map = uffizi();
    let (w, h) = (map.width, map.height);
    // The brightest texel, the texels on the +X, +Z, -X, -Z axes just above the horizon,
    // and one near the zenith.
    let brightest = (0..w * h).max_by(|&a, &b| {
        let (la, lb) = (map.texel(a % w, a / w).y, map.texel(b % w, b / w).y);
        la.total_cmp(&lb)
    });
    let mut texels = vec![(600, 290), (300, 290), (5, 290), (900, 290), (17, 3)];
    texels.extend(brightest.map(|i| (i % w, i / w)));
    for (x, y) in texels {
        let theta = (y as f64 + 0.5) / h as f64 * PI;
        let phi = (x as f64 + 0.5) / w as f64 * 2.0 * PI;
        let d = DVec3::new((phi - PI).cos() * theta.sin(), theta.cos(), -(phi - PI).sin() * theta.sin()).as_vec3();
        let mut scene = Scene {
            name: "probe".into(),
            // Something to intersect, behind the camera.
            spheres: vec![Sphere { center: -d * 100.0, radius: 0.01, material: 0 }],
            materials: vec![Material::default()],
            camera: Camera::look_at(Vec3::ZERO, d, if d.y.abs() > 0.9 { Vec3::Z } else { Vec3::Y }, 1.0, 1.0),
            env: Environment::Map(map.clone()),
            ..Scene::default()
        };
        scene.camera.nclip = 0.0;
        let mut s = Settings::default();
        s.image.width = 1;
        s.image.height = 1;
        s.paths.max_depth = 1;
        s.paths.shading = Shading::Direct;
        let (film, _) = crate::render::render(&scene, &BruteForce::new(&scene), &s).unwrap();
        let got = film.get(0, 0);
        let want = map.texel(x, y);
        assert!(
            (got - want).abs().max_element() <= 1e-6 * want.max_element().max(1.0),
            "texel ({x},{y}): {got} vs {want}"
        );
    }
    // The orientation itself: the axis directions land in the CS184 columns.
    assert_eq!(map.texel_of(Vec3::new(1.0, 0.05, 0.0).normalize()).0, 600);
    assert_eq!(map.texel_of(Vec3::new(0.0, 0.05, 1.0).normalize()).0, 300);
    assert_eq!(map.texel_of(Vec3::new(0.0, 0.05, -1.0).normalize()).0, 900);
    assert!(map.texel_of(Vec3::new(0.0, 0.999, 0.01).normalize()).1 < 20);
}

/// A scene with no light of its own gets the default sky; an environment given to it
/// afterwards is its light instead, not the map plus the sky: a white plane under a constant
/// map of radiance 0.5 reflects the map's irradiance alone, E / pi = 0.5 (the sky would add
/// its own radiance, 1, to every pixel).
#[test]
fn a_map_replaces_the_default_sky() {
    let mut scene = white_plane();
    scene.light_by_default_sky();
    assert_eq!(scene.lights, [crate::scene::DEFAULT_SKY], "an unlit scene gets the sky");
    let grey = EnvMap::from_texels("grey".into(), 8, 4, vec![Vec3::splat(0.5); 32]).unwrap();
    scene.set_environment(Environment::Map(Arc::new(grey)));
    assert!(scene.lights.is_empty(), "{:?}", scene.lights);
    let mut s = Settings::default();
    s.image.width = 16;
    s.image.height = 16;
    s.sampling.spp = 4;
    s.sampling.light_samples = 16;
    s.paths.shading = Shading::Direct;
    let (film, _) = crate::render::render(&scene, &BruteForce::new(&scene), &s).unwrap();
    let mean = film.pixels.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / film.pixels.len() as f64;
    assert!((mean - DVec3::splat(0.5)).abs().max_element() < 0.01, "mean {mean} against 0.5");
    // Without the map, the sky comes back.
    scene.set_environment(Environment::None);
    assert_eq!(scene.lights, [crate::scene::DEFAULT_SKY]);
}

/// The map's importance sampling (in lanes and one lane at a time, with MIS) against an
/// estimator that never draws from the map: uniform hemisphere probes that only look the
/// texels up. A white sphere on the white plane under the Uffizi map, global illumination:
/// both integrators' renders agree region by region with the probes' render, so the map's
/// directions, densities and weights are consistent with its radiance.
#[test]
fn importance_sampled_renders_agree_with_hemisphere_probes() {
    let mut scene = white_plane();
    scene.env = Environment::Map(uffizi());
    scene.materials.push(Material::diffuse("grey", Vec3::splat(0.6)));
    scene.spheres.push(Sphere { center: Vec3::new(0.0, 0.4, 0.0), radius: 0.4, material: 1 });
    scene.camera = Camera::look_at(Vec3::new(0.0, 1.2, 2.6), Vec3::new(0.0, 0.3, 0.0), Vec3::Y, 40.0, 4.0 / 3.0);
    let s = common::render::small_settings(16, 12, 3, 256);
    let probes = common::render::wavefront(&scene, &s.clone().with(|s| s.paths.hemisphere = true)).0;
    for (what, sampled) in [
        ("wavefront, map sampled", common::render::wavefront(&scene, &s).0),
        ("recursive, map sampled", common::render::recursive(&scene, &s).0),
    ] {
        common::agree::assert_regions_agree(&sampled, &probes, 4, 0.0, what);
    }
}
