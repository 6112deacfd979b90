//! The BSDF models against their own stated densities and against physics: chi-square of
//! every sampler against its pdf, reciprocity, energy (albedo <= 1, a white furnace for a
//! perfect rough conductor), Fresnel choice frequencies for glass, and no NaN or Inf for any
//! input.

use crate::bsdf::{Dielectric, Distribution, Lambert, Microfacet, Mirror, Model, Pbr, fresnel_dielectric};
use crate::sampling::Sampler;
use crate::tests::common::chi2::chi_square_with_missing;
use crate::tests::common::gltf_brdf::{self, Surface};
use glam::{DVec3, Vec3};

fn wo_at(cos: f32, phi: f32) -> Vec3 {
    let s = (1.0 - cos * cos).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), cos)
}

fn u3(r: &mut Sampler) -> [f32; 3] {
    [r.next_f32(), r.next_f32(), r.next_f32()]
}

fn metal(alpha: f32, distribution: Distribution) -> Model {
    Model::Microfacet(Microfacet { alpha, eta: Vec3::new(0.2, 0.9, 1.1), k: Vec3::new(3.9, 2.4, 2.2), distribution })
}

fn glossy_models() -> Vec<(String, Model)> {
    let mut v = vec![("lambert".to_string(), Model::Lambert(Lambert { albedo: Vec3::new(0.9, 0.5, 0.1) }))];
    for d in [Distribution::Beckmann, Distribution::Ggx] {
        for a in [0.1, 0.3, 0.8] {
            v.push((format!("{d:?} alpha {a}"), metal(a, d)));
        }
    }
    for (name, s) in pbr_surfaces() {
        v.push((name, pbr_model(s)));
    }
    v
}

/// glTF surfaces: plastic, metal and half-metal at several roughnesses, and a
/// specular-glossiness one. (Sharp lobes, too narrow for the albedo test's quadrature, are
/// named so: it skips them, as it skips alpha 0.1.)
fn pbr_surfaces() -> Vec<(String, Surface)> {
    let base = DVec3::new(0.9, 0.5, 0.2);
    let mut v = Vec::new();
    for (metallic, roughness) in [(0.0, 0.5), (1.0, 0.45), (0.5, 0.8), (0.0, 1.0), (1.0, 0.25)] {
        let sharp = if roughness < 0.3 { " (sharp)" } else { "" };
        v.push((
            format!("glTF metallic {metallic} roughness {roughness}{sharp}"),
            Surface::MetalRough { base, metallic, roughness },
        ));
    }
    let spec = Surface::SpecGloss { diffuse: base, specular: DVec3::new(0.3, 0.25, 0.2), glossiness: 0.4 };
    v.push(("glTF specular-glossiness".into(), spec));
    v
}

fn pbr_model(s: Surface) -> Model {
    Model::Pbr(match s {
        Surface::MetalRough { base, metallic, roughness } => {
            Pbr::metallic_roughness(base.as_vec3(), metallic as f32, roughness as f32)
        }
        Surface::SpecGloss { diffuse, specular, glossiness } => {
            Pbr::specular_glossiness(diffuse.as_vec3(), specular.as_vec3(), glossiness as f32)
        }
    })
}

/// Rough glTF surfaces seen at grazing angles: every sample's weight stays near the albedo
/// (the lobe choice must not leave the diffuse lobe a tiny probability where the diffuse
/// term is large: those samples would be fireflies).
#[test]
fn rough_pbr_sample_weights_stay_bounded_at_grazing_angles() {
    let mut r = Sampler::for_sample(10, 0, 0);
    for (name, s) in pbr_surfaces().into_iter().filter(|(n, _)| !n.contains("sharp")) {
        let m = pbr_model(s);
        for cos in [0.3f32, 0.1, 0.05, 0.02] {
            let wo = wo_at(cos, 0.4);
            let mut worst = 0.0f32;
            for _ in 0..20_000 {
                if let Some(s) = m.sample(wo, u3(&mut r)) {
                    worst = worst.max(s.weight.max_element());
                }
            }
            assert!(worst < 2.5, "{name} cos {cos}: a sample of weight {worst}");
        }
    }
}

/// The model equals glTF's BRDF as the specification writes it, direction by direction.
#[test]
fn pbr_is_the_gltf_specification_brdf() {
    let mut r = Sampler::for_sample(9, 0, 0);
    for (name, s) in pbr_surfaces() {
        let m = pbr_model(s);
        let mut worst = 0.0f64;
        for _ in 0..5000 {
            let v = wo_at(r.next_f32().max(0.02), r.next_f32() * std::f32::consts::TAU);
            let l = wo_at(r.next_f32().max(0.02), r.next_f32() * std::f32::consts::TAU);
            let want = gltf_brdf::brdf(s, v.as_dvec3(), l.as_dvec3());
            let got = m.eval(v, l).as_dvec3();
            let rel = ((got - want).abs() / want.max(DVec3::splat(1e-3))).max_element();
            worst = worst.max(rel);
        }
        assert!(worst < 2e-3, "{name}: worst relative difference {worst}");
    }
}

