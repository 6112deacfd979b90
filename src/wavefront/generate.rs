//! Stage 1: camera rays for every (pixel, sample) slot of a wave.

use super::queues::PathQueue;
use crate::integrator::Transport;
use crate::sampling::Sampler;

/// Which samples of which pixels a wave takes: slot s is sample `base + s % batch` of pixel
/// `pixels[s / batch]`.
#[derive(Clone, Copy, Debug)]
pub struct Wave<'p> {
    pub pixels: &'p [u32],
    pub base: u32,
    pub batch: u32,
}

impl Wave<'_> {
    pub fn len(&self) -> usize {
        self.pixels.len() * self.batch as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    #[inline]
    pub fn pixel_sample(&self, slot: u32) -> (u32, u32) {
        (self.pixels[(slot / self.batch) as usize], self.base + slot % self.batch)
    }
}

/// Fills the path queue with the wave's camera rays, in slot order. A pixel's samples are
/// consecutive slots, so the pixel's coordinates and the pixel part of the path key
/// ([`Sampler::pixel_key`], two of the key's three hashes) are computed once per pixel.
pub fn generate(t: &Transport, q: &mut PathQueue, wave: &Wave, width: usize, height: usize, spp: u32) {
    q.clear();
    let n = wave.len();
    q.ray.reserve(n);
    q.key.reserve(n);
    for &pixel in wave.pixels {
        let (x, y) = (pixel % width as u32, pixel / width as u32);
        let pixel_key = Sampler::pixel_key(t.seed, pixel as u64);
        for sample in wave.base..wave.base + wave.batch {
            let key = Sampler::sample_key(pixel_key, sample as u64);
            q.ray.push(t.camera_ray_keyed(x, y, width, height, key, spp));
            q.key.push(key);
        }
    }
    // The fields every camera path starts with are the same: filled field by field.
    q.start_camera_paths(n);
}
