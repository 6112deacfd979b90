//! Sampling routines against their stated densities: a chi-square goodness-of-fit test over
//! bins of (cos theta, phi) (expected counts are the pdf integrated over each bin by
//! quadrature; bins expecting fewer than 5 samples are pooled; p-value threshold 1e-3, fixed
//! seeds), and a quadrature check that each pdf integrates to 1 over the sphere.

mod patterns;

use crate::lights::{EmissiveTriangles, Infinite, SampledLight};
use crate::sampling::{Frame, Sampler, warp};
use crate::scene::{Material, Mesh, Scene};
use crate::tests::common::chi2::chi_square;
use crate::tests::common::special::{gamma_q, ln_gamma};
use glam::{DVec3, Vec3};
use std::f64::consts::{PI, TAU};

fn f32x3(r: &mut Sampler) -> [f32; 3] {
    [r.next_f32(), r.next_f32(), r.next_f32()]
}

#[test]
fn p_values_of_the_test_itself() {
    // Known values: Q(1, x) = e^-x; chi-square with 10 dof at 18.307 has p = 0.05.
    assert!((gamma_q(1.0, 2.0) - (-2.0f64).exp()).abs() < 1e-12);
    assert!((gamma_q(5.0, 18.307 / 2.0) - 0.05).abs() < 1e-4);
    // Table values for 100 dof: the 5% and 95% critical values are 124.342 and 77.929.
    assert!((gamma_q(50.0, 124.342 / 2.0) - 0.05).abs() < 1e-4);
    assert!((gamma_q(50.0, 77.929 / 2.0) - 0.95).abs() < 1e-4);
    assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
}

#[test]
fn a_wrong_pdf_is_rejected() {
    // The test has power: cosine-distributed samples do not pass as uniform.
    let result = std::panic::catch_unwind(|| {
        chi_square(
            "cosine as uniform",
            1,
            |r| {
                let (u, v) = r.next_2d();
                Some(warp::cosine_hemisphere(u, v).as_dvec3())
            },
            &|d| if d.z > 0.0 { 1.0 / TAU } else { 0.0 },
        )
    });
    assert!(result.is_err());
}

#[test]
fn uniform_hemisphere_matches_its_pdf() {
    assert!((warp::UNIFORM_HEMISPHERE_PDF as f64 - 1.0 / TAU).abs() < 1e-7);
    chi_square(
        "uniform hemisphere",
        11,
        |r| {
            let (u, v) = r.next_2d();
            Some(warp::uniform_hemisphere(u, v).as_dvec3())
        },
        &|d| if d.z > 0.0 { warp::UNIFORM_HEMISPHERE_PDF as f64 } else { 0.0 },
    );
}

#[test]
fn cosine_hemisphere_matches_its_pdf() {
    chi_square(
        "cosine hemisphere",
        12,
        |r| {
            let (u, v) = r.next_2d();
            Some(warp::cosine_hemisphere(u, v).as_dvec3())
        },
        &|d| warp::cosine_hemisphere_pdf(d.z as f32) as f64,
    );
}

/// The infinite light's cosine sampling about a tilted normal (exercises the frame too);
/// the stated pdf is radiance / weight.
#[test]
fn infinite_light_sampling_matches_its_pdf() {
    let n = Vec3::new(0.3, -0.5, 0.8).normalize();
    let light = SampledLight::Infinite(Infinite { upper: Vec3::ZERO, all: Vec3::splat(2.0), map: None });
    let nd = n.as_dvec3();
    chi_square(
        "infinite light (cosine about a tilted normal)",
        13,
        |r| {
            let s = light.sample(Vec3::ZERO, n, f32x3(r))?;
            let stated = 2.0 / s.weight.x as f64;
            let cos = s.wi.as_dvec3().dot(nd);
            assert!((stated - cos / PI).abs() < 1e-3 * (1.0 + stated), "stated pdf {stated} vs cos/pi {}", cos / PI);
            Some(s.wi.as_dvec3())
        },
        &|d| d.dot(nd).max(0.0) / PI,
    );
    // The frame maps +Z to the normal.
    assert!((Frame::new(n).to_world(Vec3::Z) - n).length() < 1e-6);
}

