use super::{AovSums, Film};
use glam::{DVec3, Vec3};

/// Running sums of one pixel's samples: enough for its mean, the variance of that mean, and
/// the reference's adaptive-sampling test.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelSums {
    pub sum: DVec3,
    pub sum_sq: DVec3,
    /// Sum of illuminance and of its square (the reference's s1, s2).
    pub s1: f64,
    pub s2: f64,
    /// Camera samples taken, including dropped ones.
    pub taken: u32,
    /// Samples that were finite and entered the sums.
    pub valid: u32,
}

impl PixelSums {
    /// Adds one sample; a NaN or Inf sample is counted as taken and dropped. Returns whether
    /// it was valid.
    #[inline]
    pub fn add(&mut self, l: Vec3) -> bool {
        self.taken += 1;
        if !l.is_finite() {
            return false;
        }
        let d = l.as_dvec3();
        self.sum += d;
        self.sum_sq += d * d;
        let y = crate::geometry::illuminance(l) as f64;
        self.s1 += y;
        self.s2 += y * y;
        self.valid += 1;
        true
    }

    #[inline]
    pub fn merge(&mut self, o: &PixelSums) {
        self.sum += o.sum;
        self.sum_sq += o.sum_sq;
        self.s1 += o.s1;
        self.s2 += o.s2;
        self.taken += o.taken;
        self.valid += o.valid;
    }

    pub fn mean(&self) -> Vec3 {
        if self.valid == 0 { Vec3::ZERO } else { (self.sum / self.valid as f64).as_vec3() }
    }

    /// Variance of the mean per channel, from the sample variance.
    pub fn variance_of_mean(&self) -> DVec3 {
        let n = self.valid as f64;
        if n < 2.0 {
            return DVec3::ZERO;
        }
        let var = (self.sum_sq - self.sum * self.sum / n) / (n - 1.0);
        var.max(DVec3::ZERO) / n
    }

    /// The reference's stopping rule: 1.96 sigma / sqrt(n) <= tolerance * mu.
    pub fn converged(&self, tolerance: f32) -> bool {
        let n = self.valid as f64;
        if n < 2.0 {
            return false;
        }
        let mu = self.s1 / n;
        let var = ((self.s2 - self.s1 * self.s1 / n) / (n - 1.0)).max(0.0);
        1.96 * (var / n).sqrt() <= tolerance as f64 * mu
    }
}

/// Per-pixel sums of a whole image (row 0 at the bottom, as the film).
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulator {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<PixelSums>,
    /// Each pixel's first-hit sums ([`super::AovSet::traced`]); empty when the render records
    /// none, so a render without AOVs keeps nothing more.
    pub aovs: Vec<AovSums>,
}

impl Accumulator {
    /// Samples taken per pixel of `region` (row-major, bottom row first).
    pub fn samples_taken_in(&self, region: crate::settings::Cell) -> Vec<u32> {
        let r = region;
        let mut out = Vec::with_capacity(r.w * r.h);
        for y in r.y..r.y + r.h {
            for x in r.x..r.x + r.w {
                out.push(self.pixels[y * self.width + x].taken);
            }
        }
        out
    }

    pub fn new(width: usize, height: usize) -> Self {
        Accumulator { width, height, pixels: vec![PixelSums::default(); width * height], aovs: Vec::new() }
    }

    /// As [`new`](Self::new), with first-hit sums for every pixel when `first_hits`.
    pub fn with_aovs(width: usize, height: usize, first_hits: bool) -> Self {
        let aovs = if first_hits { vec![AovSums::default(); width * height] } else { Vec::new() };
        Accumulator { aovs, ..Accumulator::new(width, height) }
    }

    /// The images of the output variables `set` (see [`super::AovImage::from_sums`]).
    pub fn aov_images(&self, set: crate::settings::AovSet) -> Vec<super::AovImage> {
        super::AovImage::from_sums(set, self.width, self.height, &self.pixels, &self.aovs)
    }

    /// The mean of every pixel, f32 linear RGB.
    pub fn to_film(&self) -> Film {
        Film { width: self.width, height: self.height, pixels: self.pixels.iter().map(|p| p.mean()).collect() }
    }

    pub fn samples_taken(&self) -> Vec<u32> {
        self.pixels.iter().map(|p| p.taken).collect()
    }

    pub fn invalid_samples(&self) -> u64 {
        self.pixels.iter().map(|p| (p.taken - p.valid) as u64).sum()
    }

    /// [`invalid_samples`](Self::invalid_samples) of the pixels in `region` alone.
    pub fn invalid_samples_in(&self, region: crate::settings::Cell) -> u64 {
        let r = region;
        (r.y..r.y + r.h)
            .flat_map(|y| &self.pixels[y * self.width + r.x..y * self.width + r.x + r.w])
            .map(|p| (p.taken - p.valid) as u64)
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drops_non_finite_samples_and_keeps_the_mean() {
        let mut p = PixelSums::default();
        assert!(p.add(Vec3::splat(1.0)));
        assert!(!p.add(Vec3::new(f32::NAN, 0.0, 0.0)));
        assert!(p.add(Vec3::splat(3.0)));
        assert!(!p.add(Vec3::splat(f32::INFINITY)));
        assert_eq!((p.taken, p.valid), (4, 2));
        assert_eq!(p.mean(), Vec3::splat(2.0));
        // Sample variance of {1, 3} is 2; of the mean 1.
        assert!((p.variance_of_mean().x - 1.0).abs() < 1e-12);
    }

    #[test]
    fn convergence_rule_matches_the_formula() {
        let mut p = PixelSums::default();
        for v in [1.0, 1.0, 1.0, 1.0] {
            p.add(Vec3::splat(v));
        }
        assert!(p.converged(1e-6), "zero variance converges");
        let mut q = PixelSums::default();
        for v in [0.0, 2.0, 0.0, 2.0] {
            q.add(Vec3::splat(v));
        }
        // mu = 1, sigma^2 = 4/3, I = 1.96 sqrt(1/3) = 1.1316.
        assert!(!q.converged(1.13) && q.converged(1.14));
        let black = {
            let mut b = PixelSums::default();
            b.add(Vec3::ZERO);
            b.add(Vec3::ZERO);
            b
        };
        assert!(black.converged(0.05), "a black pixel has nothing left to learn");
    }
}
