//! The numbers of eight streams at once, for kernels that shade eight paths in lanes: the
//! same splitmix64 hashes as [`Sampler`] one lane at a time, on four 64-bit lanes per AVX2
//! register (AVX2 has no 64-bit multiply: each one is three 32 x 32 -> 64-bit products),
//! so the bits are those of the scalar streams. The compiler keeps a plain loop of eight
//! `wrapping_mul`s scalar.

use super::pattern::{sobol_1d, sobol_2d};
use super::splitmix::{splitmix64, unit_f32};
use super::{Pattern, Sampler};
#[cfg(target_arch = "x86_64")]
use crate::cpu::Avx2;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Streams per call.
pub const LANES: usize = 8;

/// How eight 64-bit hashes are computed: with AVX2's products where the token proves the CPU
/// has them ([`Avx2`]), or in a plain loop that the compiler vectorises for whatever the
/// target has ([`Portable`]; NEON on aarch64). Both give the bits of [`splitmix64`], so a
/// lane kernel's numbers are the scalar streams' on every CPU. A type, not a value: each
/// kernel is compiled for its hasher, with nothing to decide at run time.
pub trait Hasher: Copy {
    /// `splitmix64` of each input.
    fn splitmix64_x8(self, z: &[u64; LANES]) -> [u64; LANES];

    /// The two 24-bit halves of each input's hash as numbers in [0, 1), as
    /// [`Sampler::next_2d`] takes them.
    #[inline(always)]
    fn unit_pairs_x8(self, z: &[u64; LANES]) -> ([f32; LANES], [f32; LANES]) {
        let h = self.splitmix64_x8(z);
        // Exact: the integers are below 2^24 and the scale a power of two (as `unit_f32`).
        (h.map(|h| (h >> 40) as f32 * unit_f32(1)), h.map(|h| ((h >> 16) & 0xFF_FFFF) as f32 * unit_f32(1)))
    }
}

/// The hasher of plain code, for every CPU.
#[derive(Clone, Copy, Debug)]
pub struct Portable;

impl Hasher for Portable {
    #[inline(always)]
    fn splitmix64_x8(self, z: &[u64; LANES]) -> [u64; LANES] {
        z.map(splitmix64)
    }
}

#[cfg(target_arch = "x86_64")]
impl Hasher for Avx2 {
    #[inline(always)]
    fn splitmix64_x8(self, z: &[u64; LANES]) -> [u64; LANES] {
        splitmix64_avx2(self, z)
    }

    #[inline(always)]
    fn unit_pairs_x8(self, z: &[u64; LANES]) -> ([f32; LANES], [f32; LANES]) {
        unit_pairs_avx2(self, z)
    }
}

/// `splitmix64` of each input.
/// The token proves the CPU has AVX2.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn splitmix64_avx2(_: Avx2, z: &[u64; LANES]) -> [u64; LANES] {
    let mut out = [0u64; LANES];
    // SAFETY: the token proves AVX2; loads and stores are unaligned ones of four u64
    // inside the arrays `z` and `out`.
    unsafe {
        for half in 0..2 {
            let v = _mm256_loadu_si256(z.as_ptr().add(4 * half).cast());
            _mm256_storeu_si256(out.as_mut_ptr().add(4 * half).cast(), splitmix4(v));
        }
    }
    out
}

/// [`Sampler::for_vertex`] of eight paths: the streams whose keys are `splitmix64` of the
/// [`Sampler::vertex_input`]s `inputs`.
/// The token proves the CPU has AVX2.
#[inline(always)]
pub fn for_vertex_x8<H: Hasher>(h: H, inputs: &[u64; LANES]) -> [Sampler; LANES] {
    let keys = h.splitmix64_x8(inputs);
    keys.map(Sampler::from_vertex_hash)
}