/// Solid-angle pdf of uniform area sampling of a rectangle seen from `p`.
fn rect_pdf(p: DVec3, center: DVec3, normal: DVec3, dx: DVec3, dy: DVec3, d: DVec3) -> f64 {
    let denom = d.dot(normal);
    if denom >= 0.0 {
        return 0.0; // back side or parallel: the light is one-sided
    }
    let t = (center - p).dot(normal) / denom;
    if t <= 0.0 {
        return 0.0;
    }
    let q = p + t * d - center;
    let (s, u) = (q.dot(dx) / dx.length_squared(), q.dot(dy) / dy.length_squared());
    if s.abs() > 0.5 || u.abs() > 0.5 {
        return 0.0;
    }
    let area = dx.length() * dy.length();
    t * t / (area * -denom)
}

#[test]
fn area_light_sampling_matches_its_pdf() {
    let (center, normal, dx, dy) =
        (Vec3::new(0.3, 0.2, 1.0), -Vec3::Z, Vec3::new(1.6, 0.0, 0.0), Vec3::new(0.0, 0.9, 0.0));
    let radiance = Vec3::splat(3.0);
    let light = SampledLight::Area {
        position: center,
        normal,
        dim_x: dx,
        dim_y: dy,
        area: dx.length() * dy.length(),
        radiance,
        cs184_pdf: false,
    };
    let (c, nn, ddx, ddy) = (center.as_dvec3(), normal.as_dvec3(), dx.as_dvec3(), dy.as_dvec3());
    let pdf = move |d: DVec3| rect_pdf(DVec3::ZERO, c, nn, ddx, ddy, d);
    chi_square(
        "area light",
        14,
        |r| {
            let s = light.sample(Vec3::ZERO, Vec3::Z, f32x3(r))?;
            let d = s.wi.as_dvec3();
            let stated = 3.0 / s.weight.x as f64;
            assert!((stated - pdf(d)).abs() < 1e-3 * pdf(d), "stated pdf {stated} vs geometric {}", pdf(d));
            Some(d)
        },
        &pdf,
    );
}

/// Ray–triangle distance (Möller–Trumbore in f64), for the reference pdf.
fn tri_t(o: DVec3, d: DVec3, [a, b, c]: [DVec3; 3]) -> Option<(f64, DVec3)> {
    let (e1, e2) = (b - a, c - a);
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det.abs() < 1e-14 {
        return None;
    }
    let tv = o - a;
    let u = tv.dot(pv) / det;
    let qv = tv.cross(e1);
    let v = d.dot(qv) / det;
    let t = e2.dot(qv) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then(|| (t, e1.cross(e2).normalize()))
}

/// Emissive triangles: a triangle chosen by area, a point uniform on it; two-sided.
#[test]
fn emissive_triangle_sampling_matches_its_pdf() {
    let tris = [
        [Vec3::new(-1.0, -0.5, 1.0), Vec3::new(1.0, -0.5, 1.2), Vec3::new(0.0, 1.0, 0.8)],
        [Vec3::new(-1.5, 0.5, -0.5), Vec3::new(-0.6, 0.8, -1.5), Vec3::new(-1.2, -0.6, -1.0)],
        [Vec3::new(0.8, 0.1, -0.4), Vec3::new(1.4, 0.3, -0.2), Vec3::new(1.1, 1.0, -0.9)],
    ];
    let mut mesh = Mesh::default();
    for t in &tris {
        let b = mesh.positions.len() as u32;
        mesh.positions.extend(t);
        mesh.triangles.push([b, b + 1, b + 2]);
        mesh.material_ids.push(0);
    }
    let scene = Scene { mesh, materials: vec![Material::emitter("e", Vec3::splat(2.0))], ..Scene::default() };
    let light = SampledLight::Emissive(EmissiveTriangles::new(&scene).unwrap());
    let dt: Vec<[DVec3; 3]> = tris.iter().map(|t| t.map(|v| v.as_dvec3())).collect();
    let total: f64 = dt.iter().map(|[a, b, c]| 0.5 * (b - a).cross(c - a).length()).sum();
    let pdf = move |d: DVec3| -> f64 {
        dt.iter().filter_map(|&t| tri_t(DVec3::ZERO, d, t)).map(|(t, n)| t * t / (total * d.dot(n).abs())).sum()
    };
    chi_square(
        "emissive triangles",
        15,
        |r| {
            let s = light.sample(Vec3::ZERO, Vec3::Z, f32x3(r))?;
            let d = s.wi.as_dvec3();
            let stated = 2.0 / s.weight.x as f64;
            assert!((stated - pdf(d)).abs() < 2e-3 * pdf(d), "stated pdf {stated} vs geometric {}", pdf(d));
            Some(d)
        },
        &pdf,
    );
}

