//! The path's random streams: every number a path draws comes from (seed, pixel, sample,
//! depth) following the pixel's pattern, so images do not depend on the thread count.

use crate::sampling::{Pattern, Sampler};
use crate::settings::Settings;

/// The seed and the pattern (`--sampler`) of one render.
#[derive(Clone, Copy, Debug)]
pub struct Streams {
    pub seed: u64,
    /// How each pixel's samples spread over the path space (`--sampler`).
    pub pattern: Pattern,
}

impl Streams {
    pub fn new(settings: &Settings) -> Streams {
        Streams {
            seed: settings.sampling.seed,
            pattern: Pattern::new(settings.sampling.sampler, settings.sampling.spp),
        }
    }

    /// The stream of the vertex at `depth` of path (pixel, sample).
    #[inline]
    pub fn sampler(&self, pixel: u32, sample: u32, depth: u32) -> Sampler {
        self.vertex_sampler(self.path_key(pixel, sample), depth)
    }

    /// The key of path (pixel, sample)'s random streams (see [`Pattern::path_key`]).
    #[inline]
    pub fn path_key(&self, pixel: u32, sample: u32) -> u64 {
        self.pattern.path_key(self.seed, pixel as u64, sample as u64)
    }

    /// The stream of the vertex at `depth` of the path with key `key`; the same numbers as
    /// [`sampler`](Self::sampler).
    #[inline]
    pub fn vertex_sampler(&self, key: u64, depth: u32) -> Sampler {
        self.pattern.vertex(key, depth + 1)
    }
}
