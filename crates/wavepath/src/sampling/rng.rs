use super::pattern::{SOBOL_LENGTH, SamplerKind, Strata, sobol_1d, sobol_2d};
use super::splitmix::{splitmix64, unit_f32};

/// The random-number stream of one camera sample of one pixel, one stream per bounce.
///
/// Counter based: the n-th number of a stream is a hash of (key, n), so a stream is fully
/// described by two integers (`key`, `dim`) that fit in a ray queue, and the numbers a path
/// draws do not depend on which thread, chunk or wave runs it.
///
/// A stratified or Sobol stream (see [`Pattern`]) keys each dimension by (seed, pixel,
/// vertex, dimension) only and carries the sample's index within its pixel: the pixel's
/// samples then spread over each dimension instead of falling independently.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sampler {
    key: u64,
    dim: u32,
    seq: Seq,
}

/// Where a stream's numbers come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Seq {
    /// Hashes of (key, dimension).
    #[default]
    Hashed,
    /// Sample `index` of a stratified pattern.
    Stratified { index: u32, strata: Strata },
    /// Point `index` of an Owen-scrambled Sobol sequence.
    Sobol { index: u32 },
}

impl Seq {
    /// The pattern's number of the dimension whose hash is `h`, when the pattern covers the
    /// sample (`None`: hashed numbers).
    #[inline(always)]
    fn pattern_1d(self, h: u64) -> Option<f32> {
        match self {
            Seq::Stratified { index, strata } if index < strata.count => Some(strata.sample_1d(index, h)),
            Seq::Sobol { index } if index < SOBOL_LENGTH => Some(sobol_1d(index, (h >> 32) as u32)),
            _ => None,
        }
    }

    /// [`pattern_1d`](Self::pattern_1d) for a dimension pair.
    #[inline(always)]
    fn pattern_2d(self, h: u64) -> Option<(f32, f32)> {
        match self {
            Seq::Stratified { index, strata } if index < strata.count => Some(strata.sample_2d(index, h)),
            Seq::Sobol { index } if index < SOBOL_LENGTH => Some(sobol_2d(index, (h >> 32) as u32)),
            _ => None,
        }
    }
}

/// A render's sampler: which pattern, and how many samples per pixel it stratifies.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Pattern {
    pub kind: SamplerKind,
    strata: Strata,
}

impl Pattern {
    /// `kind` for renders of `spp` samples per pixel.
    pub fn new(kind: SamplerKind, spp: u32) -> Self {
        Pattern { kind, strata: Strata::new(spp) }
    }

    /// The key of path (`pixel`, `sample`) (as [`Sampler::path_key`] for independent numbers).
    #[inline]
    pub fn path_key(self, seed: u64, pixel: u64, sample: u64) -> u64 {
        self.sample_key(Sampler::pixel_key(seed, pixel), sample)
    }

    /// [`path_key`](Self::path_key) from the pixel's [`Sampler::pixel_key`]. A patterned
    /// key is the pixel key's top half and the sample index.
    #[inline]
    pub fn sample_key(self, pixel_key: u64, sample: u64) -> u64 {
        match self.kind {
            SamplerKind::Independent => Sampler::sample_key(pixel_key, sample),
            _ => (pixel_key & !0xFFFF_FFFF) | (sample & 0xFFFF_FFFF),
        }
    }

    /// Stream `bounce` of the path with key `key` (0: the camera ray, d + 1: the vertex at
    /// depth d).
    #[inline]
    pub fn vertex(self, key: u64, bounce: u32) -> Sampler {
        self.with_hash(key, splitmix64(self.hash_input(key, bounce)))
    }

    /// What stream `bounce` of the path with key `key` hashes: a patterned stream keys its
    /// dimensions by the pixel (the key's top half), an independent one by the whole key.
    #[inline(always)]
    pub(super) fn hash_input(self, key: u64, bounce: u32) -> u64 {
        match self.kind {
            SamplerKind::Independent => Sampler::vertex_input(key, bounce),
            _ => Sampler::vertex_input(key & !0xFFFF_FFFF, bounce),
        }
    }

