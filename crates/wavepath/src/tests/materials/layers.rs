//! The glTF extension layers (transmission, ior, volume, specular, clearcoat, sheen) as
//! scattering models and in renders: their samplers against their densities, white
//! furnaces (energy kept or lost as the model says), and a glass slab against Fresnel and
//! Beer–Lambert in closed form.

use crate::bsdf::{Layered, Model, SHEEN_TABLE, sheen_albedo_table};
use crate::sampling::Sampler;
use crate::scene::{Bsdf, Camera, Environment, Layers, Material, Mesh, Scene};
use crate::tests::common;
use crate::tests::common::chi2::chi_square_with_missing;
use crate::tests::common::meshgen::quad;
use glam::{DVec3, Vec3, vec3};

fn wo_at(cos: f32, phi: f32) -> Vec3 {
    let s = (1.0 - cos * cos).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), cos)
}

fn u3(r: &mut Sampler) -> [f32; 3] {
    [r.next_f32(), r.next_f32(), r.next_f32()]
}

/// A layered model with the sheen scaling its material would have seen from `cos_o`.
fn layered(base: Vec3, metallic: f32, roughness: f32, l: &Layers, cos_o: f32) -> Model {
    let m = Layered::new(base, metallic, roughness, l.transmission, l);
    let table: [f32; SHEEN_TABLE] = sheen_albedo_table(l.sheen_roughness);
    Model::Layered(m.seen_from(cos_o, &table))
}

fn surfaces() -> Vec<(&'static str, Vec3, f32, f32, Layers)> {
    let white = Vec3::ONE;
    vec![
        (
            "clearcoat on a white base",
            white,
            0.0,
            1.0,
            Layers { clearcoat: 1.0, clearcoat_roughness: 0.3, ..Layers::default() },
        ),
        (
            "clearcoat on a rough metal",
            white,
            1.0,
            0.6,
            Layers { clearcoat: 0.7, clearcoat_roughness: 0.35, ..Layers::default() },
        ),
        (
            "sheen on a white base",
            white,
            0.0,
            1.0,
            Layers { sheen_color: white, sheen_roughness: 0.5, ..Layers::default() },
        ),
        (
            "coloured sheen",
            vec3(0.8, 0.3, 0.1),
            0.0,
            0.7,
            Layers { sheen_color: vec3(0.2, 0.9, 0.5), sheen_roughness: 0.3, ..Layers::default() },
        ),
        (
            "specular colour and ior",
            vec3(0.6, 0.6, 0.6),
            0.0,
            0.5,
            Layers { specular: 0.5, specular_color: vec3(1.0, 0.5, 2.0), ior: 1.8, ..Layers::default() },
        ),
        ("rough transmission", white, 0.0, 0.5, Layers { transmission: 1.0, thickness: 1.0, ..Layers::default() }),
        ("half transmission, thin", vec3(0.9, 0.7, 0.5), 0.0, 0.6, Layers { transmission: 0.5, ..Layers::default() }),
        (
            "everything",
            vec3(0.7, 0.5, 0.3),
            0.3,
            0.5,
            Layers {
                transmission: 0.4,
                thickness: 1.0,
                clearcoat: 0.5,
                clearcoat_roughness: 0.4,
                sheen_color: vec3(0.5, 0.5, 0.5),
                sheen_roughness: 0.6,
                specular: 0.8,
                ior: 1.4,
                ..Layers::default()
            },
        ),
    ]
}

/// The continuous lobes are sampled as `pdf` says (the delta transmission's samples are
/// the mass the density leaves out).
#[test]
fn layered_samplers_match_their_pdfs() {
    for (i, (name, base, metallic, roughness, l)) in surfaces().into_iter().enumerate() {
        for (j, cos) in [0.9f32, 0.35].into_iter().enumerate() {
            let m = layered(base, metallic, roughness, &l, cos);
            let wo = wo_at(cos, 0.7);
            chi_square_with_missing(
                &format!("{name}, cos wo {cos}"),
                700 + (i * 10 + j) as u64,
                |r| m.sample(wo, u3(r)).filter(|s| !s.delta).map(|s| s.wi.as_dvec3()),
                &|d: DVec3| m.pdf(wo, d.as_vec3()) as f64,
                true,
            );
        }
    }
}

