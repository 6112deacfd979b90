//! Chi-square goodness-of-fit of a direction sampler against its stated density, over
//! bins of (cos theta, phi): expected counts are the pdf integrated over each bin by
//! quadrature; bins expecting fewer than 5 samples are pooled; p-value threshold 1e-3.

use super::special::gamma_q;
use crate::sampling::Sampler;
use glam::DVec3;
use std::f64::consts::TAU;

pub const N_COS: usize = 24;
pub const N_PHI: usize = 48;
pub const SAMPLES: usize = 400_000;
pub const P_THRESHOLD: f64 = 1e-3;

/// Direction of (cos theta, phi) about +Z.
pub fn dir(c: f64, phi: f64) -> DVec3 {
    let s = (1.0 - c * c).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), c)
}

pub fn bin_of(d: DVec3) -> usize {
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
pub fn expected_mass(pdf: &dyn Fn(DVec3) -> f64) -> Vec<f64> {
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

/// Draws SAMPLES directions (None: the routine declined, counted as mass outside the
/// pdf's support), bins them and tests against the pdf. Returns the p-value.
pub fn chi_square(
    name: &str,
    seed: u64,
    sample: impl FnMut(&mut Sampler) -> Option<DVec3>,
    pdf: &dyn Fn(DVec3) -> f64,
) -> f64 {
    chi_square_with_missing(name, seed, sample, pdf, false)
}

/// [`chi_square`] for a routine whose density integrates to less than 1 (`missing`): the
/// samples it declines form one more bin, expecting 1 minus the pdf's integral (a
/// microfacet BSDF's reflected half vectors that point below the surface).
pub fn chi_square_with_missing(
    name: &str,
    seed: u64,
    mut sample: impl FnMut(&mut Sampler) -> Option<DVec3>,
    pdf: &dyn Fn(DVec3) -> f64,
    missing: bool,
) -> f64 {
    let mut mass = expected_mass(pdf);
    let total: f64 = mass.iter().sum();
    if missing {
        assert!(total <= 1.0 + 2e-3, "{name}: pdf integrates to {total} > 1");
    } else {
        assert!((total - 1.0).abs() < 2e-3, "{name}: pdf integrates to {total}, not 1");
    }
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
    if missing {
        mass.push((1.0 - total).max(0.0));
        counts.push(declined as u64);
    } else {
        // A routine may decline a sample of zero density (e.g. a direction exactly at the
        // horizon); more than a handful would be mass missing from the distribution.
        assert!(declined <= SAMPLES / 10_000, "{name}: the routine declined {declined} samples");
    }
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