#[test]
fn every_non_delta_sampler_matches_its_pdf() {
    for (i, (name, m)) in glossy_models().into_iter().enumerate() {
        for (j, cos) in [0.9f32, 0.35].into_iter().enumerate() {
            let wo = wo_at(cos, 0.7);
            chi_square_with_missing(
                &format!("{name}, cos wo {cos}"),
                100 + (i * 10 + j) as u64,
                |r| m.sample(wo, u3(r)).map(|s| s.wi.as_dvec3()),
                &|d: DVec3| m.pdf(wo, d.as_vec3()) as f64,
                true,
            );
        }
    }
}

#[test]
fn sample_weights_are_f_cos_over_pdf() {
    let mut r = Sampler::for_sample(3, 0, 0);
    for (name, m) in glossy_models() {
        let wo = wo_at(0.6, 1.0);
        for _ in 0..2000 {
            let Some(s) = m.sample(wo, u3(&mut r)) else { continue };
            assert!(!s.delta && (s.pdf - m.pdf(wo, s.wi)).abs() <= 1e-3 * s.pdf, "{name}");
            let expect = m.eval(wo, s.wi) * s.wi.z / s.pdf;
            assert!((s.weight - expect).abs().max_element() <= 1e-3 * expect.max_element().max(1e-3), "{name}");
        }
    }
}

#[test]
fn non_delta_lobes_are_reciprocal() {
    let mut r = Sampler::for_sample(4, 0, 0);
    for (name, m) in glossy_models() {
        for _ in 0..2000 {
            let a = wo_at(r.next_f32(), r.next_f32() * std::f32::consts::TAU);
            let b = wo_at(r.next_f32(), r.next_f32() * std::f32::consts::TAU);
            let (f, g) = (m.eval(a, b), m.eval(b, a));
            assert!((f - g).abs().max_element() <= 1e-4 * f.max_element().max(1e-3), "{name}: {f} vs {g}");
        }
    }
}

/// Directional albedo by stratified quadrature of f cos over the hemisphere (independent of
/// the samplers).
fn albedo_quadrature(m: &Model, wo: Vec3, n: usize) -> Vec3 {
    let mut sum = DVec3::ZERO;
    for i in 0..n {
        for j in 0..n {
            let c = (i as f32 + 0.5) / n as f32;
            let phi = (j as f32 + 0.5) / n as f32 * std::f32::consts::TAU;
            let wi = wo_at(c, phi);
            sum += (m.eval(wo, wi) * c).as_dvec3();
        }
    }
    (sum * (std::f64::consts::TAU / (n * n) as f64)).as_vec3()
}

#[test]
fn albedo_is_at_most_one_in_every_direction() {
    let mut r = Sampler::for_sample(5, 0, 0);
    for (name, m) in glossy_models() {
        for cos in [1.0f32, 0.7, 0.3, 0.05] {
            let wo = wo_at(cos, 0.3);
            // The sampler's estimate (weights) and the quadrature agree and are <= 1.
            let n = 100_000;
            let mut est = DVec3::ZERO;
            for _ in 0..n {
                if let Some(s) = m.sample(wo, u3(&mut r)) {
                    est += s.weight.as_dvec3();
                }
            }
            let est = (est / n as f64).as_vec3();
            // glTF's layering (diffuse weighted by 1 - F(v.h)) reflects slightly more than it
            // receives at grazing incidence: the specification's model, kept as written.
            let bound = if name.starts_with("glTF") && cos < 0.1 { 1.05 } else { 1.0 + 1e-3 };
            assert!(est.max_element() <= bound, "{name} cos {cos}: albedo {est}");
            if !name.contains("0.1") && !name.contains("sharp") {
                let q = albedo_quadrature(&m, wo, 400);
                assert!(q.max_element() <= bound + 1e-3, "{name} cos {cos}: albedo {q}");
                assert!((q - est).abs().max_element() < 0.02, "{name} cos {cos}: {q} vs sampled {est}");
            }
        }
    }
}

/// With eta = 0 and k > 0 the conductor reflects everything (F = 1); at small roughness the
/// microfacet model then loses almost no energy, so its albedo is 1.
#[test]
fn perfect_rough_conductor_is_a_white_furnace() {
    let mut r = Sampler::for_sample(6, 0, 0);
    for d in [Distribution::Beckmann, Distribution::Ggx] {
        let m = Model::Microfacet(Microfacet { alpha: 0.05, eta: Vec3::ZERO, k: Vec3::ONE, distribution: d });
        for cos in [1.0f32, 0.7, 0.4] {
            let wo = wo_at(cos, 0.0);
            let n = 100_000;
            let mut est = 0.0f64;
            for _ in 0..n {
                if let Some(s) = m.sample(wo, u3(&mut r)) {
                    assert!((s.weight.x - s.weight.z).abs() < 1e-6);
                    est += s.weight.x as f64;
                }
            }
            let est = est / n as f64;
            assert!((0.98..=1.0005).contains(&est), "{d:?} cos {cos}: albedo {est}");
        }
    }
}

