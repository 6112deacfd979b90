//! Stage 1: camera rays for every (active pixel, sample) of a wave.

use super::CHUNK;
use super::queues::PathQueue;
use crate::integrator::Transport;
use rayon::prelude::*;

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

/// Fills the path queue with the wave's camera rays.
pub fn generate(t: &Transport, q: &mut PathQueue, wave: &Wave, width: usize, height: usize, spp: u32) {
    let n = wave.len();
    q.ensure(n);
    q.len = n;
    q.chunks(n, CHUNK).into_par_iter().for_each(|c| {
        for k in 0..c.slot.len() {
            let slot = (c.start + k) as u32;
            let (pixel, sample) = wave.pixel_sample(slot);
            let (x, y) = (pixel % width as u32, pixel / width as u32);
            let r = t.camera_ray(x, y, width, height, sample, spp);
            (c.ox[k], c.oy[k], c.oz[k]) = (r.origin.x, r.origin.y, r.origin.z);
            (c.dx[k], c.dy[k], c.dz[k]) = (r.dir.x, r.dir.y, r.dir.z);
            (c.tmin[k], c.tmax[k]) = (r.tmin, r.tmax);
            c.slot[k] = slot;
            (c.tr[k], c.tg[k], c.tb[k]) = (1.0, 1.0, 1.0);
            (c.lr[k], c.lg[k], c.lb[k]) = (0.0, 0.0, 0.0);
            c.depth[k] = 0;
            c.alive[k] = 0;
        }
    });
}