    /// The stream of the path with key `key` whose [`hash_input`](Self::hash_input) hashes
    /// to `hash` (hashed elsewhere: for all lanes of a kernel at once).
    #[inline(always)]
    pub(super) fn with_hash(self, key: u64, hash: u64) -> Sampler {
        let index = key as u32;
        let seq = match self.kind {
            SamplerKind::Independent => Seq::Hashed,
            SamplerKind::Stratified => Seq::Stratified { index, strata: self.strata },
            SamplerKind::Sobol => Seq::Sobol { index },
        };
        Sampler { key: hash, dim: 0, seq }
    }
}

impl Sampler {
    /// The stream for sample `sample` of pixel `pixel` (row-major index) under `seed`.
    pub fn for_sample(seed: u64, pixel: u64, sample: u64) -> Self {
        Self::for_bounce(seed, pixel, sample, 0)
    }

    /// Stream `bounce` of the path of (`seed`, `pixel`, `sample`): stream 0 is the camera
    /// ray, stream d + 1 the vertex at depth d. Each vertex starts at dimension 0 so the
    /// numbers it uses do not depend on how many earlier vertices consumed.
    #[inline]
    pub fn for_bounce(seed: u64, pixel: u64, sample: u64, bounce: u32) -> Self {
        Self::for_vertex(Self::path_key(seed, pixel, sample), bounce)
    }

    /// The part of a stream's key that depends only on the path (seed, pixel, sample): a
    /// wavefront path stores it once so each vertex costs one hash, not four.
    #[inline]
    pub fn path_key(seed: u64, pixel: u64, sample: u64) -> u64 {
        Self::sample_key(Self::pixel_key(seed, pixel), sample)
    }

    /// The part of [`path_key`](Self::path_key) that depends only on (seed, pixel): the
    /// wavefront's generate stage takes it once per pixel instead of once per sample.
    #[inline]
    pub fn pixel_key(seed: u64, pixel: u64) -> u64 {
        splitmix64(splitmix64(seed ^ 0xA076_1D64_78BD_642F) ^ pixel)
    }

    /// [`path_key`](Self::path_key) from the pixel's [`pixel_key`](Self::pixel_key).
    #[inline]
    pub fn sample_key(pixel_key: u64, sample: u64) -> u64 {
        splitmix64(Self::sample_input(pixel_key, sample))
    }

    /// What [`sample_key`](Self::sample_key) hashes.
    #[inline(always)]
    pub fn sample_input(pixel_key: u64, sample: u64) -> u64 {
        pixel_key ^ sample.wrapping_mul(0xE703_7ED1_A0B4_28DB)
    }

    /// Stream `bounce` of the path whose [`path_key`](Self::path_key) is `key`; the same
    /// numbers as [`for_bounce`](Self::for_bounce).
    #[inline]
    pub fn for_vertex(key: u64, bounce: u32) -> Self {
        Self::from_vertex_hash(splitmix64(Self::vertex_input(key, bounce)))
    }

    /// What [`for_vertex`](Self::for_vertex) hashes: the path key and the bounce, mixed.
    #[inline(always)]
    pub fn vertex_input(key: u64, bounce: u32) -> u64 {
        key ^ (bounce as u64).wrapping_mul(0x8EBC_6AF0_9C88_C6E3)
    }

    /// The stream whose key is `splitmix64` of a [`vertex_input`](Self::vertex_input)
    /// (hashed elsewhere, e.g. eight at a time), at dimension 0.
    #[inline(always)]
    pub fn from_vertex_hash(key: u64) -> Self {
        Sampler { key, dim: 0, seq: Seq::Hashed }
    }

    /// What the number at dimension `dim` hashes (`key + dim * golden ratio`).
    #[inline(always)]
    pub fn dim_input(&self, dim: u32) -> u64 {
        self.key.wrapping_add((dim as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15))
    }

    /// Whether the stream follows a stratified or Sobol pattern (not hashed numbers).
    #[inline(always)]
    pub fn patterned(&self) -> bool {
        self.seq != Seq::Hashed
    }