#[test]
fn layered_sample_weights_are_f_cos_over_pdf() {
    let mut r = Sampler::for_sample(31, 0, 0);
    for (name, base, metallic, roughness, l) in surfaces() {
        let m = layered(base, metallic, roughness, &l, 0.6);
        let wo = wo_at(0.6, 1.0);
        for _ in 0..2000 {
            let Some(s) = m.sample(wo, u3(&mut r)) else { continue };
            if s.delta {
                assert!(s.wi.z < 0.0 && (s.wi.length() - 1.0).abs() < 1e-5, "{name}: {s:?}");
                continue;
            }
            assert!((s.pdf - m.pdf(wo, s.wi)).abs() <= 1e-3 * s.pdf, "{name}");
            let expect = m.eval(wo, s.wi) * s.wi.z / s.pdf;
            assert!((s.weight - expect).abs().max_element() <= 1e-3 * expect.max_element().max(1e-3), "{name}");
        }
    }
}

/// Mean sample weight (the directional albedo, reflection and transmission together) and
/// its standard error, from `n` samples. Refracted samples carry radiance scaled by
/// 1 / eta^2 (compressed into a narrower cone); `eta` (1 for none) undoes it, so that the
/// mean is the energy sent on.
fn albedo_energy(m: &Model, wo: Vec3, n: usize, seed: u64, eta: f32) -> (DVec3, DVec3) {
    let mut r = Sampler::for_sample(seed, 0, 0);
    let (mut s, mut s2) = (DVec3::ZERO, DVec3::ZERO);
    for _ in 0..n {
        if let Some(x) = m.sample(wo, u3(&mut r)) {
            let refracted = x.delta && x.wi.z < 0.0;
            let w = (x.weight * if refracted { eta * eta } else { 1.0 }).as_dvec3();
            s += w;
            s2 += w * w;
        }
    }
    let mean = s / n as f64;
    let var = (s2 / n as f64 - mean * mean).max(DVec3::ZERO);
    (mean, (var / n as f64).map(f64::sqrt))
}

fn albedo(m: &Model, wo: Vec3, n: usize, seed: u64) -> (DVec3, DVec3) {
    albedo_energy(m, wo, n, seed, 1.0)
}

/// White furnaces. A smooth transmitting dielectric with no absorption sends on all the
/// energy it receives (what its Fresnel reflection does not take, the transmission does:
/// 1, thin or refracting, from either side; refracted radiance is 1 / eta^2 of it); rough, it loses what single-scattering GGX loses; a clearcoat or a
/// sheen on a white base never gives more than it receives. Bounds are 5 standard errors
/// (a false failure has probability below 3e-7 per comparison).
#[test]
fn layered_white_furnaces() {
    let white = Vec3::ONE;
    for (k, cos) in [1.0f32, 0.8, 0.5, 0.25].into_iter().enumerate() {
        let wo = wo_at(cos, 0.3);
        for thickness in [0.0, 1.0] {
            for inside in [false, true] {
                let l = Layers { transmission: 1.0, thickness, ior: 1.5, ..Layers::default() };
                let mut m = Layered::new(white, 0.0, 0.0, 1.0, &l);
                if inside && thickness > 0.0 {
                    m = m.inside();
                }
                let (a, se) =
                    albedo_energy(&Model::Layered(m), wo, 20_000, 40 + k as u64, if m.thin { 1.0 } else { m.eta });
                let what = format!("smooth transmission, thickness {thickness}, inside {inside}, cos {cos}");
                assert!(((a - DVec3::ONE).abs() - 5.0 * se).max_element() < 2e-3, "{what}: albedo {a} +- {se}");
            }
        }
        let rough =
            Layered::new(white, 0.0, 0.5, 1.0, &Layers { transmission: 1.0, thickness: 1.0, ..Layers::default() });
        let (a, se) = albedo_energy(&Model::Layered(rough), wo, 100_000, 50 + k as u64, rough.eta);
        assert!((a - 5.0 * se).max_element() <= 1.0 && a.min_element() > 0.8, "rough transmission cos {cos}: {a}");
        for (name, l) in [
            ("clearcoat", Layers { clearcoat: 1.0, clearcoat_roughness: 0.3, ..Layers::default() }),
            ("smooth clearcoat", Layers { clearcoat: 1.0, clearcoat_roughness: 0.0, ..Layers::default() }),
            ("sheen", Layers { sheen_color: white, sheen_roughness: 0.5, ..Layers::default() }),
            ("rough sheen", Layers { sheen_color: white, sheen_roughness: 1.0, ..Layers::default() }),
        ] {
            let m = layered(white, 0.0, 1.0, &l, cos);
            let (a, se) = albedo(&m, wo, 100_000, 60 + k as u64);
            assert!((a - 5.0 * se).max_element() <= 1.0, "{name} on white, cos {cos}: albedo {a} +- {se}");
            // The base under the layer still reflects most of the light.
            assert!(a.min_element() > 0.6, "{name} on white, cos {cos}: albedo {a}");
        }
    }
}

