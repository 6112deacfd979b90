//! Stage 1: camera rays for every (pixel, sample) slot of a wave.

use super::lanes::width::{LaneKernel, ShadeWidth};
use super::queues::PathQueue;
use crate::integrator::Transport;
use crate::sampling::rng8::Hasher;
use crate::sampling::{Sampler, SamplerKind, rng8};
use glam::Vec3;

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

    #[cfg(test)]
    #[inline]
    pub fn pixel_sample(&self, slot: u32) -> (u32, u32) {
        (self.pixels[(slot / self.batch) as usize], self.base + slot % self.batch)
    }
}

/// Fills the path queue with the wave's camera rays, in slot order. A pixel's samples are
/// consecutive slots, so the pixel's coordinates and the pixel part of the path key
/// ([`Sampler::pixel_key`], two of the key's three hashes) are computed once per pixel.
/// With `lanes` (a pinhole camera: `super::Lanes`; eight lanes at every width), the rays of eight samples are set
/// up lane-parallel: the keys and jitters hashed or drawn eight at a time (independent
/// numbers, or a pattern's: Sobol, stratified), the directions' normalisations together.
pub fn generate(
    t: &Transport,
    lanes: Option<ShadeWidth>,
    q: &mut PathQueue,
    wave: &Wave,
    width: usize,
    height: usize,
    spp: u32,
) {
    q.clear();
    let n = wave.len();
    q.ray.reserve(n);
    q.key.reserve(n);
    // Eight lanes hold eight samples of one pixel: with fewer per pixel (a viewer's or a
    // part's small batches) most lanes would be wasted, and the one-by-one loop is cheaper.
    if let Some(w) = lanes.filter(|_| wave.batch as usize >= L) {
        w.dispatch(Pinhole { t, q: &mut *q, wave, width, height, spp });
        q.start_camera_paths(n);
        return;
    }
    for &pixel in wave.pixels {
        let (x, y) = (pixel % width as u32, pixel / width as u32);
        let pixel_key = Sampler::pixel_key(t.streams.seed, pixel as u64);
        for sample in wave.base..wave.base + wave.batch {
            let key = t.streams.pattern.sample_key(pixel_key, sample as u64);
            q.ray.push(t.camera_ray_keyed(x, y, width, height, key, spp));
            q.key.push(key);
        }
    }
    // The fields every camera path starts with are the same: filled field by field.
    q.start_camera_paths(n);
}

/// Lanes per group of camera rays.
const L: usize = 8;

/// The pinhole camera's rays of the wave, eight samples of a pixel at a time; the same rays
/// as [`Transport::camera_ray_keyed`] (the same functions, per lane, and the streams'
/// numbers as `rng8` draws them for the shading kernels).
/// [`pinhole_lanes`]' arguments, run at the chosen width's instructions (eight lanes at any).
struct Pinhole<'a, 's, 'w> {
    t: &'a Transport<'s>,
    q: &'a mut PathQueue,
    wave: &'a Wave<'w>,
    width: usize,
    height: usize,
    spp: u32,
}

impl LaneKernel for Pinhole<'_, '_, '_> {
    #[inline(always)]
    fn run<H: Hasher, const W: usize>(self, h: H) {
        let Pinhole { t, q, wave, width, height, spp } = self;
        pinhole_lanes(h, t, q, wave, width, height, spp)
    }
}

