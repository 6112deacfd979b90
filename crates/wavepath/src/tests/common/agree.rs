//! Renders compared region by region: with each other, or with expected pixel values.
//!
//! Each comparison is a z-test on a region's sum of many samples (a region holds at least 16
//! pixels, so the central limit theorem applies to the sum even when single samples are heavy
//! tailed). Thresholds:
//! - **False failures**: the per-region threshold is Bonferroni's for a probability of at most
//!   [`FALSE_FAILURE`] that any region of one call fails by chance, and never under 5 sigma.
//! - **Heavy tails**: a rare bright sample can be missing from a render, and then its sample
//!   variance underestimates the truth. Two renders of one image estimate one variance, so the
//!   larger of the two estimates stands for both.
//! - **Seeds** are fixed, so each test's outcome is deterministic; the probability above is
//!   over the choice of seed, and a change of seed is a fair re-draw.

use glam::DVec3;
use wavepath::Accumulator;

/// Probability that one call fails although both sides have the same expectation.
pub const FALSE_FAILURE: f64 = 1e-6;

/// The |z| above which a region fails, with `comparisons` regions x channels tested.
pub fn z_threshold(comparisons: usize) -> f64 {
    // Two-sided normal tail P(|Z| > z) = erfc(z / sqrt 2) = Q(1/2, z^2 / 2).
    let tail = |z: f64| super::special::gamma_q(0.5, z * z / 2.0);
    let target = FALSE_FAILURE / comparisons.max(1) as f64;
    let (mut lo, mut hi) = (0.0f64, 40.0f64);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if tail(mid) > target { lo = mid } else { hi = mid }
    }
    hi.max(5.0)
}

/// Sum of means and of variances of the means over a `size` x `size` region, pixels where
/// `keep` holds.
fn region(acc: &Accumulator, size: usize, rx: usize, ry: usize, keep: &dyn Fn(usize, usize) -> bool) -> Region {
    let mut r = Region::default();
    for y in ry * size..(ry + 1) * size {
        for x in rx * size..(rx + 1) * size {
            if keep(x, y) {
                let p = &acc.pixels[y * acc.width + x];
                r.mean += p.mean().as_dvec3();
                r.var += p.variance_of_mean();
                r.pixels += 1;
            }
        }
    }
    r
}

#[derive(Default)]
struct Region {
    mean: DVec3,
    var: DVec3,
    pixels: usize,
}

/// Both renders estimate one image: every `size` x `size` region's mean agrees within the
/// threshold, the variance of each side being the larger of the two estimates, plus
/// `rel_tol` of the mean (for differences in rounding that are not noise). Returns the
/// largest |z| seen, or the first region that fails (or why nothing could be compared).
pub fn regions_agree(a: &Accumulator, b: &Accumulator, size: usize, rel_tol: f64, what: &str) -> Result<f64, String> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!("{what}: sizes differ"));
    }
    let all = |_: usize, _: usize| true;
    let (nx, ny) = (a.width / size, a.height / size);
    let z_max = z_threshold(nx * ny * 3);
    let (mut worst, mut tested) = (0.0f64, 0);
    for ry in 0..ny {
        for rx in 0..nx {
            let (ra, rb) = (region(a, size, rx, ry, &all), region(b, size, rx, ry, &all));
            for c in 0..3 {
                let d = (ra.mean[c] - rb.mean[c]).abs();
                let sd = (2.0 * ra.var[c].max(rb.var[c])).sqrt();
                let tol = rel_tol * ra.mean[c].abs().max(rb.mean[c].abs()) + 1e-9 * ra.pixels as f64;
                if sd == 0.0 {
                    if d > tol {
                        return Err(format!(
                            "{what}: region ({rx},{ry}) channel {c}: {} vs {} with zero variance",
                            ra.mean[c], rb.mean[c]
                        ));
                    }
                    continue;
                }
                tested += 1;
                let z = (d - tol).max(0.0) / sd;
                worst = worst.max(z);
                let n = ra.pixels as f64;
                if z >= z_max {
                    return Err(format!(
                        "{what}: region ({rx},{ry}) channel {c}: mean {} vs {} (sd {}, z = {z:.2} >= {z_max:.2})",
                        ra.mean[c] / n,
                        rb.mean[c] / n,
                        sd / n
                    ));
                }
            }
        }
    }
    if tested == 0 {
        return Err(format!("{what}: nothing to compare"));
    }
    Ok(worst)
}