    /// The point index of a Sobol stream whose numbers all come from the sequence (its index
    /// within [`SOBOL_LENGTH`]); `None` for other streams.
    #[inline(always)]
    pub(super) fn sobol_index(&self) -> Option<u32> {
        match self.seq {
            Seq::Sobol { index } if index < SOBOL_LENGTH => Some(index),
            _ => None,
        }
    }

    /// Jumps to dimension `dim` of this stream.
    #[inline]
    pub fn at(mut self, dim: u32) -> Self {
        self.dim = dim;
        self
    }

    /// The hash of the current dimension; the stream moves on one dimension.
    #[inline(always)]
    fn next_u64(&mut self) -> u64 {
        let h = splitmix64(self.dim_input(self.dim));
        self.dim = self.dim.wrapping_add(1);
        h
    }

    /// The hash of the current dimension, for hashed numbers: a patterned stream's samples
    /// past its pattern mix in their index (their keys do not hold it).
    #[inline(always)]
    fn hashed(&self, h: u64) -> u64 {
        match self.seq {
            Seq::Hashed => h,
            Seq::Stratified { index, .. } | Seq::Sobol { index } => {
                splitmix64(h ^ (index as u64).wrapping_mul(0xE703_7ED1_A0B4_28DB))
            }
        }
    }

    /// A uniform number in [0, 1) with at least 24 bits of precision (never exactly 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        let h = self.next_u64();
        if let Some(x) = self.seq.pattern_1d(h) {
            return x;
        }
        unit_f32((self.hashed(h) >> 40) as u32)
    }

    /// Two uniform numbers in [0, 1) from one hash (one dimension): its top 24 bits and the
    /// 24 bits below them. splitmix64's output bits are all well mixed, so the two are as
    /// independent as two hashes would be, for half the work.
    /// A patterned stream gives the dimension pair of its pattern.
    #[inline]
    pub fn next_2d(&mut self) -> (f32, f32) {
        let h = self.next_u64();
        if let Some(xy) = self.seq.pattern_2d(h) {
            return xy;
        }
        let h = self.hashed(h);
        (unit_f32((h >> 40) as u32), unit_f32(((h >> 16) & 0xFF_FFFF) as u32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_mean_and_range() {
        let mut s = Sampler::for_sample(1, 2, 3);
        let n = 100_000;
        let mut sum = 0.0f64;
        let mut sum_xy = 0.0f64;
        let mut prev = 0.5f64;
        for _ in 0..n {
            let x = s.next_f32();
            assert!((0.0..1.0).contains(&x));
            sum += x as f64;
            sum_xy += (x as f64 - 0.5) * (prev - 0.5);
            prev = x as f64;
        }
        // Mean of U(0,1) is 1/2 with standard error 1/sqrt(12 n) ~ 0.0009.
        assert!((sum / n as f64 - 0.5).abs() < 0.005);
        // Successive numbers are uncorrelated: E[(x-1/2)(y-1/2)] = 0, s.e. 1/(12 sqrt n).
        assert!((sum_xy / n as f64).abs() < 0.002);
    }

    #[test]
    fn streams_differ_between_pixels_samples_and_bounces() {
        let a = Sampler::for_sample(0, 0, 0).next_f32();
        let b = Sampler::for_sample(0, 1, 0).next_f32();
        let c = Sampler::for_sample(0, 0, 1).next_f32();
        let d = Sampler::for_sample(1, 0, 0).next_f32();
        let e = Sampler::for_bounce(0, 0, 0, 1).next_f32();
        assert!(a != b && a != c && a != d && b != c && a != e);
        assert_eq!(a, Sampler::for_sample(0, 0, 0).next_f32());
        let mut s = Sampler::for_sample(3, 4, 5);
        s.next_f32();
        assert_eq!(s.next_f32(), Sampler::for_sample(3, 4, 5).at(1).next_f32());
        let key = Sampler::path_key(3, 4, 5);
        assert_eq!(Sampler::for_vertex(key, 2), Sampler::for_bounce(3, 4, 5, 2));
        assert_eq!(Sampler::sample_key(Sampler::pixel_key(3, 4), 5), key);
    }
}