/// The concentric disk map is uniform: pdf 1/pi on the unit disk (binned as the direction
/// (x, y, sqrt(1 - r^2)), whose pdf in solid angle is cos theta / pi: Malley's method).
#[test]
fn concentric_disk_is_uniform() {
    chi_square(
        "concentric disk (via Malley)",
        16,
        |r| {
            let (u, v) = r.next_2d();
            let p = warp::concentric_disk(u, v).as_dvec2();
            Some(DVec3::new(p.x, p.y, (1.0 - p.length_squared()).max(0.0).sqrt()).normalize())
        },
        &|d| d.z.max(0.0) / PI,
    );
}

/// A 16x8 map with a black row, a bright patch near the zenith and colours of different
/// luminance: its light samples, and the half-and-half mixture with a hemisphere light about
/// a tilted normal (the black row made dim there: a sample of no light at all is declined,
/// which is right but not a density), against densities written here from their
/// definitions. Contrasts stay moderate so that the bins' quadrature, which does not follow
/// texel edges, stays well inside the test's noise. The map's texel
/// (i, j) is drawn with probability proportional to luminance (Rec. 709) x sin(theta) at
/// the row's centre, uniformly in (u, v) inside it (u = phi / 2pi with phi = atan2(-z, x) +
/// pi, v = theta / pi with theta from +Y); so its solid-angle density is that weight over
/// the sum of weights x texel area in (u, v), divided by 2 pi^2 sin(theta).
/// False-failure probability 1e-3 per test (p-value threshold; fixed seeds).
#[test]
fn environment_map_sampling_matches_luminance_times_sin_theta() {
    use crate::scene::EnvMap;
    use std::sync::Arc;
    let (w, h) = (16usize, 8usize);
    let texels = |black: f32| -> Vec<Vec3> {
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                match (x, y) {
                    (_, 5) => Vec3::splat(black),
                    (3..=5, 1) => Vec3::new(2.0, 1.5, 1.0),
                    _ => Vec3::new(0.2 + 0.1 * (x % 4) as f32, 0.1 + 0.1 * (y % 3) as f32, 0.5),
                }
            })
            .collect()
    };
    // The density of texels `t`, coded from the definition above.
    let density = |t: Vec<Vec3>| {
        let lum = |c: Vec3| 0.2126 * c.x as f64 + 0.7152 * c.y as f64 + 0.0722 * c.z as f64;
        let weight = move |x: usize, y: usize| lum(t[y * w + x]) * ((y as f64 + 0.5) / h as f64 * PI).sin();
        let total: f64 = (0..w * h).map(|i| weight(i % w, i / w)).sum::<f64>() / (w * h) as f64;
        move |d: DVec3| {
            let d = d.normalize();
            let theta = d.y.clamp(-1.0, 1.0).acos();
            let phi = (-d.z).atan2(d.x) + PI;
            let x = ((phi / TAU * w as f64) as usize).min(w - 1);
            let y = ((theta / PI * h as f64) as usize).min(h - 1);
            let s = theta.sin();
            if s <= 0.0 { 0.0 } else { weight(x, y) / total / (2.0 * PI * PI * s) }
        }
    };
    let n = Vec3::new(0.3, 0.8, -0.5).normalize();
    let map = |black: f32| Some(Arc::new(EnvMap::from_texels("test".into(), w, h, texels(black)).unwrap()));
    let alone = Infinite { map: map(0.0), ..Default::default() };
    chi_square(
        "environment map",
        21,
        |r| {
            let (a, b) = r.next_2d();
            alone.sample(n, [a, b]).map(|s| s.wi.as_dvec3())
        },
        &density(texels(0.0)),
    );
    let mixed = Infinite { upper: Vec3::splat(0.5), map: map(0.05), ..Default::default() };
    let (map_pdf, nd) = (density(texels(0.05)), n.as_dvec3());
    chi_square(
        "environment map mixed with a hemisphere light",
        22,
        |r| {
            let (a, b) = r.next_2d();
            mixed.sample(n, [a, b]).map(|s| s.wi.as_dvec3())
        },
        &|d| 0.5 * map_pdf(d) + 0.5 * d.normalize().dot(nd).max(0.0) / PI,
    );
}
