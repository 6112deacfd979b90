//! Where a group's random numbers come from, dimension by dimension, for all its lanes at
//! once: drawn from the lanes' vertex streams when the leaving kernel asks ([`Hashed`]; at one
//! lane, [`Stream`]), so each lane gets its stream's numbers and draws no dimension its model
//! does not read.

#![allow(clippy::needless_range_loop)]

use crate::sampling::Sampler;
use crate::sampling::rng8::{self, Hasher};

/// A group's numbers by dimension (a pair, or one number), every lane's at once.
pub trait LaneNumbers<const L: usize>: Copy {
    fn pair(self, dim: u32) -> ([f32; L], [f32; L]);
    fn one(self, dim: u32) -> [f32; L];
}

/// Drawn from lane `j`'s stream `rng[j]` with the hasher `h`, when asked.
#[derive(Clone, Copy)]
pub struct Hashed<'a, H, const L: usize> {
    pub h: H,
    pub rng: &'a [Sampler; L],
}

impl<H: Hasher, const L: usize> LaneNumbers<L> for Hashed<'_, H, L> {
    #[inline(always)]
    fn pair(self, dim: u32) -> ([f32; L], [f32; L]) {
        rng8::next_2d_lanes(self.h, self.rng, dim)
    }

    #[inline(always)]
    fn one(self, dim: u32) -> [f32; L] {
        rng8::next_f32_lanes(self.h, self.rng, dim)
    }
}

/// One lane's numbers from its vertex stream (the leaving kernel at one lane: the one-path
/// code).
#[derive(Clone, Copy)]
pub struct Stream(pub Sampler);

impl LaneNumbers<1> for Stream {
    #[inline(always)]
    fn pair(self, dim: u32) -> ([f32; 1], [f32; 1]) {
        let (a, b) = self.0.at(dim).next_2d();
        ([a], [b])
    }

    #[inline(always)]
    fn one(self, dim: u32) -> [f32; 1] {
        [self.0.at(dim).next_f32()]
    }
}
