//! A vertex's random numbers by dimension ([`Numbers`]): the one-vertex code is generic over
//! where they come from, a vertex's own stream ([`Sampler`]) or a stream seen from another
//! dimension.

use super::Sampler;

/// A vertex's stream of uniform numbers, by dimension.
pub trait Numbers: Copy {
    /// This stream at dimension `dim`.
    fn at(self, dim: u32) -> Self;
    /// The 2-d sample of the current dimension; the stream moves on one dimension.
    fn next_2d(&mut self) -> (f32, f32);
    /// The 1-d sample of the current dimension; the stream moves on one dimension.
    fn next_f32(&mut self) -> f32;
}

impl Numbers for Sampler {
    #[inline(always)]
    fn at(self, dim: u32) -> Self {
        Sampler::at(self, dim)
    }

    #[inline(always)]
    fn next_2d(&mut self) -> (f32, f32) {
        Sampler::next_2d(self)
    }

    #[inline(always)]
    fn next_f32(&mut self) -> f32 {
        Sampler::next_f32(self)
    }
}
