//! How far a render is from the reference: the error measures the study reports.

use glam::DVec3;
use wavepath::{Accumulator, Film};

/// Added to the squared reference value in the relative MSE so black pixels do not divide
/// by zero (the usual choice, Rousselle et al. 2011).
pub const REL_MSE_EPSILON: f64 = 1e-2;

/// Errors of one render against the reference, over all pixels and the three linear channels.
///
/// A render's per-pixel sums ([`compare`]) give every field; an image alone ([`compare_film`],
/// e.g. a denoised one) gives the error against the reference (`rmse`, `rel_mse`), `ref_floor`
/// and `mean_spp`, while `ci95` and `predicted_rmse`, which come from the samples' variance,
/// do not exist for it and are NaN ([`ErrorStats::has_variance`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorStats {
    /// Root mean squared error.
    pub rmse: f64,
    /// Mean of (x - r)^2 / (r^2 + epsilon).
    pub rel_mse: f64,
    /// Mean over pixels and channels of the 95% confidence half-width of the pixel mean,
    /// 1.96 sqrt(var / n), from the render's own per-pixel sums: what the render believes its
    /// error is, without a reference.
    pub ci95: f64,
    /// The RMSE the render predicts from its own samples: sqrt of the mean variance of the
    /// pixel means (equals the expected RMSE of an unbiased render against the truth).
    pub predicted_rmse: f64,
    /// The RMSE the reference's own noise alone would add (sqrt of its mean variance of the
    /// mean): errors near this floor are not resolved by the reference.
    pub ref_floor: f64,
    /// Mean camera samples per pixel (differs from `-s` with adaptive sampling).
    pub mean_spp: f64,
}

impl ErrorStats {
    /// Whether `ci95` and `predicted_rmse` were measured (from per-pixel sums); they are NaN
    /// for an image compared without its samples ([`compare_film`]).
    pub fn has_variance(&self) -> bool {
        self.ci95.is_finite() && self.predicted_rmse.is_finite()
    }
}

/// The converged image and, per pixel, the variance of its mean.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    pub mean: Film,
    pub variance: Film,
}

impl Reference {
    pub fn from_accumulator(acc: &Accumulator) -> Self {
        let variance = Film {
            width: acc.width,
            height: acc.height,
            pixels: acc.pixels.iter().map(|p| p.variance_of_mean().as_vec3()).collect(),
        };
        Reference { mean: acc.to_film(), variance }
    }
}

/// Compares a render's per-pixel sums with the reference: every field of [`ErrorStats`].
pub fn compare(acc: &Accumulator, reference: &Reference) -> ErrorStats {
    let spp = acc.pixels.iter().map(|p| p.taken as f64).sum::<f64>() / acc.pixels.len().max(1) as f64;
    let mut e = compare_film(&acc.to_film(), reference, spp);
    let (mut ci, mut var) = (0.0, 0.0);
    for p in &acc.pixels {
        let half = p.variance_of_mean().max(DVec3::ZERO);
        ci += 1.96 * (half.x.sqrt() + half.y.sqrt() + half.z.sqrt());
        var += half.x + half.y + half.z;
    }
    let n = (acc.pixels.len() * 3).max(1) as f64;
    e.ci95 = ci / n;
    e.predicted_rmse = (var / n).sqrt();
    e
}

