//! Arbitrary output variables: what a render keeps beside the picture for a denoiser, a
//! compositor or an error estimate. The first-hit values are recorded once per camera sample
//! by the wavefront's AOV stage (only when asked for: a render without AOVs keeps no sums
//! and runs no stage) and summed per pixel in slot order, as the beauty's samples are, so
//! they are the same bits for any thread count and instruction set.
//!
//! The rule for where a sample's albedo and normal come from follows Open Image Denoise's
//! advice for its auxiliary images: the first hit that is not a delta surface (a mirror or
//! glass is seen through, along the path's own continuation); a camera ray that escapes
//! (directly or after delta surfaces) gives the background it sees, clamped to [0, 1], as
//! albedo and a zero normal (OIDN's "no surface here"); a path that ends on a delta surface
//! gives zeros. Depth and position are those of the camera ray's own hit, mirrors included.

use super::PixelSums;
use crate::settings::{Aov, AovSet};
use glam::{DVec3, Vec3};

/// What one camera sample recorded at its first hit (zeros until recorded).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AovSample {
    pub albedo: Vec3,
    pub normal: Vec3,
    pub position: Vec3,
    pub depth: f32,
    /// The camera ray hit a surface (depth and position are meaningful).
    pub hit: bool,
}

/// One pixel's sums of its samples' records.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AovSums {
    pub albedo: DVec3,
    pub normal: DVec3,
    pub position: DVec3,
    pub depth: f64,
    /// Samples whose camera ray hit a surface.
    pub hits: u32,
    /// Samples recorded.
    pub samples: u32,
}

impl AovSums {
    /// Adds one sample; a record with a non-finite value enters as zeros (never NaN or Inf in
    /// an output).
    #[inline]
    pub fn add(&mut self, s: &AovSample) {
        self.samples += 1;
        let finite = |v: Vec3| if v.is_finite() { v.as_dvec3() } else { DVec3::ZERO };
        self.albedo += finite(s.albedo);
        self.normal += finite(s.normal);
        if s.hit && s.position.is_finite() && s.depth.is_finite() {
            self.hits += 1;
            self.position += s.position.as_dvec3();
            self.depth += s.depth as f64;
        }
    }

    #[inline]
    pub fn merge(&mut self, o: &AovSums) {
        self.albedo += o.albedo;
        self.normal += o.normal;
        self.position += o.position;
        self.depth += o.depth;
        self.hits += o.hits;
        self.samples += o.samples;
    }

    /// Albedo and normal: means over the samples; depth and position: means over the samples
    /// that hit (zero where none did).
    fn value(&self, aov: Aov) -> [f32; 3] {
        let over = |v: DVec3, n: u32| if n == 0 { [0.0; 3] } else { (v / n as f64).as_vec3().to_array() };
        match aov {
            Aov::Albedo => over(self.albedo, self.samples),
            Aov::Normal => over(self.normal, self.samples),
            Aov::Position => over(self.position, self.hits),
            Aov::Depth => [if self.hits == 0 { 0.0 } else { (self.depth / self.hits as f64) as f32 }, 0.0, 0.0],
            Aov::Variance => [0.0; 3],
        }
    }
}

/// One output variable's image: its channels interleaved per pixel, rows bottom first as the
/// film's.
#[derive(Clone, Debug, PartialEq)]
pub struct AovImage {
    pub aov: Aov,
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl AovImage {
    /// Channels per pixel.
    pub fn channels(&self) -> usize {
        self.aov.channels().len()
    }

    /// Pixel (x, y)'s channels (y = 0 at the bottom).
    pub fn get(&self, x: usize, y: usize) -> &[f32] {
        let c = self.channels();
        let i = (y * self.width + x) * c;
        &self.data[i..i + c]
    }

    /// The image as a film (one-channel images in every channel): what the denoiser and the
    /// image writers take.
    pub fn to_film(&self) -> super::Film {
        let c = self.channels();
        let pixels = self
            .data
            .chunks_exact(c)
            .map(|p| if c == 1 { Vec3::splat(p[0]) } else { Vec3::new(p[0], p[1], p[2]) })
            .collect();
        super::Film { width: self.width, height: self.height, pixels }
    }

    /// The images of `set` from a render's sums: `aovs` (empty when no first hits were
    /// recorded) and `pixels` (the variance).
    pub fn from_sums(
        set: AovSet,
        width: usize,
        height: usize,
        pixels: &[PixelSums],
        aovs: &[AovSums],
    ) -> Vec<AovImage> {
        set.iter()
            .map(|aov| {
                let c = aov.channels().len();
                let mut data = Vec::with_capacity(width * height * c);
                for (i, p) in pixels.iter().enumerate().take(width * height) {
                    let v = match aov {
                        Aov::Variance => p.variance_of_mean().as_vec3().to_array(),
                        _ => aovs.get(i).map_or([0.0; 3], |s| s.value(aov)),
                    };
                    data.extend(v.iter().take(c).map(|x| if x.is_finite() { *x } else { 0.0 }));
                }
                AovImage { aov, width, height, data }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn means_count_misses_for_albedo_and_only_hits_for_depth() {
        let mut p = AovSums::default();
        p.add(&AovSample { albedo: Vec3::ONE, normal: Vec3::Z, position: Vec3::X, depth: 2.0, hit: true });
        p.add(&AovSample { albedo: Vec3::ZERO, ..AovSample::default() });
        p.add(&AovSample { albedo: Vec3::splat(f32::NAN), depth: f32::INFINITY, hit: true, ..AovSample::default() });
        assert_eq!(p.value(Aov::Albedo), [1.0 / 3.0; 3]);
        assert_eq!(p.value(Aov::Normal), [0.0, 0.0, 1.0 / 3.0]);
        assert_eq!(p.value(Aov::Depth)[0], 2.0);
        assert_eq!(p.value(Aov::Position), [1.0, 0.0, 0.0]);
        assert_eq!(AovSums::default().value(Aov::Depth), [0.0; 3]);
    }
}
