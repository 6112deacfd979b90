//! How the samples of one pixel spread over each dimension of the path space.
//!
//! Independent numbers leave clumps and gaps between a pixel's samples; a stratified or
//! low-discrepancy pattern spreads them evenly, so the same number of samples integrates
//! smooth parts of the integrand (pixel footprint, soft shadows, glossy lobes) with less
//! error. Every dimension pair gets its own scramble, keyed by (seed, pixel, vertex,
//! dimension) and not by the thread or the order of work: images stay deterministic.

use super::splitmix::{splitmix64, unit_f32};
use sobol_burley::parts::{hash, owen_scramble_rev, u32_to_f32_norm};

/// Which pattern a render's samples follow (`--sampler`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    /// A hash of (seed, pixel, sample, vertex, dimension): the seed's numbers.
    #[default]
    Independent,
    /// Jittered strata: the pixel's `spp` samples fall one per cell of a grid in each
    /// dimension pair (and one per interval in each single dimension), the cells visited in
    /// an order scrambled per dimension so that dimensions stay independent of each other.
    Stratified,
    /// Owen-scrambled Sobol points (Burley's hash-based scrambling and index shuffling, the
    /// `sobol_burley` crate), one independently scrambled 2-D sequence per dimension pair
    /// ("padded", as pbrt-v4's PaddedSobol): stratified at every power of two of samples, so
    /// adaptive sampling's batches stay well spread too.
    Sobol,
}

impl SamplerKind {
    /// Every pattern, as an array (tests and sweeps map over it).
    pub const ALL: [SamplerKind; 3] = [SamplerKind::Independent, SamplerKind::Stratified, SamplerKind::Sobol];
}

crate::choice::named!(SamplerKind, "sampler", {
    Independent => "independent", "independent hashed numbers (the seed's)";
    Stratified => "stratified", "jittered strata: one sample per cell of each dimension pair's grid";
    Sobol => "sobol", "Owen-scrambled Sobol points, one scrambled sequence per dimension pair";
});

/// Sobol points past this index repeat: later samples fall back to independent numbers.
pub(super) const SOBOL_LENGTH: u32 = 1 << 16;

/// A stratified pattern of `count` samples: the grid of its 2-D strata, `cols` x
/// `count / cols`, as square as `count`'s divisors allow (a prime count gives strips, still
/// stratified along one axis and jittered along the other).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Strata {
    pub count: u32,
    pub cols: u32,
}

impl Strata {
    pub fn new(count: u32) -> Self {
        let count = count.max(1);
        let mut cols = (count as f64).sqrt() as u32;
        while !count.is_multiple_of(cols) {
            cols -= 1;
        }
        Strata { count, cols }
    }

    /// One number of sample `index` (< `count`) in the dimension whose scramble is `hash`.
    #[inline]
    pub fn sample_1d(self, index: u32, hash: u64) -> f32 {
        let s = permute(index, self.count, (hash >> 32) as u32);
        let j = jitter(index, hash);
        below_one((s as f32 + unit_f32((j >> 40) as u32)) / self.count as f32)
    }

    /// Two numbers of sample `index` (< `count`) in the dimension pair whose scramble is
    /// `hash`: a jittered point of the stratum the scrambled index names.
    #[inline]
    pub fn sample_2d(self, index: u32, hash: u64) -> (f32, f32) {
        let s = permute(index, self.count, (hash >> 32) as u32);
        let rows = self.count / self.cols;
        let (cx, cy) = (s % self.cols, s / self.cols);
        let j = jitter(index, hash);
        let (jx, jy) = (unit_f32((j >> 40) as u32), unit_f32(((j >> 16) & 0xFF_FFFF) as u32));
        (below_one((cx as f32 + jx) / self.cols as f32), below_one((cy as f32 + jy) / rows as f32))
    }
}

/// The hash of sample `index`'s jitter inside its stratum (each sample its own).
#[inline(always)]
fn jitter(index: u32, hash: u64) -> u64 {
    splitmix64(hash ^ (index as u64).wrapping_mul(0xE703_7ED1_A0B4_28DB))
}

/// Two numbers of Sobol point `index` (< [`SOBOL_LENGTH`]) in the dimension pair whose
/// scramble is `seed`: exactly `sobol_burley::sample_4d(index, 0, seed)`'s first two, at
/// less than half its cost (Sobol's first dimension is the bit reversal of the index and
/// its second one two table lookups, where the crate walks the index's bits with a
/// data-dependent loop). A render draws a few of these per path vertex.
#[inline(always)]
pub fn sobol_2d(index: u32, seed: u32) -> (f32, f32) {
    let i = shuffled_index(index, seed);
    let y = SOBOL_DIM1[0][(i >> 24) as usize] ^ SOBOL_DIM1[1][((i >> 16) & 0xFF) as usize];
    (scrambled(sobol_dim0(i), seed, 0x912f_69ba), scrambled(y, seed, 0x174f_18ab))
}