/// Compares an image with the reference when its samples are not at hand (a denoised
/// image): `rmse`, `rel_mse` and `ref_floor` as [`compare`] computes them (the same values
/// for a render's own film), `mean_spp` as given (the samples of the render behind it);
/// `ci95` and `predicted_rmse` are NaN: an image has no variance of its own, and a
/// denoised one's error is mostly bias, which no variance predicts.
pub fn compare_film(film: &Film, reference: &Reference, mean_spp: f64) -> ErrorStats {
    assert_eq!((film.width, film.height), (reference.mean.width, reference.mean.height), "image sizes differ");
    let (mut se, mut rel, mut floor) = (0.0, 0.0, 0.0);
    for ((x, r), rv) in film.pixels.iter().zip(&reference.mean.pixels).zip(&reference.variance.pixels) {
        let (x, r) = (x.as_dvec3(), r.as_dvec3());
        let d = x - r;
        se += d.dot(d);
        let rel_px = d * d / (r * r + DVec3::splat(REL_MSE_EPSILON));
        rel += rel_px.x + rel_px.y + rel_px.z;
        let rv = rv.as_dvec3();
        floor += rv.x + rv.y + rv.z;
    }
    let n = (film.pixels.len() * 3).max(1) as f64;
    ErrorStats {
        rmse: (se / n).sqrt(),
        rel_mse: rel / n,
        ci95: f64::NAN,
        predicted_rmse: f64::NAN,
        ref_floor: (floor / n).sqrt(),
        mean_spp,
    }
}

/// Least-squares slope of log(y) against log(x): the convergence order of an error curve.
pub fn log_log_slope(points: &[(f64, f64)]) -> f64 {
    let pts: Vec<(f64, f64)> =
        points.iter().filter(|(x, y)| *x > 0.0 && *y > 0.0).map(|(x, y)| (x.ln(), y.ln())).collect();
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    sxy / sxx
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn slope_of_a_power_law() {
        let pts: Vec<_> = (0..8).map(|i| (2f64.powi(i), 3.0 * 2f64.powi(i).powf(-0.5))).collect();
        assert!((log_log_slope(&pts) + 0.5).abs() < 1e-12);
    }

    #[test]
    fn errors_of_a_known_difference() {
        let mut acc = Accumulator::new(2, 1);
        for v in [1.0, 3.0] {
            acc.pixels[0].add(Vec3::splat(v)); // mean 2, variance of mean 1
            acc.pixels[1].add(Vec3::splat(1.0));
        }
        let reference = Reference {
            mean: Film { width: 2, height: 1, pixels: vec![Vec3::splat(1.0), Vec3::splat(1.0)] },
            variance: Film { width: 2, height: 1, pixels: vec![Vec3::splat(0.04), Vec3::ZERO] },
        };
        let e = compare(&acc, &reference);
        // Squared errors: 1 (x3 channels) and 0 (x3): mean 0.5.
        assert!((e.rmse - 0.5f64.sqrt()).abs() < 1e-12);
        assert!((e.rel_mse - 0.5 / 1.01).abs() < 1e-12);
        assert!((e.ci95 - 1.96 / 2.0).abs() < 1e-12);
        assert!((e.predicted_rmse - 0.5f64.sqrt()).abs() < 1e-12);
        assert!((e.ref_floor - 0.02f64.sqrt()).abs() < 1e-7);
        assert_eq!(e.mean_spp, 2.0);
        assert!(e.has_variance());
    }

    /// An image compared alone has the render's error against the reference, and no
    /// variance-based fields.
    #[test]
    fn an_image_alone_has_the_same_error_and_no_variance() {
        let mut acc = Accumulator::new(2, 1);
        for v in [1.0, 3.0] {
            acc.pixels[0].add(Vec3::splat(v));
            acc.pixels[1].add(Vec3::splat(0.5 * v));
        }
        let reference = Reference {
            mean: Film { width: 2, height: 1, pixels: vec![Vec3::splat(1.0), Vec3::splat(1.5)] },
            variance: Film { width: 2, height: 1, pixels: vec![Vec3::splat(0.04), Vec3::ZERO] },
        };
        let (sums, image) = (compare(&acc, &reference), compare_film(&acc.to_film(), &reference, 2.0));
        assert_eq!(
            (image.rmse, image.rel_mse, image.ref_floor, image.mean_spp),
            (sums.rmse, sums.rel_mse, sums.ref_floor, sums.mean_spp)
        );
        assert!(image.ci95.is_nan() && image.predicted_rmse.is_nan() && !image.has_variance());
    }
}