/// The sheen table is the sheen lobe's albedo: checked against an independent estimate
/// (uniform hemisphere sampling of the same f cos).
#[test]
fn sheen_albedo_table_is_the_lobes_albedo() {
    for r in [0.3f32, 0.7, 1.0] {
        let table = sheen_albedo_table(r);
        let l = Layers { sheen_color: Vec3::ONE, sheen_roughness: r, ..Layers::default() };
        // The sheen lobe alone: the model with it less the model without it (the base
        // under it is not scaled until the model is seen from a direction).
        let m = Model::Layered(Layered::new(Vec3::ZERO, 0.0, 1.0, 0.0, &l));
        let bare = Model::Layered(Layered::new(Vec3::ZERO, 0.0, 1.0, 0.0, &Layers::default()));
        let mut rng = Sampler::for_sample(77, 0, 0);
        for k in [8usize, 20, 31] {
            let cos = k as f32 / (SHEEN_TABLE - 1) as f32;
            let wo = wo_at(cos, 0.0);
            let n = 200_000;
            let mut s = 0.0f64;
            for _ in 0..n {
                let (a, b) = rng.next_2d();
                let wi = crate::sampling::warp::uniform_hemisphere(a, b);
                let f = m.eval(wo, wi).x - bare.eval(wo, wi).x;
                s += (f * wi.z) as f64 / crate::sampling::warp::UNIFORM_HEMISPHERE_PDF as f64;
            }
            let e = s / n as f64;
            assert!((e - table[k] as f64).abs() < 0.01 + 0.02 * e, "roughness {r}, cos {cos}: {e} vs {}", table[k]);
            assert!((0.0..=1.0).contains(&table[k]));
        }
    }
}

#[test]
fn layered_has_no_nan_or_inf() {
    let mut r = Sampler::for_sample(88, 0, 0);
    let dirs = [Vec3::Z, -Vec3::Z, Vec3::X, wo_at(1e-7, 0.0), wo_at(-1e-7, 1.0), wo_at(0.5, 0.0), wo_at(-0.5, 0.0)];
    let us = [[0.0; 3], [1.0 - f32::EPSILON; 3], [0.5; 3], [0.0, 1.0 - f32::EPSILON, 0.5]];
    for (_, base, metallic, roughness, l) in surfaces() {
        for rough in [roughness, 0.0, 1.0] {
            for inside in [false, true] {
                let mut m = Layered::new(base, metallic, rough, l.transmission, &l);
                if inside {
                    m = m.inside();
                }
                let m = Model::Layered(m.seen_from(0.5, &sheen_albedo_table(l.sheen_roughness)));
                let check = |wo: Vec3, wi: Vec3, u: [f32; 3]| {
                    let f = m.eval(wo, wi);
                    assert!(f.is_finite() && f.min_element() >= 0.0, "{m:?} {wo} {wi}");
                    assert!(m.pdf(wo, wi).is_finite() && m.pdf(wo, wi) >= 0.0, "{m:?} {wo} {wi}");
                    if let Some(s) = m.sample(wo, u) {
                        assert!(s.wi.is_finite() && s.weight.is_finite() && s.pdf > 0.0, "{m:?} {wo} {s:?}");
                    }
                };
                for &wo in &dirs {
                    for &wi in &dirs {
                        for &u in &us {
                            check(wo, wi, u);
                        }
                    }
                }
                for _ in 0..2000 {
                    let wo = wo_at(r.next_f32() * 2.0 - 1.0, r.next_f32() * 6.3);
                    let wi = wo_at(r.next_f32() * 2.0 - 1.0, r.next_f32() * 6.3);
                    check(wo, wi, u3(&mut r));
                }
            }
        }
    }
}

