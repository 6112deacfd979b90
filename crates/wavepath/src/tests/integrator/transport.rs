//! Light transport against answers computed here in f64, apart from the renderer's code
//! (the wavefront and recursive integrators share `Transport`, so their agreement checks
//! queues, not light):
//! - a rough conductor plane under a small area light: f Le cos integrated over the light
//!   by quadrature, with its own Beckmann D, Smith G and a complex-number Fresnel;
//! - furnace spheres: a perfect conductor (F = 1) in a uniform environment reflects the
//!   environment times the microfacet albedo A(wo), integrated here over half vectors; a
//!   mirror reflects it exactly;
//! - a small bright light in a nearly smooth conductor: the mean as above, and each pixel's
//!   sample variance under the bound that the power heuristic puts on every sample's value
//!   (light sampling alone exceeds it many times: the fireflies MIS removes).
//!
//! Statistics: region means by the shared z-test of `common::agree` (false failures below
//! 1e-6 a call, fixed seeds); the variance bound holds for every sample by construction, and
//! its slack covers the sample variance's own noise.

use crate::film::Accumulator;
use crate::scene::{Bsdf, Camera, Environment, Material, Mesh, Scene, Sphere};
use crate::settings::Settings;
use crate::tests::common::agree::assert_regions_match;
use crate::tests::common::meshgen::quad;
use crate::tests::common::render;
use glam::{DVec3, Vec3, vec3};
use std::f64::consts::PI;

const W: usize = 32;
const H: usize = 24;
/// Sub-pixel points per side at which an expected pixel value is averaged (samples are
/// jittered uniformly across the pixel).
const SUB: usize = 4;

/// Copper's complex index of refraction (R, G, B).
const ETA: [f64; 3] = [0.27, 0.68, 1.22];
const K: [f64; 3] = [3.61, 2.63, 2.29];

/// The rendered image, with no invalid sample.
fn render(scene: &Scene, s: &Settings) -> Accumulator {
    let (acc, st) = render::wavefront(scene, s);
    assert_eq!(st.invalid_samples, 0, "{}", scene.name);
    acc
}

// ---- The model in f64, written from the formulas (pbrt 3rd ed. 8.4, Walter et al. 2007).

fn beckmann_d(cos_h: f64, alpha: f64) -> f64 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let c2 = cos_h * cos_h;
    let tan2 = (1.0 - c2) / c2;
    (-tan2 / (alpha * alpha)).exp() / (PI * alpha * alpha * c2 * c2)
}

/// Smith's Lambda for Beckmann, Walter's rational approximation.
fn beckmann_lambda(cos: f64, alpha: f64) -> f64 {
    if cos >= 1.0 {
        return 0.0;
    }
    let a = cos / (alpha * (1.0 - cos * cos).sqrt());
    if a >= 1.6 { 0.0 } else { (1.0 - 1.259 * a + 0.396 * a * a) / (3.535 * a + 2.181 * a * a) }
}

#[derive(Clone, Copy)]
struct C(f64, f64);

