//! The hash every random number comes from, and its bits as a float.

/// SplitMix64 finaliser: a cheap, well-mixed 64-bit hash used to derive seeds.
#[inline]
pub fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// `bits` (< 2^24) as a number in [0, 1).
#[inline(always)]
pub(super) fn unit_f32(bits: u32) -> f32 {
    bits as f32 * (1.0 / (1u32 << 24) as f32)
}