/// One number of Sobol point `index` (< [`SOBOL_LENGTH`]) in the dimension whose scramble is
/// `seed`: exactly `sobol_burley::sample(index, 0, seed)`.
#[inline(always)]
pub fn sobol_1d(index: u32, seed: u32) -> f32 {
    scrambled(sobol_dim0(shuffled_index(index, seed)), seed, 0x912f_69ba)
}

/// The sequence's index shuffled by `seed` (Burley's nested uniform scramble of the
/// bit-reversed index), bit-reversed: the crate's `sample_4d` step by step.
#[inline(always)]
fn shuffled_index(index: u32, seed: u32) -> u32 {
    owen_scramble_rev(index.reverse_bits(), hash(seed ^ 0x79c6_8e4a))
}

/// Sobol dimension 0 of a bit-reversed shuffled index, bit-reversed (its top 16 bits
/// reversed).
#[inline(always)]
fn sobol_dim0(i: u32) -> u32 {
    (i >> 16).reverse_bits() >> 16
}

/// A bit-reversed Sobol coordinate Owen-scrambled by `seed` (and the crate's constant of
/// its dimension), as a number in [0, 1).
#[inline(always)]
fn scrambled(v: u32, seed: u32, dimension: u32) -> f32 {
    let scramble = hash(seed.wrapping_mul(0x9c8f_2d3b) ^ dimension);
    u32_to_f32_norm(owen_scramble_rev(v, scramble).reverse_bits())
}

/// Sobol dimension 1 over GF(2), bit-reversed: for each byte of the bit-reversed index's
/// top 16 bits, the XOR of the direction numbers its set bits select. Direction numbers:
/// v_0 = 2^31, v_k = v_(k-1) ^ (v_(k-1) >> 1) (primitive polynomial x + 1).
const SOBOL_DIM1: [[u32; 256]; 2] = {
    let mut v = [0u32; 16];
    v[0] = 1 << 31;
    let mut k = 1;
    while k < 16 {
        v[k] = v[k - 1] ^ (v[k - 1] >> 1);
        k += 1;
    }
    let mut t = [[0u32; 256]; 2];
    let mut b = 0;
    while b < 256 {
        let mut j = 0;
        while j < 8 {
            // Bit 7 - j of the top byte is bit j of the index; of the next byte, bit 8 + j.
            if b & (0x80 >> j) != 0 {
                t[0][b] ^= v[j].reverse_bits();
                t[1][b] ^= v[8 + j].reverse_bits();
            }
            j += 1;
        }
        b += 1;
    }
    t
};

/// `x` rounded down to the largest float below 1 when the division rounded it up to 1.
#[inline(always)]
fn below_one(x: f32) -> f32 {
    x.min(1.0 - f32::EPSILON / 2.0)
}

/// Element `i` of a pseudo-random permutation of `0..n` chosen by `seed` (Kensler,
/// "Correlated Multi-Jittered Sampling", 2013): a bijection on the smallest power-of-two
/// range holding `n`, walked until it lands below `n`, then rotated by the seed.
#[inline]
pub fn permute(mut i: u32, n: u32, seed: u32) -> u32 {
    if n <= 1 {
        return 0;
    }
    let w = u32::MAX >> (n - 1).leading_zeros();
    // Each step maps the low bits (those under `w`) to themselves one to one: xor with a
    // constant, multiplication by an odd number, xor with the masked value shifted right.
    loop {
        i ^= seed;
        i = i.wrapping_mul(0xe170_893d);
        i ^= seed >> 16;
        i ^= (i & w) >> 4;
        i ^= seed >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= seed >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | seed >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < n {
            break;
        }
    }
    ((i as u64 + seed as u64) % n as u64) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutations_are_bijections() {
        for n in [1u32, 2, 3, 7, 16, 17, 100, 1000, 4096] {
            for seed in [0u32, 1, 0xDEAD_BEEF, u32::MAX] {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let p = permute(i, n, seed);
                    assert!(p < n && !seen[p as usize], "n {n} seed {seed}: {i} -> {p} twice");
                    seen[p as usize] = true;
                }
            }
        }
    }

    #[test]
    fn sobol_points_are_the_crates() {
        for seed in [0u32, 1, 12_345, 0xDEAD_BEEF] {
            for index in 0..SOBOL_LENGTH {
                let [x, y, _, _] = sobol_burley::sample_4d(index, 0, seed);
                assert_eq!(sobol_2d(index, seed), (x, y), "index {index} seed {seed}");
                assert_eq!(sobol_1d(index, seed), sobol_burley::sample(index, 0, seed));
            }
        }
    }

    #[test]
    fn strata_grids_are_as_square_as_the_count_allows() {
        for (n, cols) in [(1, 1), (4, 2), (8, 2), (12, 3), (16, 4), (7, 1), (64, 8), (1000, 25)] {
            assert_eq!(Strata::new(n), Strata { count: n, cols });
        }
    }
}