/// [`Sampler::next_2d`] of each stream at dimension `dim` (the stream's own dimension is
/// ignored): `(a, b)` per lane. Hashed streams are hashed together; streams that follow a
/// pattern are drawn one by one.
#[inline(always)]
pub fn next_2d_x8<H: Hasher>(h: H, s: &[Sampler; LANES], dim: u32) -> ([f32; LANES], [f32; LANES]) {
    if let Some(index) = sobol_indices(s) {
        let seeds = sobol_seeds(h, s, dim);
        let (mut a, mut b) = ([0f32; LANES], [0f32; LANES]);
        for j in 0..LANES {
            (a[j], b[j]) = sobol_2d(index[j], seeds[j]);
        }
        return (a, b);
    }
    if s.iter().any(Sampler::patterned) {
        let (mut a, mut b) = ([0f32; LANES], [0f32; LANES]);
        for j in 0..LANES {
            (a[j], b[j]) = s[j].at(dim).next_2d();
        }
        return (a, b);
    }
    let mut z = [0u64; LANES];
    for j in 0..LANES {
        z[j] = s[j].dim_input(dim);
    }
    h.unit_pairs_x8(&z)
}

/// [`Hasher::unit_pairs_x8`] with AVX2's products.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn unit_pairs_avx2(_: Avx2, z: &[u64; LANES]) -> ([f32; LANES], [f32; LANES]) {
    let (mut a, mut b) = ([0f32; LANES], [0f32; LANES]);
    // SAFETY: the token proves AVX2; loads and stores are unaligned ones of four u64
    // or eight f32 inside the arrays `z`, `a` and `b`.
    unsafe {
        let h0 = splitmix4(_mm256_loadu_si256(z.as_ptr().cast()));
        let h1 = splitmix4(_mm256_loadu_si256(z.as_ptr().add(4).cast()));
        let mask = _mm256_set1_epi64x(0xFF_FFFF);
        let hi = pack_low_dwords(_mm256_srli_epi64::<40>(h0), _mm256_srli_epi64::<40>(h1));
        let lo = pack_low_dwords(
            _mm256_and_si256(_mm256_srli_epi64::<16>(h0), mask),
            _mm256_and_si256(_mm256_srli_epi64::<16>(h1), mask),
        );
        // Exact: the integers are below 2^24 and the scale a power of two (as `unit_f32`).
        let scale = _mm256_set1_ps(unit_f32(1));
        _mm256_storeu_ps(a.as_mut_ptr(), _mm256_mul_ps(_mm256_cvtepi32_ps(hi), scale));
        _mm256_storeu_ps(b.as_mut_ptr(), _mm256_mul_ps(_mm256_cvtepi32_ps(lo), scale));
    }
    (a, b)
}

/// [`Sampler::next_f32`] of each stream at dimension `dim`.
#[inline(always)]
pub fn next_f32_x8<H: Hasher>(h: H, s: &[Sampler; LANES], dim: u32) -> [f32; LANES] {
    if let Some(index) = sobol_indices(s) {
        let seeds = sobol_seeds(h, s, dim);
        let mut a = [0f32; LANES];
        for j in 0..LANES {
            a[j] = sobol_1d(index[j], seeds[j]);
        }
        return a;
    }
    if s.iter().any(Sampler::patterned) {
        return s.map(|r| r.at(dim).next_f32());
    }
    next_2d_x8(h, s, dim).0
}

/// [`Pattern::vertex`] of `L` paths (a multiple of eight): the streams of vertex `bounces[j]`
/// of the paths with keys `keys[j]`, hashed for all lanes at once (sixteen lanes in plain
/// loops, which the AVX-512 kernels compile to 64-bit vector products; eight with the AVX2
/// forms). One lane at a time in a kernel's gather, each lane's hash was a chain of dependent
/// 64-bit products.
#[inline(always)]
pub fn vertex_lanes<H: Hasher, const L: usize>(
    h: H,
    pattern: Pattern,
    keys: &[u64; L],
    bounces: &[u32; L],
) -> [Sampler; L] {
    let mut inputs = [0u64; L];
    for j in 0..L {
        inputs[j] = pattern.hash_input(keys[j], bounces[j]);
    }
    let mut hashes = [0u64; L];
    if L > LANES {
        for j in 0..L {
            hashes[j] = splitmix64(inputs[j]);
        }
    } else {
        for c in (0..L).step_by(LANES) {
            let part: &[u64; LANES] = inputs[c..c + LANES].try_into().expect("groups of eight");
            hashes[c..c + LANES].copy_from_slice(&h.splitmix64_x8(part));
        }
    }
    let mut out = [Sampler::default(); L];
    for j in 0..L {
        out[j] = pattern.with_hash(keys[j], hashes[j]);
    }
    out
}