impl C {
    fn mul(self, o: C) -> C {
        C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    fn div(self, o: C) -> C {
        let d = o.0 * o.0 + o.1 * o.1;
        C((self.0 * o.0 + self.1 * o.1) / d, (self.1 * o.0 - self.0 * o.1) / d)
    }
    fn add(self, o: C) -> C {
        C(self.0 + o.0, self.1 + o.1)
    }
    fn sub(self, o: C) -> C {
        C(self.0 - o.0, self.1 - o.1)
    }
    fn sqrt(self) -> C {
        let r = (self.0 * self.0 + self.1 * self.1).sqrt();
        let re = ((r + self.0) / 2.0).max(0.0).sqrt();
        let im = ((r - self.0) / 2.0).max(0.0).sqrt();
        C(re, if self.1 < 0.0 { -im } else { im })
    }
    fn norm2(self) -> f64 {
        self.0 * self.0 + self.1 * self.1
    }
}

/// Unpolarised Fresnel reflectance at a conductor of index eta + i k, from Snell's law with
/// a complex transmitted cosine.
fn fresnel_conductor(cos_i: f64, eta: f64, k: f64) -> f64 {
    let n = C(eta, k);
    let ci = C(cos_i, 0.0);
    let sin2 = C(1.0 - cos_i * cos_i, 0.0);
    let ct = C(1.0, 0.0).sub(sin2.div(n.mul(n))).sqrt();
    let rs = ci.sub(n.mul(ct)).div(ci.add(n.mul(ct))).norm2();
    let rp = n.mul(ci).sub(ct).div(n.mul(ci).add(ct)).norm2();
    0.5 * (rs + rp)
}

/// f(wo, wi) of the rough conductor about normal +Y (world directions, unit).
fn conductor_f(wo: DVec3, wi: DVec3, alpha: f64) -> DVec3 {
    let (co, ci) = (wo.y, wi.y);
    if co <= 0.0 || ci <= 0.0 {
        return DVec3::ZERO;
    }
    let h = (wo + wi).normalize();
    let g = 1.0 / (1.0 + beckmann_lambda(co, alpha) + beckmann_lambda(ci, alpha));
    let v = beckmann_d(h.y, alpha) * g / (4.0 * co * ci);
    let c = wi.dot(h);
    DVec3::new(
        fresnel_conductor(c, ETA[0], K[0]),
        fresnel_conductor(c, ETA[1], K[1]),
        fresnel_conductor(c, ETA[2], K[2]),
    ) * v
}

// ---- A conductor plane under a square emitter.

/// The emitter: a square of side `side` centred at `centre`, facing down.
#[derive(Clone, Copy)]
struct Emitter {
    centre: Vec3,
    side: f32,
    le: f32,
}

fn plane_scene(alpha: f32, light: Emitter) -> Scene {
    let mut mesh = Mesh::default();
    let h = 10.0;
    quad(&mut mesh, [vec3(-h, 0.0, -h), vec3(-h, 0.0, h), vec3(h, 0.0, h), vec3(h, 0.0, -h)], 0);
    let (c, a) = (light.centre, light.side / 2.0);
    quad(&mut mesh, [c + vec3(-a, 0.0, -a), c + vec3(a, 0.0, -a), c + vec3(a, 0.0, a), c + vec3(-a, 0.0, a)], 1);
    let metal = Bsdf::Microfacet { alpha, eta: Vec3::from(ETA.map(|x| x as f32)), k: Vec3::from(K.map(|x| x as f32)) };
    let mut camera = Camera::look_at(vec3(0.0, 0.6, 2.0), vec3(0.0, 0.0, -0.3), Vec3::Y, 50.0, W as f32 / H as f32);
    camera.nclip = 1e-3;
    Scene {
        name: format!("conductor alpha {alpha}"),
        mesh,
        materials: vec![
            Material { bsdf: metal, ..Material::diffuse("copper", Vec3::ONE) },
            Material::emitter("light", Vec3::splat(light.le)),
        ],
        camera,
        ..Scene::default()
    }
}

/// The floor points of pixel (x, y) on a `sub` x `sub` grid, with the direction back to the
/// camera; `None` when any of them misses the floor or sees the emitter first.
fn floor_points(cam: &Camera, light: Emitter, sub: usize, x: usize, y: usize) -> Option<Vec<(DVec3, DVec3)>> {
    let mut out = Vec::new();
    for k in 0..sub * sub {
        let (fx, fy) = (((k % sub) as f32 + 0.5) / sub as f32, ((k / sub) as f32 + 0.5) / sub as f32);
        let r = cam.generate_ray((x as f32 + fx) / W as f32, (y as f32 + fy) / H as f32);
        let (o, d) = (r.origin.as_dvec3(), r.dir.as_dvec3());
        let t = -o.y / d.y;
        let p = o + t * d;
        let tl = (light.centre.y as f64 - o.y) / d.y;
        let q = o + tl * d - light.centre.as_dvec3();
        let sees_light = tl > 0.0 && q.x.abs() <= light.side as f64 / 2.0 && q.z.abs() <= light.side as f64 / 2.0;
        if !(t > 0.0 && p.x.abs() < 9.9 && p.z.abs() < 9.9) || (sees_light && tl < t) {
            return None;
        }
        out.push((p, -d));
    }
    Some(out)
}

/// Reflected radiance at p toward wo: f Le cos_i cos_l / r^2 over the emitter, midpoint rule
/// on an n x n grid.
fn reflected(p: DVec3, wo: DVec3, alpha: f64, light: Emitter, n: usize) -> DVec3 {
    let side = light.side as f64;
    let da = side * side / (n * n) as f64;
    let mut sum = DVec3::ZERO;
    for j in 0..n {
        for i in 0..n {
            let q = light.centre.as_dvec3()
                + DVec3::new(
                    ((i as f64 + 0.5) / n as f64 - 0.5) * side,
                    0.0,
                    ((j as f64 + 0.5) / n as f64 - 0.5) * side,
                );
            let d = q - p;
            let r2 = d.length_squared();
            let wi = d / r2.sqrt();
            sum += conductor_f(wo, wi, alpha) * (wi.y * wi.y / r2 * da);
        }
    }
    sum * light.le as f64
}

fn expected_plane(
    scene: &Scene,
    alpha: f64,
    light: Emitter,
    sub: usize,
    n: usize,
) -> impl Fn(usize, usize) -> Option<DVec3> + '_ {
    move |x, y| {
        let pts = floor_points(&scene.camera, light, sub, x, y)?;
        Some(pts.iter().map(|&(p, wo)| reflected(p, wo, alpha, light, n)).sum::<DVec3>() / pts.len() as f64)
    }
}