/// [`regions_agree`], panicking with its message when the renders disagree.
pub fn assert_regions_agree(a: &Accumulator, b: &Accumulator, size: usize, rel_tol: f64, what: &str) -> f64 {
    regions_agree(a, b, size, rel_tol, what).unwrap_or_else(|e| panic!("{e}"))
}

/// Every `size` x `size` region's mean, over the pixels that have an expected value, is
/// within the threshold of the expected values' mean, plus `rel_tol` of it (for the error of
/// the expectation itself: a quadrature, or f32 against f64); exactly equal where the
/// estimate has no variance. Returns the largest |z| and the number of pixels checked, or the
/// first region that fails.
pub fn regions_match(
    acc: &Accumulator,
    size: usize,
    expected: impl Fn(usize, usize) -> Option<DVec3>,
    rel_tol: f64,
    what: &str,
) -> Result<(f64, usize), String> {
    let (nx, ny) = (acc.width / size, acc.height / size);
    let z_max = z_threshold(nx * ny * 3);
    let mut want = vec![None; acc.width * acc.height];
    for y in 0..ny * size {
        for x in 0..nx * size {
            want[y * acc.width + x] = expected(x, y);
        }
    }
    let has = |x: usize, y: usize| want[y * acc.width + x].is_some();
    let (mut worst, mut checked) = (0.0f64, 0);
    for ry in 0..ny {
        for rx in 0..nx {
            let r = region(acc, size, rx, ry, &has);
            if r.pixels == 0 {
                continue;
            }
            checked += r.pixels;
            let mut e = DVec3::ZERO;
            for y in ry * size..(ry + 1) * size {
                for x in rx * size..(rx + 1) * size {
                    e += want[y * acc.width + x].unwrap_or(DVec3::ZERO);
                }
            }
            let n = r.pixels as f64;
            for c in 0..3 {
                let d = (r.mean[c] - e[c]).abs();
                let tol = rel_tol * e[c].abs() + 1e-7 * n;
                let sd = r.var[c].sqrt();
                let z = if sd > 0.0 {
                    (d - tol).max(0.0) / sd
                } else if d <= tol {
                    0.0
                } else {
                    f64::INFINITY
                };
                worst = worst.max(z);
                if z >= z_max {
                    return Err(format!(
                        "{what}: region ({rx},{ry}) channel {c}, {} pixels: mean {} expected {} (sd {}, z = {z:.2})",
                        r.pixels,
                        r.mean[c] / n,
                        e[c] / n,
                        sd / n
                    ));
                }
            }
        }
    }
    Ok((worst, checked))
}

/// [`regions_match`], panicking with its message when a region does not match.
pub fn assert_regions_match(
    acc: &Accumulator,
    size: usize,
    expected: impl Fn(usize, usize) -> Option<DVec3>,
    rel_tol: f64,
    what: &str,
) -> (f64, usize) {
    regions_match(acc, size, expected, rel_tol, what).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn z_threshold_is_bonferronis() {
    // One comparison at 1e-6: 4.89 sigma, raised to the floor of 5; 1e4 comparisons: 1e-10
    // each, 6.47 sigma (normal tables).
    assert_eq!(z_threshold(1), 5.0);
    assert!((z_threshold(10_000) - 6.4674).abs() < 1e-3, "{}", z_threshold(10_000));
}
