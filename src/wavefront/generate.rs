//! Stage 1: camera rays for every (pixel, sample) slot of a wave.

use super::queues::PathQueue;
use crate::integrator::Transport;

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

/// Fills the path queue with the wave's camera rays, in slot order.
pub fn generate(t: &Transport, q: &mut PathQueue, wave: &Wave, width: usize, height: usize, spp: u32) {
    q.clear();
    for slot in 0..wave.len() as u32 {
        let (pixel, sample) = wave.pixel_sample(slot);
        let (x, y) = (pixel % width as u32, pixel / width as u32);
        let key = t.path_key(pixel, sample);
        q.push_camera(t.camera_ray_keyed(x, y, width, height, key, spp), key, slot);
    }
}
