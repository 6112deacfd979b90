//! Sampling routines against their stated densities: a chi-square goodness-of-fit test over
//! bins of (cos theta, phi) (expected counts are the pdf integrated over each bin by
//! quadrature; bins expecting fewer than 5 samples are pooled; p-value threshold 1e-3, fixed
//! seeds), and a quadrature check that each pdf integrates to 1 over the sphere.

use glam::{DVec3, Vec3};
use std::f64::consts::{PI, TAU};
use wavepath::lights::{EmissiveTriangles, Infinite, SampledLight};
use wavepath::sampling::{Frame, Sampler, warp};
use wavepath::scene::{Material, Mesh, Scene};

const N_COS: usize = 24;
const N_PHI: usize = 48;
const SAMPLES: usize = 400_000;
const P_THRESHOLD: f64 = 1e-3;

/// Direction of (cos theta, phi) about +Z.
fn dir(c: f64, phi: f64) -> DVec3 {
    let s = (1.0 - c * c).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), c)
}

fn bin_of(d: DVec3) -> usize {
    let d = d.normalize();
    let c = ((d.z + 1.0) * 0.5 * N_COS as f64).floor().clamp(0.0, N_COS as f64 - 1.0) as usize;
    let mut phi = d.y.atan2(d.x);
    if phi < 0.0 {
        phi += TAU;
    }
    let p = (phi / TAU * N_PHI as f64).floor().clamp(0.0, N_PHI as f64 - 1.0) as usize;
    c * N_PHI + p
}

/// The pdf (solid angle) integrated over each bin, by the midpoint rule on a k x k grid;
/// bins where the pdf has an edge (some subcells zero, some not) are redone at 128 x 128.
fn expected_mass(pdf: &dyn Fn(DVec3) -> f64) -> Vec<f64> {
    let (dc, dp) = (2.0 / N_COS as f64, TAU / N_PHI as f64);
    let integrate = |ci: usize, pi: usize, k: usize| -> (f64, bool, bool) {
        let (mut sum, mut any_zero, mut any_pos) = (0.0, false, false);
        for a in 0..k {
            for b in 0..k {
                let c = -1.0 + dc * (ci as f64 + (a as f64 + 0.5) / k as f64);
                let phi = dp * (pi as f64 + (b as f64 + 0.5) / k as f64);
                let v = pdf(dir(c, phi));
                assert!(v.is_finite() && v >= 0.0, "pdf {v}");
                if v > 0.0 {
                    any_pos = true;
                } else {
                    any_zero = true;
                }
                sum += v;
            }
        }
        (sum * dc * dp / (k * k) as f64, any_zero, any_pos)
    };
    // Coarse pass; then bins with an edge of the support in them, or next to a bin that
    // has support (a sliver of support can fall between all coarse midpoints), are redone.
    let coarse: Vec<(f64, bool, bool)> = (0..N_COS * N_PHI).map(|i| integrate(i / N_PHI, i % N_PHI, 8)).collect();
    let mut out = vec![0.0; N_COS * N_PHI];
    for ci in 0..N_COS {
        for pi in 0..N_PHI {
            let (m, zero, pos) = coarse[ci * N_PHI + pi];
            let mut near_support = false;
            for dc in -1i64..=1 {
                for dp in -1i64..=1 {
                    let c = ci as i64 + dc;
                    if c < 0 || c >= N_COS as i64 {
                        continue;
                    }
                    let p = (pi as i64 + dp).rem_euclid(N_PHI as i64);
                    near_support |= coarse[c as usize * N_PHI + p as usize].2;
                }
            }
            out[ci * N_PHI + pi] = if zero && (pos || near_support) { integrate(ci, pi, 128).0 } else { m };
        }
    }
    out
}

/// ln Gamma(x), Lanczos approximation (g = 7, 9 terms).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (TAU).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Upper regularised incomplete gamma Q(a, x): the chi-square survival function is
/// Q(dof / 2, chi2 / 2).
fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let lead = (-x + a * x.ln() - ln_gamma(a)).exp();
    if x < a + 1.0 {
        let (mut sum, mut term, mut n) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            n += 1.0;
            term *= x / n;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * lead
    } else {
        // Continued fraction (modified Lentz).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-15 {
                break;
            }
        }
        lead * h
    }
}

/// Draws SAMPLES directions (None: the routine declined, counted as mass outside the
/// pdf's support), bins them and tests against the pdf. Returns the p-value.
fn chi_square(
    name: &str,
    seed: u64,
    mut sample: impl FnMut(&mut Sampler) -> Option<DVec3>,
    pdf: &dyn Fn(DVec3) -> f64,
) -> f64 {
    let mass = expected_mass(pdf);
    let total: f64 = mass.iter().sum();
    assert!((total - 1.0).abs() < 2e-3, "{name}: pdf integrates to {total}, not 1");
    let mut counts = vec![0u64; mass.len()];
    let mut rng = Sampler::for_sample(seed, 0, 0);
    let mut declined = 0usize;
    for _ in 0..SAMPLES {
        match sample(&mut rng) {
            Some(d) => {
                assert!(d.is_finite() && (d.length() - 1.0).abs() < 1e-3, "{name}: direction {d}");
                counts[bin_of(d)] += 1;
            }
            None => declined += 1,
        }
    }
    // A routine may decline a sample of zero density (e.g. a direction exactly at the
    // horizon); more than a handful would be mass missing from the distribution.
    assert!(declined <= SAMPLES / 10_000, "{name}: the routine declined {declined} samples");
    // Pool bins expecting fewer than 5 samples into one.
    let n = SAMPLES as f64;
    let (mut chi2, mut bins) = (0.0, 0usize);
    let (mut pooled_e, mut pooled_o) = (0.0, 0.0);
    for (m, &o) in mass.iter().zip(&counts) {
        let e = m * n;
        if e < 5.0 {
            pooled_e += e;
            pooled_o += o as f64;
        } else {
            chi2 += (o as f64 - e).powi(2) / e;
            bins += 1;
        }
    }
    if pooled_e >= 5.0 {
        chi2 += (pooled_o - pooled_e).powi(2) / pooled_e;
        bins += 1;
    } else {
        if pooled_o > 5.0 + 5.0 * pooled_e.max(1.0).sqrt() {
            for (i, (m, &o)) in mass.iter().zip(&counts).enumerate() {
                if m * n < 5.0 && o > 0 {
                    eprintln!("bin {i} (cos {}, phi {}): mass {m:e} observed {o}", i / N_PHI, i % N_PHI);
                }
            }
            panic!("{name}: {pooled_o} samples where the pdf expects {pooled_e}");
        }
    }
    let dof = (bins - 1) as f64;
    let p = gamma_q(dof / 2.0, chi2 / 2.0);
    eprintln!("{name}: chi2 {chi2:.1} over {bins} bins, p = {p:.4}");
    assert!(p > P_THRESHOLD, "{name}: chi-square {chi2:.1} with {dof} dof, p = {p:e}");
    p
}

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