#[inline(always)]
fn pinhole_lanes<H: Hasher>(
    h: H,
    t: &Transport,
    q: &mut PathQueue,
    wave: &Wave,
    width: usize,
    height: usize,
    spp: u32,
) {
    let pattern = t.streams.pattern;
    let hashed = pattern.kind == SamplerKind::Independent;
    for &pixel in wave.pixels {
        let (x, y) = (pixel % width as u32, pixel / width as u32);
        let pixel_key = Sampler::pixel_key(t.streams.seed, pixel as u64);
        let mut sample = wave.base;
        let end = wave.base + wave.batch;
        while sample < end {
            let m = ((end - sample) as usize).min(L);
            // The keys and jitters of `Sampler::sample_key` and `Transport::camera_ray_keyed`,
            // hashed eight at a time (lanes past `m` are computed and dropped).
            let (keys, (jx, jy)) = if hashed {
                let mut inputs = [0u64; L];
                for (j, input) in inputs.iter_mut().enumerate() {
                    *input = Sampler::sample_input(pixel_key, (sample + j as u32) as u64);
                }
                let keys = h.splitmix64_x8(&inputs);
                let jitter = if spp <= 1 {
                    ([0.5f32; L], [0.5f32; L])
                } else {
                    for j in 0..L {
                        inputs[j] = Sampler::vertex_input(keys[j], 0);
                    }
                    let streams = rng8::for_vertex_x8(h, &inputs);
                    rng8::next_2d_x8(h, &streams, 0)
                };
                (keys, jitter)
            } else {
                // A patterned sampler's keys are the pixel's with the sample's index, and
                // the eight streams are one pattern's (Sobol's points drawn eight at a time).
                let mut keys = [0u64; L];
                let mut streams = [Sampler::default(); L];
                for j in 0..L {
                    keys[j] = pattern.sample_key(pixel_key, (sample + j as u32) as u64);
                    streams[j] = pattern.vertex(keys[j], 0);
                }
                let jitter = if spp <= 1 { ([0.5f32; L], [0.5f32; L]) } else { rng8::next_2d_x8(h, &streams, 0) };
                (keys, jitter)
            };
            let mut rays = [crate::geometry::Ray::new(Vec3::ZERO, Vec3::ZERO); L];
            for j in 0..L {
                rays[j] = t.camera.pinhole_ray(x, y, width, height, jx[j], jy[j]);
            }
            q.ray.extend_from_slice(&rays[..m]);
            q.key.extend_from_slice(&keys[..m]);
            sample += m as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Settings;

    /// The lane-parallel camera rays (when the CPU runs them) are bit for bit the rays of
    /// `Transport::camera_ray_keyed`, for batches that fill 8 lanes and batches that do not,
    /// with every sampler.
    #[test]
    fn wave_rays_are_the_single_camera_rays() {
        let scene = crate::load::default_scene();
        let (w, h) = (13, 7);
        for (spp, batch, sampler) in [
            (16, 16, SamplerKind::Independent),
            (16, 5, SamplerKind::Independent),
            (1, 1, SamplerKind::Independent),
            (64, 11, SamplerKind::Independent),
            (16, 16, SamplerKind::Sobol),
            (64, 21, SamplerKind::Sobol),
            (1, 1, SamplerKind::Sobol),
            (16, 16, SamplerKind::Stratified),
            (9, 9, SamplerKind::Stratified),
        ] {
            let mut s = Settings::default();
            s.image.width = w;
            s.image.height = h;
            s.sampling.spp = spp;
            s.sampling.sampler = sampler;
            let t = Transport::new(&scene, &s, &crate::effects::Effects::of(&scene, &s));
            let pixels: Vec<u32> = (0..(w * h) as u32).step_by(3).collect();
            let wave = Wave { pixels: &pixels, base: 2, batch };
            for lanes in std::iter::once(None).chain(ShadeWidth::all().into_iter().map(Some)) {
                let mut q = PathQueue::default();
                generate(&t, lanes, &mut q, &wave, w, h, spp);
                assert_eq!(q.len(), wave.len());
                for slot in 0..wave.len() as u32 {
                    let (pixel, sample) = wave.pixel_sample(slot);
                    let key = t.streams.path_key(pixel, sample);
                    let (x, y) = (pixel % w as u32, pixel / w as u32);
                    assert_eq!(q.key[slot as usize], key);
                    assert_eq!(q.ray[slot as usize], t.camera_ray_keyed(x, y, w, h, key, spp), "slot {slot}");
                    assert_eq!(q.ray[slot as usize], t.camera_ray(x, y, w, h, sample, spp));
                }
            }
        }
    }
}
