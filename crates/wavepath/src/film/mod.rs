//! The image being rendered and how it is written to disk.

mod accum;
mod aov;
mod rate;
mod write;

pub use accum::{Accumulator, PixelSums};
pub use aov::{AovImage, AovSample, AovSums};
pub use rate::{rate_film, write_rate_image};
pub use write::{Tonemap, write_image, write_image_with_aovs};

use glam::Vec3;

/// Linear RGB radiance per pixel, row 0 at the *bottom* (CS184 convention: pixel (0,0) is
/// the bottom-left); writers flip rows for top-down file formats.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<Vec3>,
}

impl Film {
    pub fn new(width: usize, height: usize) -> Self {
        Film { width, height, pixels: vec![Vec3::ZERO; width * height] }
    }

    #[inline]
    pub fn get(&self, x: usize, y: usize) -> Vec3 {
        self.pixels[y * self.width + x]
    }

    #[inline]
    pub fn set(&mut self, x: usize, y: usize, v: Vec3) {
        self.pixels[y * self.width + x] = v;
    }

    /// True when every pixel is finite: no NaN or Inf may ever reach an output.
    pub fn all_finite(&self) -> bool {
        self.pixels.iter().all(|p| p.is_finite())
    }
}