/// [`next_2d_x8`] for `L` streams.
#[inline(always)]
pub fn next_2d_lanes<H: Hasher, const L: usize>(h: H, s: &[Sampler; L], dim: u32) -> ([f32; L], [f32; L]) {
    let (mut a, mut b) = ([0.0; L], [0.0; L]);
    if L > LANES
        && let Some((index, seeds)) = sobol_wide(s, dim)
    {
        for j in 0..L {
            (a[j], b[j]) = sobol_2d(index[j], seeds[j]);
        }
        return (a, b);
    }
    for c in (0..L).step_by(LANES) {
        let part: &[Sampler; LANES] = s[c..c + LANES].try_into().expect("groups of eight");
        let (pa, pb) = next_2d_x8(h, part, dim);
        a[c..c + LANES].copy_from_slice(&pa);
        b[c..c + LANES].copy_from_slice(&pb);
    }
    (a, b)
}

/// [`next_f32_x8`] for `L` streams.
#[inline(always)]
pub fn next_f32_lanes<H: Hasher, const L: usize>(h: H, s: &[Sampler; L], dim: u32) -> [f32; L] {
    let mut a = [0.0; L];
    if L > LANES
        && let Some((index, seeds)) = sobol_wide(s, dim)
    {
        for j in 0..L {
            a[j] = sobol_1d(index[j], seeds[j]);
        }
        return a;
    }
    for c in (0..L).step_by(LANES) {
        let part: &[Sampler; LANES] = s[c..c + LANES].try_into().expect("groups of eight");
        a[c..c + LANES].copy_from_slice(&next_f32_x8(h, part, dim));
    }
    a
}

/// The point indices of `L` Sobol streams and their scramble seeds of dimension `dim` (as
/// [`sobol_indices`] and [`sobol_seeds`]), when every lane's numbers come from the sequence.
/// For the sixteen-lane kernels: plain loops over all lanes, which the compiler turns into
/// 512-bit operations there (64-bit products included), where eight lanes at a time with the
/// AVX2 forms took twice the instructions for the same numbers (a long chain of dependent
/// products per draw: the sampler was about a fifth of the diffuse kernel's time).
#[inline(always)]
fn sobol_wide<const L: usize>(s: &[Sampler; L], dim: u32) -> Option<([u32; L], [u32; L])> {
    let index = sobol_indices(s)?;
    let mut seeds = [0u32; L];
    for j in 0..L {
        seeds[j] = (splitmix64(s[j].dim_input(dim)) >> 32) as u32;
    }
    Some((index, seeds))
}

/// The point indices of `N` Sobol streams, when every lane's numbers come from the sequence.
#[inline(always)]
fn sobol_indices<const N: usize>(s: &[Sampler; N]) -> Option<[u32; N]> {
    let mut index = [0u32; N];
    for j in 0..N {
        index[j] = s[j].sobol_index()?;
    }
    Some(index)
}

/// The scramble seeds of dimension `dim` of eight Sobol streams: the top half of the
/// dimension's hash, as [`Sampler::next_2d`] takes it. The sequence's own hashing and
/// scrambling then run as plain loops over the lanes (32-bit products, which AVX2 has).
#[inline(always)]
fn sobol_seeds<H: Hasher>(h: H, s: &[Sampler; LANES], dim: u32) -> [u32; LANES] {
    let mut z = [0u64; LANES];
    for j in 0..LANES {
        z[j] = s[j].dim_input(dim);
    }
    h.splitmix64_x8(&z).map(|h| (h >> 32) as u32)
}

/// The low 64 bits of `a * c` in each 64-bit lane.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn mul64(a: __m256i, c: u64) -> __m256i {
    // SAFETY: the caller guarantees AVX2.
    unsafe {
        let (cl, ch) = (_mm256_set1_epi64x(c as u32 as i64), _mm256_set1_epi64x((c >> 32) as i64));
        let lo = _mm256_mul_epu32(a, cl);
        let cross = _mm256_add_epi64(_mm256_mul_epu32(_mm256_srli_epi64::<32>(a), cl), _mm256_mul_epu32(a, ch));
        _mm256_add_epi64(lo, _mm256_slli_epi64::<32>(cross))
    }
}