/// The closed box [lo, hi] with outward-facing quads of material `m`.
fn boxed(mesh: &mut Mesh, lo: Vec3, hi: Vec3, m: u32) {
    for a in 0..3 {
        let (u, v) = ((a + 1) % 3, (a + 2) % 3);
        let d = hi - lo;
        let (mut du, mut dv) = (Vec3::ZERO, Vec3::ZERO);
        du[u] = d[u];
        dv[v] = d[v];
        let mut top = lo;
        top[a] = hi[a];
        // e_u x e_v = e_a: counter-clockwise seen from +a on the top face, reversed below.
        quad(mesh, [top, top + du, top + du + dv, top + dv], m);
        quad(mesh, [lo, lo + dv, lo + du + dv, lo + du], m);
    }
}

/// A clear glass slab (transmission 1, ior 1.5, white, smooth) of thickness d absorbing by
/// Beer–Lambert (attenuation colour c at distance D: sigma = -ln c / D), between the camera
/// and a white emitter of radiance 1, seen at normal incidence (a 2-degree field of view).
/// Each pixel sees the slab's transmittance, with the multiple reflections inside:
/// T = (1 - F)^2 a / (1 - F^2 a^2), a = exp(-sigma d), F = ((n - 1) / (n + 1))^2 = 0.04
/// (the model's Schlick Fresnel at normal incidence). Every path ends in the emitter (1)
/// or in the black sky, so the image mean is a binomial-like estimate: within 5 standard
/// errors of T per channel (false failure below 1e-6), in both integrators.
#[test]
fn glass_slab_transmits_as_fresnel_and_beer_lambert_say() {
    let (d, dist) = (0.5f32, 1.0f32);
    let c = vec3(0.5, 0.7, 0.9);
    let mut mesh = Mesh::default();
    boxed(&mut mesh, vec3(-5.0, -5.0, 0.0), vec3(5.0, 5.0, d), 0);
    // The emitter faces the camera (+z).
    let z = -1.0;
    quad(&mut mesh, [vec3(-20.0, -20.0, z), vec3(20.0, -20.0, z), vec3(20.0, 20.0, z), vec3(-20.0, 20.0, z)], 1);
    let layers = Layers {
        transmission: 1.0,
        ior: 1.5,
        thickness: d,
        attenuation_color: c,
        attenuation_distance: dist,
        ..Layers::default()
    };
    let glass = Material {
        bsdf: Bsdf::MetallicRoughness { base: Vec3::ONE, metallic: 0.0, roughness: 0.0 },
        layers: Some(Box::new(layers)),
        ..Material::diffuse("glass", Vec3::ONE)
    };
    let scene = Scene {
        name: "glass slab".into(),
        mesh,
        materials: vec![glass, Material::emitter("light", Vec3::ONE)],
        camera: Camera::look_at(vec3(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y, 2.0, 1.0),
        env: Environment::None,
        ..Scene::default()
    };
    let f = 0.04f64;
    let a = (c.as_dvec3().map(f64::ln) * (d / dist) as f64).map(f64::exp);
    let t = (1.0 - f).powi(2) * a / (DVec3::ONE - f * f * a * a);
    let mut s = common::render::small_settings(16, 16, 16, 512);
    s.paths.roulette.continue_prob = 1.0;
    let n = (16 * 16 * 512) as f64;
    for (which, (acc, st)) in
        [("wavefront", common::render::wavefront(&scene, &s)), ("recursive", common::render::recursive(&scene, &s))]
    {
        assert_eq!(st.invalid_samples, 0);
        let mean = acc.pixels.iter().map(|p| p.mean().as_dvec3()).sum::<DVec3>() / acc.pixels.len() as f64;
        let se = (t * (DVec3::ONE - t) / n).map(f64::sqrt);
        assert!(
            ((mean - t).abs() - 5.0 * se).max_element() < 1e-4,
            "{which}: transmittance {mean}, closed form {t} (+- {se})"
        );
        // The single pass alone, (1 - F)^2 a, is lower by the reflections' share.
        let single = (1.0 - f).powi(2) * a;
        assert!((mean - single).min_element() > -5.0 * se.max_element(), "{which}: {mean} vs single pass {single}");
    }
}