#[test]
fn glass_chooses_reflection_with_fresnel_probability() {
    let g = Dielectric { reflectance: Vec3::ONE, transmittance: Vec3::ONE, eta: 1.5, reflect: true };
    let mut r = Sampler::for_sample(7, 0, 0);
    for (eta, cos) in [(1.5f32, 0.9f32), (1.5, 0.2), (1.0 / 1.5, 0.9), (1.0 / 1.5, 0.75)] {
        let m = Model::Dielectric(Dielectric { eta, ..g });
        let wo = wo_at(cos, 2.0);
        let f = fresnel_dielectric(cos, eta) as f64;
        let n = 200_000;
        let mut reflected = 0usize;
        for _ in 0..n {
            let s = m.sample(wo, u3(&mut r)).unwrap();
            assert!(s.delta && (s.wi.length() - 1.0).abs() < 1e-5);
            if s.wi.z > 0.0 {
                reflected += 1;
                assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
                assert_eq!(s.weight, Vec3::ONE);
            } else {
                // Radiance through the interface scales by 1 / eta^2.
                assert!((s.weight.x - 1.0 / (eta * eta)).abs() < 1e-5);
            }
        }
        let p = reflected as f64 / n as f64;
        let sd = (f * (1.0 - f) / n as f64).sqrt().max(1e-9);
        assert!((p - f).abs() <= 5.0 * sd + 1e-9, "eta {eta} cos {cos}: reflected {p}, Fresnel {f}");
    }
    // Delta lobes have no density and no value for any given pair of directions.
    let m = Model::Dielectric(g);
    assert_eq!(m.eval(wo_at(0.5, 0.0), wo_at(0.5, 3.0)), Vec3::ZERO);
    assert_eq!(m.pdf(wo_at(0.5, 0.0), wo_at(0.5, 3.0)), 0.0);
    let mirror = Model::Mirror(Mirror { reflectance: Vec3::new(0.9, 0.8, 0.7) });
    let s = mirror.sample(wo_at(0.3, 1.0), [0.5; 3]).unwrap();
    assert!(s.delta && s.weight == Vec3::new(0.9, 0.8, 0.7) && (s.wi.z - 0.3).abs() < 1e-6);
}

#[test]
fn no_nan_or_inf_for_any_input() {
    let mut r = Sampler::for_sample(8, 0, 0);
    let mut models = glossy_models().into_iter().map(|(_, m)| m).collect::<Vec<_>>();
    for a in [0.0, 1e-9, 1e-4, 1.0, 5.0] {
        for d in [Distribution::Beckmann, Distribution::Ggx] {
            models.push(metal(a, d));
            models.push(Model::Microfacet(Microfacet { alpha: a, eta: Vec3::ZERO, k: Vec3::ZERO, distribution: d }));
        }
    }
    for eta in [1.5, 1.0 / 1.5, 1.0] {
        for reflect in [true, false] {
            models.push(Model::Dielectric(Dielectric {
                reflectance: Vec3::ONE,
                transmittance: Vec3::ONE,
                eta,
                reflect,
            }));
        }
    }
    models.push(Model::Mirror(Mirror { reflectance: Vec3::ONE }));
    let dirs = [Vec3::Z, -Vec3::Z, Vec3::X, wo_at(1e-7, 0.0), wo_at(-1e-7, 1.0), wo_at(0.5, 0.0), wo_at(-0.5, 0.0)];
    let us = [[0.0; 3], [1.0 - f32::EPSILON; 3], [0.5; 3], [0.0, 1.0 - f32::EPSILON, 0.5]];
    for m in &models {
        let check = |wo: Vec3, wi: Vec3, u: [f32; 3]| {
            assert!(m.eval(wo, wi).is_finite() && m.eval(wo, wi).min_element() >= 0.0, "{m:?} {wo} {wi}");
            assert!(m.pdf(wo, wi).is_finite() && m.pdf(wo, wi) >= 0.0, "{m:?} {wo} {wi}");
            if let Some(s) = m.sample(wo, u) {
                assert!(
                    s.wi.is_finite() && s.weight.is_finite() && s.pdf.is_finite() && s.pdf > 0.0,
                    "{m:?} {wo} {s:?}"
                );
            }
        };
        for &wo in &dirs {
            for &wi in &dirs {
                for &u in &us {
                    check(wo, wi, u);
                }
            }
        }
        for _ in 0..5000 {
            let wo = wo_at(r.next_f32() * 2.0 - 1.0, r.next_f32() * 6.3);
            let wi = wo_at(r.next_f32() * 2.0 - 1.0, r.next_f32() * 6.3);
            check(wo, wi, u3(&mut r));
        }
    }
}