/// [`splitmix64`](super::splitmix64) of four lanes.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn splitmix4(z: __m256i) -> __m256i {
    // SAFETY: the caller guarantees AVX2.
    unsafe {
        let z = _mm256_add_epi64(z, _mm256_set1_epi64x(0x9E37_79B9_7F4A_7C15u64 as i64));
        let z = mul64(_mm256_xor_si256(z, _mm256_srli_epi64::<30>(z)), 0xBF58_476D_1CE4_E5B9);
        let z = mul64(_mm256_xor_si256(z, _mm256_srli_epi64::<27>(z)), 0x94D0_49BB_1331_11EB);
        _mm256_xor_si256(z, _mm256_srli_epi64::<31>(z))
    }
}

/// The low 32 bits of the four 64-bit lanes of `x`, then of `y`, as eight 32-bit lanes.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn pack_low_dwords(x: __m256i, y: __m256i) -> __m256i {
    // SAFETY: the caller guarantees AVX2.
    unsafe {
        let idx = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
        let (px, py) = (_mm256_permutevar8x32_epi32(x, idx), _mm256_permutevar8x32_epi32(y, idx));
        _mm256_permute2x128_si256::<0x20>(px, py)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::splitmix64;

    type Pairs = ([f32; LANES], [f32; LANES]);

    /// Runs `$f` (a generic function's name) with every hasher this CPU has, then the
    /// arguments: the portable one, and AVX2's inside an AVX2 context where the CPU has it.
    macro_rules! each_hasher {
        ($f:ident($($arg:expr),*)) => {{
            $f(Portable, $($arg),*);
            #[cfg(target_arch = "x86_64")]
            if let Some(avx) = Avx2::new() {
                crate::cpu::with_avx2(avx, |avx| $f(avx, $($arg),*));
            }
        }};
    }

    fn run<H: Hasher>(h: H, keys: &[u64; LANES], dim: u32) -> ([u64; LANES], Pairs, [f32; LANES]) {
        let s = keys.map(|k| Sampler::for_vertex(k, 3));
        (h.splitmix64_x8(keys), next_2d_x8(h, &s, dim), next_f32_x8(h, &s, dim))
    }

    /// Eight lanes give the scalar streams' numbers, bit for bit, for keys with high, low,
    /// zero and all-ones halves (the 32 x 32-bit products and their carries).
    #[test]
    fn lanes_are_the_scalar_streams() {
        let mut state = 0x0123_4567_89AB_CDEFu64;
        let mut groups = vec![[0, u64::MAX, 1, 1 << 32, (1 << 32) - 1, u64::MAX << 32, 0x8000_0000_0000_0000, 42]];
        for _ in 0..5000 {
            let mut g = [0u64; LANES];
            for k in g.iter_mut() {
                state = splitmix64(state);
                *k = state;
            }
            groups.push(g);
        }
        for (n, keys) in groups.iter().enumerate() {
            let dim = n as u32 % 11;
            fn check<H: Hasher>(hasher: H, keys: &[u64; LANES], dim: u32) {
                let (h, (a, b), f) = run(hasher, keys, dim);
                for j in 0..LANES {
                    assert_eq!(h[j], splitmix64(keys[j]), "{:#x}", keys[j]);
                    let (mut s2, mut s1) =
                        (Sampler::for_vertex(keys[j], 3).at(dim), Sampler::for_vertex(keys[j], 3).at(dim));
                    let (wa, wb) = s2.next_2d();
                    assert_eq!((a[j].to_bits(), b[j].to_bits()), (wa.to_bits(), wb.to_bits()), "{:#x}", keys[j]);
                    assert_eq!(f[j].to_bits(), s1.next_f32().to_bits(), "{:#x}", keys[j]);
                }
            }
            each_hasher!(check(keys, dim));
        }
    }

    /// Groups of `N` Sobol streams (a vertex of `1 + n % 5` bounces, sample indices below the
    /// sequence's length, and in every `every`-th group lane `past` beyond it), one per `n`.
    fn sobol_groups<const N: usize>(spp: u32, every: u32, past: usize) -> impl Iterator<Item = (u32, [Sampler; N])> {
        let pattern = crate::sampling::Pattern::new(crate::sampling::SamplerKind::Sobol, spp);
        let mut state = 0x0FED_CBA9_8765_4321u64 ^ N as u64;
        (0..3000u32).map(move |n| {
            let mut s = [Sampler::default(); N];
            for (j, lane) in s.iter_mut().enumerate() {
                state = splitmix64(state);
                let index = if n % every == 0 && j == past { (1 << 16) + n } else { (state as u32) % 4096 };
                *lane = pattern.vertex((state & !0xFFFF_FFFF) | index as u64, 1 + n % 5);
            }
            (n, s)
        })
    }

    /// Each lane's numbers `((a, b), f)` at dimension `dim` are its scalar stream's.
    fn assert_scalar<const N: usize>(s: &[Sampler; N], dim: u32, ((a, b), f): (([f32; N], [f32; N]), [f32; N])) {
        for j in 0..N {
            let (wa, wb) = s[j].at(dim).next_2d();
            assert_eq!((a[j].to_bits(), b[j].to_bits()), (wa.to_bits(), wb.to_bits()), "dim {dim} lane {j}");
            assert_eq!(f[j].to_bits(), s[j].at(dim).next_f32().to_bits(), "dim {dim} lane {j}");
        }
    }

    /// Sobol streams (the default sampler) give the scalar numbers too, lanes with sample
    /// indices inside the sequence and past it (hashed numbers) mixed or not.
    #[test]
    fn sobol_lanes_are_the_scalar_streams() {
        for (n, s) in sobol_groups::<LANES>(64, 4, 3) {
            let dim = n % 9;
            fn check<H: Hasher>(h: H, s: &[Sampler; LANES], dim: u32) {
                assert_scalar(s, dim, (next_2d_x8(h, s, dim), next_f32_x8(h, s, dim)));
            }
            each_hasher!(check(&s, dim));
        }
    }

    /// Every lane's vertex stream, hashed for eight and sixteen lanes at once, is
    /// `Pattern::vertex`'s, for every sampler, keys with high, low, zero and all-ones halves
    /// and bounces from the camera ray's on.
    #[test]
    fn vertex_lanes_are_the_patterns_streams() {
        fn check_with<H: Hasher + std::fmt::Debug, const N: usize>(
            h: H,
            p: Pattern,
            keys: &[u64; N],
            bounces: &[u32; N],
        ) {
            let got = vertex_lanes(h, p, keys, bounces);
            for j in 0..N {
                assert_eq!(got[j], p.vertex(keys[j], bounces[j]), "{p:?} lane {j} {h:?}");
            }
        }
        fn check<const N: usize>(pattern: Pattern, keys: &[u64; N], bounces: &[u32; N]) {
            each_hasher!(check_with(pattern, keys, bounces));
        }
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let fixed = [0, u64::MAX, 1, 1 << 32, (1 << 32) - 1, u64::MAX << 32, 0x8000_0000_0000_0000, 42];
        for kind in crate::sampling::SamplerKind::ALL {
            let pattern = Pattern::new(kind, 64);
            check::<LANES>(pattern, &fixed, &[0, 1, 2, 3, 4, 5, 6, u32::MAX]);
            for n in 0..500u32 {
                let mut keys = [0u64; 16];
                for k in keys.iter_mut() {
                    state = splitmix64(state);
                    *k = state;
                }
                let bounces: [u32; 16] = std::array::from_fn(|j| (n + j as u32) % 7);
                check::<16>(pattern, &keys, &bounces);
                let (k8, b8) = (keys[..LANES].try_into().unwrap(), bounces[..LANES].try_into().unwrap());
                check::<LANES>(pattern, k8, b8);
            }
        }
    }

    /// Sixteen lanes at once (the whole-width path, and the eight-at-a-time one where a lane
    /// leaves the sequence): each lane's numbers are its scalar stream's.
    #[test]
    fn sixteen_sobol_lanes_are_the_scalar_streams() {
        for (n, s) in sobol_groups::<16>(256, 3, 11) {
            let dim = n % 13;
            fn check<H: Hasher>(h: H, s: &[Sampler; 16], dim: u32) {
                assert_scalar(s, dim, (next_2d_lanes(h, s, dim), next_f32_lanes(h, s, dim)));
            }
            each_hasher!(check(&s, dim));
        }
    }
}