/// Copper at roughness 0.3 under a 0.5-wide emitter: the highlight and its falloff, direct
/// light (one bounce is all a plane has), light and BSDF sampling combined.
#[test]
fn rough_conductor_under_an_area_light_matches_quadrature() {
    let light = Emitter { centre: vec3(0.0, 0.8, -0.5), side: 0.5, le: 4.0 };
    let scene = plane_scene(0.3, light);
    let expect = expected_plane(&scene, 0.3, light, SUB, 48);
    let acc = render(&scene, &render::settings(W, H, 1, 64).with(|s| s.sampling.light_samples = 2));
    let (z, checked) = assert_regions_match(&acc, 8, &expect, 2e-3, "copper alpha 0.3");
    assert!(checked > W * H / 2, "{checked} pixels checked");
    // The highlight is in view: some pixels are many times the dimmest.
    let vals: Vec<f64> = (0..W * H).filter_map(|i| expect(i % W, i / W).map(|e| e.y)).collect();
    let (lo, hi) = vals.iter().fold((f64::MAX, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    assert!(hi > 10.0 * lo && hi > 0.05, "expected values {lo}..{hi}: no highlight in view");
    eprintln!("copper alpha 0.3: worst |z| {z:.2}");
}

/// A 0.4-wide emitter of radiance 20 in copper of roughness 0.01. Per sample, light sampling
/// weighs a direction by f cos / p_light, which in so sharp a lobe is tens of times Le; the
/// power heuristic caps each light sample at ns Le w / 2 and the BSDF sample at Le w, where
/// w = F G (wo.h) / (cos_o cos_h) <= (wo.h) / (cos_o cos_h) is the BSDF sample's weight. So
/// X <= Xmax = Le (1 + ns / 2) max w, and the sample variance E[X^2] - E[X]^2 <= Xmax E[X].
#[test]
fn mis_keeps_a_small_bright_light_in_a_sharp_lobe_within_its_variance_bound() {
    let light = Emitter { centre: vec3(0.0, 0.8, -0.5), side: 0.4, le: 20.0 };
    let alpha = 0.01;
    let scene = plane_scene(alpha as f32, light);
    let ns = 1;
    let acc = render(&scene, &render::settings(W, H, 1, 256).with(|s| s.sampling.light_samples = ns));
    let expect = expected_plane(&scene, alpha, light, 3, 80);
    let (z, checked) = assert_regions_match(&acc, 8, &expect, 5e-3, "copper alpha 0.01");
    assert!(checked > W * H / 2);
    let (mut lit, mut worst) = (0, 0.0f64);
    for y in 0..H {
        for x in 0..W {
            let Some(pts) = floor_points(&scene.camera, light, 3, x, y) else { continue };
            let mut w_max = 0.0f64;
            for &(p, wo) in &pts {
                for j in 0..=8 {
                    for i in 0..=8 {
                        let s = light.side as f64;
                        let q = light.centre.as_dvec3()
                            + DVec3::new((i as f64 / 8.0 - 0.5) * s, 0.0, (j as f64 / 8.0 - 0.5) * s);
                        let wi = (q - p).normalize();
                        let h = (wo + wi).normalize();
                        w_max = w_max.max(wo.dot(h) / (wo.y * h.y));
                    }
                }
            }
            // The grid's maximum, widened for points between its nodes.
            let x_max = light.le as f64 * (1.0 + ns as f64 / 2.0) * w_max * 1.05;
            let px = &acc.pixels[y * W + x];
            let mean = px.mean().y as f64;
            let var = px.variance_of_mean().y * px.valid as f64;
            if mean > 0.01 {
                lit += 1;
                worst = worst.max(var / (x_max * mean));
            }
            // 1.5: the sample variance of 256 samples bounded by Xmax is itself noisy.
            assert!(
                var <= 1.5 * x_max * mean + 1e-9,
                "pixel ({x},{y}): variance {var}, mean {mean}, bound {}",
                x_max * mean
            );
        }
    }
    assert!(lit >= 4, "{lit} pixels see the highlight");
    eprintln!("copper alpha 0.01: worst |z| {z:.2}, {lit} lit pixels, variance up to {worst:.2} of the bound");
}

// ---- Furnace spheres.

/// Directional albedo of the F = 1 Beckmann conductor: the integral of f cos_i over the
/// hemisphere, written over half vectors (dw_i = 4 (wo.h) dw_h): D(h) G (wo.h) / cos_o.
fn albedo(cos_o: f64, alpha: f64) -> f64 {
    let wo = DVec3::new((1.0 - cos_o * cos_o).max(0.0).sqrt(), 0.0, cos_o);
    let (nt, np) = (1200, 180);
    // theta_h up to tan = 8 alpha, where D has fallen below e^-64 of its peak.
    let t_max = (8.0 * alpha).atan();
    let (dt, dp) = (t_max / nt as f64, PI / np as f64);
    let mut sum = 0.0;
    for i in 0..nt {
        let t = (i as f64 + 0.5) * dt;
        let (st, ct) = t.sin_cos();
        for j in 0..np {
            let p = (j as f64 + 0.5) * dp;
            let h = DVec3::new(st * p.cos(), st * p.sin(), ct);
            let oh = wo.dot(h);
            if oh <= 0.0 {
                continue;
            }
            let wi = 2.0 * oh * h - wo;
            if wi.z <= 0.0 {
                continue;
            }
            let g = 1.0 / (1.0 + beckmann_lambda(cos_o, alpha) + beckmann_lambda(wi.z, alpha));
            // phi over [0, pi] counted twice: the integrand is symmetric about the plane of wo.
            sum += 2.0 * beckmann_d(ct, alpha) * g * oh / cos_o * st * dt * dp;
        }
    }
    sum
}

/// Renders a unit sphere of `bsdf` in a uniform environment of 0.5 and checks every pixel
/// against 0.5 A(cos_o) (averaged over the pixel; background 0.5; rim pixels skipped), with
/// the directional albedo A tabulated from `albedo` and interpolated linearly.
fn assert_furnace_sphere(what: &str, bsdf: Bsdf, albedo: impl Fn(f64) -> DVec3) {
    let mut camera = Camera::look_at(vec3(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 36.0, W as f32 / H as f32);
    camera.nclip = 1e-3;
    let scene = Scene {
        name: format!("furnace {what}"),
        spheres: vec![Sphere { center: Vec3::ZERO, radius: 1.0, material: 0 }],
        materials: vec![Material { bsdf, ..Material::diffuse("sphere", Vec3::ONE) }],
        camera,
        env: Environment::Constant(Vec3::splat(0.5)),
        ..Scene::default()
    };
    let nodes = 64;
    let table: Vec<DVec3> = (0..=nodes).map(|i| albedo((i as f64 / nodes as f64).max(1e-3))).collect();
    let a_of = |c: f64| {
        let f = c.clamp(0.0, 1.0) * nodes as f64;
        let i = (f as usize).min(nodes - 1);
        table[i] + (table[i + 1] - table[i]) * (f - i as f64)
    };
    let expect = |x: usize, y: usize| {
        let mut vals = Vec::new();
        for k in 0..SUB * SUB {
            let (fx, fy) = (((k % SUB) as f32 + 0.5) / SUB as f32, ((k / SUB) as f32 + 0.5) / SUB as f32);
            let r = scene.camera.generate_ray((x as f32 + fx) / W as f32, (y as f32 + fy) / H as f32);
            let (o, d) = (r.origin.as_dvec3(), r.dir.as_dvec3());
            let b = o.dot(d);
            let disc = b * b - (o.length_squared() - 1.0);
            vals.push(if disc > 0.0 {
                let p = o + (-b - disc.sqrt()) * d;
                Some(0.5 * a_of(-d.dot(p.normalize())))
            } else {
                None
            });
        }
        // Pixels across the rim mix two values: skipped.
        if vals.iter().all(Option::is_some) {
            Some(vals.iter().flatten().sum::<DVec3>() / vals.len() as f64)
        } else if vals.iter().all(Option::is_none) {
            Some(DVec3::splat(0.5))
        } else {
            None
        }
    };
    let acc = render(&scene, &render::settings(W, H, 4, 64).with(|s| s.paths.roulette.continue_prob = 1.0));
    let (z, checked) = assert_regions_match(&acc, 4, expect, 2e-3, what);
    assert!(checked > W * H / 2);
    eprintln!("furnace {what}: worst |z| {z:.2}");
}

/// Spheres of a perfect conductor (eta 0, k 1: F = 1 at every angle) at three roughnesses
/// and a perfect mirror, in a uniform environment of 0.5: the mirror disappears, the rough
/// spheres show 0.5 A(wo), darker toward their rims where shadowing loses energy.
#[test]
fn furnace_spheres_reflect_the_environment_times_their_albedo() {
    assert_furnace_sphere("mirror", Bsdf::Mirror { reflectance: Vec3::ONE }, |_| DVec3::ONE);
    for alpha in [0.1, 0.3, 0.6] {
        let bsdf = Bsdf::Microfacet { alpha, eta: Vec3::ZERO, k: Vec3::ONE };
        assert_furnace_sphere(&format!("alpha {alpha}"), bsdf, |c| DVec3::splat(albedo(c, alpha as f64)));
    }
    // The albedo itself: 1 at normal incidence for a nearly smooth surface; shadowing takes
    // energy from a rough one, more at grazing angles.
    assert!((albedo(1.0, 0.1) - 1.0).abs() < 2e-3, "{}", albedo(1.0, 0.1));
    assert!(albedo(1.0, 0.6) < 0.9 && albedo(0.2, 0.3) < albedo(1.0, 0.3) - 0.05);
}

/// glTF materials (plastic, metal, half-metal, specular-glossiness) in the furnace: each
/// pixel is 0.5 times the directional albedo of glTF's BRDF as the specification writes it,
/// integrated here in f64.
#[test]
fn gltf_material_spheres_reflect_the_environment_times_their_albedo() {
    use crate::tests::common::gltf_brdf::{self, Surface};
    let base = DVec3::new(0.95, 0.64, 0.54);
    for (metallic, roughness) in [(0.0, 0.5), (1.0, 0.5), (0.5, 0.8)] {
        let bsdf =
            Bsdf::MetallicRoughness { base: base.as_vec3(), metallic: metallic as f32, roughness: roughness as f32 };
        let s = Surface::MetalRough { base, metallic, roughness };
        assert_furnace_sphere(&format!("glTF metallic {metallic} roughness {roughness}"), bsdf, |c| {
            gltf_brdf::albedo(s, DVec3::new((1.0 - c * c).sqrt(), 0.0, c), 300)
        });
    }
    let (specular, glossiness) = (DVec3::new(0.5, 0.4, 0.3), 0.4);
    let bsdf = Bsdf::SpecularGlossiness {
        diffuse: base.as_vec3(),
        specular: specular.as_vec3(),
        glossiness: glossiness as f32,
    };
    let s = Surface::SpecGloss { diffuse: base, specular, glossiness };
    assert_furnace_sphere("glTF specular-glossiness", bsdf, |c| {
        gltf_brdf::albedo(s, DVec3::new((1.0 - c * c).sqrt(), 0.0, c), 300)
    });
}
