//! Ray set-ups in AVX2 registers: one ray's box-test values in one register, or eight rays'
//! (one per lane) for a batch's group or a packet; the same operations per lane as the
//! scalar set-up, so the same values.
use crate::accel::bvh::simd::{BoxRay, EXIT_SCALE, PLANES, PacketBoxRays, RootBox, TIE_SCALE};
use crate::geometry::Ray;
use std::arch::x86_64::*;

/// Ray fields of eight rays, one register per field (lane k = ray k): origin x, y, z,
/// direction x, y, z, tmin, tmax.
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
pub(super) unsafe fn transpose_rays8(rays: &[Ray; 8]) -> [__m256; 8] {
    // SAFETY: the caller guarantees AVX2; each load reads one 32-byte `Ray` (asserted layout).
    unsafe {
        let p = rays.as_ptr().cast::<f32>();
        let r = |k: usize| _mm256_loadu_ps(p.add(8 * k));
        transpose8([r(0), r(1), r(2), r(3), r(4), r(5), r(6), r(7)])
    }
}

/// The 8 x 8 transpose: lane `j` of result `k` is lane `k` of `r[j]`.
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
pub(super) unsafe fn transpose8(r: [__m256; 8]) -> [__m256; 8] {
    // SAFETY: the caller guarantees AVX2; no memory access.
    unsafe {
        let (t0, t1) = (_mm256_unpacklo_ps(r[0], r[1]), _mm256_unpackhi_ps(r[0], r[1]));
        let (t2, t3) = (_mm256_unpacklo_ps(r[2], r[3]), _mm256_unpackhi_ps(r[2], r[3]));
        let (t4, t5) = (_mm256_unpacklo_ps(r[4], r[5]), _mm256_unpackhi_ps(r[4], r[5]));
        let (t6, t7) = (_mm256_unpacklo_ps(r[6], r[7]), _mm256_unpackhi_ps(r[6], r[7]));
        let (s0, s1) = (_mm256_shuffle_ps::<0x44>(t0, t2), _mm256_shuffle_ps::<0xee>(t0, t2));
        let (s2, s3) = (_mm256_shuffle_ps::<0x44>(t1, t3), _mm256_shuffle_ps::<0xee>(t1, t3));
        let (s4, s5) = (_mm256_shuffle_ps::<0x44>(t4, t6), _mm256_shuffle_ps::<0xee>(t4, t6));
        let (s6, s7) = (_mm256_shuffle_ps::<0x44>(t5, t7), _mm256_shuffle_ps::<0xee>(t5, t7));
        [
            _mm256_permute2f128_ps::<0x20>(s0, s4),
            _mm256_permute2f128_ps::<0x20>(s1, s5),
            _mm256_permute2f128_ps::<0x20>(s2, s6),
            _mm256_permute2f128_ps::<0x20>(s3, s7),
            _mm256_permute2f128_ps::<0x31>(s0, s4),
            _mm256_permute2f128_ps::<0x31>(s1, s5),
            _mm256_permute2f128_ps::<0x31>(s2, s6),
            _mm256_permute2f128_ps::<0x31>(s3, s7),
        ]
    }
}

/// The last eight bytes of a [`BoxRay`] as two words, less the flags: `planes[0..2]` in the
/// upper half of the first (below them go `fma` and `live`), `planes[2..6]` the second; one
/// entry per octant.
const PLANE_WORDS: [[u32; 8]; 2] = {
    let mut t = [[0u32; 8]; 2];
    let mut oct = 0;
    while oct < 8 {
        let p = PLANES[oct];
        t[0][oct] = (p[0] as u32) << 16 | (p[1] as u32) << 24;
        t[1][oct] = u32::from_le_bytes([p[2], p[3], p[4], p[5]]);
        oct += 1;
    }
    t
};

/// The reciprocal directions of eight rays (one register per axis, lane `k` = ray `k`): per
/// lane the operations of [`box_ray8`] (`1 / d`, or +-`f32::MAX` with the sign of `d` where
/// that is not finite).
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
pub(super) unsafe fn inv8(dir: [__m256; 3]) -> [__m256; 3] {
    // SAFETY: the caller guarantees AVX2; no memory access.
    unsafe {
        let sign = _mm256_set1_ps(-0.0);
        let inf = _mm256_set1_ps(f32::INFINITY);
        // A loop, not `array::map`: its closure may be compiled out of line, outside the AVX2
        // context.
        let mut inv = [_mm256_setzero_ps(); 3];
        for axis in 0..3 {
            let d = dir[axis];
            let i = _mm256_div_ps(_mm256_set1_ps(1.0), d);
            let finite_i = _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_andnot_ps(sign, i), inf);
            let big = _mm256_or_ps(_mm256_and_ps(d, sign), _mm256_set1_ps(f32::MAX));
            inv[axis] = _mm256_blendv_ps(big, i, finite_i);
        }
        inv
    }
}

/// The rest of eight rays' box-test values from their fields and reciprocals `inv`: the
/// fused-slab terms `oi_near` and `oi_far` per axis, then as comparison masks the lanes
/// whose terms are all finite (`fma`) and the live lanes; per lane the operations of
/// [`box_ray8`].
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
pub(super) unsafe fn fused_terms8(
    org: [__m256; 3],
    dir: [__m256; 3],
    inv: [__m256; 3],
    tmin: __m256,
    tmax: __m256,
) -> ([__m256; 3], [__m256; 3], __m256, __m256) {
    // SAFETY: the caller guarantees AVX2; no memory access.
    unsafe {
        let sign = _mm256_set1_ps(-0.0);
        let inf = _mm256_set1_ps(f32::INFINITY);
        let finite = |x: __m256| _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_andnot_ps(sign, x), inf);
        let ones = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        let (mut finite_all, mut fma_all, mut nonzero) = (ones, ones, _mm256_setzero_ps());
        let (mut on, mut of) = ([_mm256_setzero_ps(); 3], [_mm256_setzero_ps(); 3]);
        for axis in 0..3 {
            let (o, d) = (org[axis], dir[axis]);
            let oi = _mm256_mul_ps(o, inv[axis]);
            let e = _mm256_add_ps(
                _mm256_mul_ps(_mm256_andnot_ps(sign, oi), _mm256_set1_ps(1.0 / 1048576.0)),
                _mm256_set1_ps(f32::MIN_POSITIVE),
            );
            (on[axis], of[axis]) = (_mm256_add_ps(oi, e), _mm256_sub_ps(oi, e));
            fma_all = _mm256_and_ps(fma_all, _mm256_and_ps(finite(on[axis]), finite(of[axis])));
            finite_all = _mm256_and_ps(finite_all, _mm256_and_ps(finite(o), finite(d)));
            nonzero = _mm256_or_ps(nonzero, _mm256_cmp_ps::<_CMP_NEQ_UQ>(d, _mm256_setzero_ps()));
        }
        let live = _mm256_and_ps(_mm256_and_ps(finite_all, nonzero), _mm256_cmp_ps::<_CMP_LE_OQ>(tmin, tmax));
        (on, of, fma_all, live)
    }
}

/// [`BoxTest::set_up`] of eight rays: [`RootBox::admits`]'s answer for each (by the values
/// below: the same products, so the same answers; a dead ray's answer is not used), and
/// unless it is no for all, [`box_ray8`]'s values for each (the same operations per lane,
/// eight rays per register, then transposed into the rays' [`BoxRay`]s).
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
pub(super) unsafe fn set_up8(root: Option<&RootBox>, rays: &[Ray; 8], out: &mut [BoxRay; 8]) -> u32 {
    // SAFETY: the caller guarantees AVX2; the stores are aligned ones of 32 bytes, the two
    // halves of each `BoxRay` (64 bytes, 32-byte aligned; layout asserted below), whose bool
    // bytes receive 0 or 1 (a comparison's sign bit shifted down).
    unsafe {
        let f = transpose_rays8(rays);
        let (org, dir, tmin, tmax) = ([f[0], f[1], f[2]], [f[3], f[4], f[5]], f[6], f[7]);
        let inv = inv8(dir);
        // Most camera rays miss the tree: eight misses need nothing more.
        let admitted = match root {
            None => 0xff,
            Some(root) => {
                let (mut enter, mut exit) = (tmin, _mm256_set1_ps(f32::INFINITY));
                for axis in 0..3 {
                    let a = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(root.lo[axis]), org[axis]), inv[axis]);
                    let b = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(root.hi[axis]), org[axis]), inv[axis]);
                    enter = _mm256_max_ps(enter, _mm256_min_ps(a, b));
                    exit = _mm256_min_ps(exit, _mm256_max_ps(a, b));
                }
                let exit = _mm256_min_ps(
                    _mm256_mul_ps(exit, _mm256_set1_ps(EXIT_SCALE)),
                    _mm256_mul_ps(tmax, _mm256_set1_ps(TIE_SCALE)),
                );
                _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit)) as u32
            }
        };
        if admitted == 0 {
            return 0;
        }
        let (on, of, fma_all, live) = fused_terms8(org, dir, inv, tmin, tmax);
        let top = |x: __m256| _mm256_srli_epi32::<31>(_mm256_castps_si256(x));
        let octant = _mm256_or_si256(
            _mm256_or_si256(top(dir[0]), _mm256_slli_epi32::<1>(top(dir[1]))),
            _mm256_slli_epi32::<2>(top(dir[2])),
        );
        let table = |t: &[u32; 8]| _mm256_permutevar8x32_epi32(_mm256_loadu_si256(t.as_ptr().cast()), octant);
        let flags =
            _mm256_or_si256(_mm256_or_si256(top(fma_all), _mm256_slli_epi32::<8>(top(live))), table(&PLANE_WORDS[0]));
        let cast = _mm256_castsi256_ps;
        let heads = transpose8([org[0], org[1], org[2], inv[0], inv[1], inv[2], tmin, cast(octant)]);
        let tails = transpose8([on[0], on[1], on[2], of[0], of[1], of[2], cast(flags), cast(table(&PLANE_WORDS[1]))]);
        for (k, o) in out.iter_mut().enumerate() {
            let p = (o as *mut BoxRay).cast::<f32>();
            _mm256_store_ps(p, heads[k]);
            _mm256_store_ps(p.add(8), tails[k]);
        }
        admitted
    }
}

/// [`box_ray8`] of eight rays at once, one ray per lane: the same operations per lane, so the
/// same values ([`PacketBoxRays`] holds each ray's [`BoxRay`] fields).
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
pub(super) unsafe fn box_rays8(rays: &[Ray; 8]) -> PacketBoxRays {
    // SAFETY: the caller guarantees AVX2; the stores are aligned ones of 8 f32 into the
    // 32-byte aligned arrays of `out`.
    unsafe {
        let f = transpose_rays8(rays);
        let (org, dir, tmin, tmax) = ([f[0], f[1], f[2]], [f[3], f[4], f[5]], f[6], f[7]);
        let inv = inv8(dir);
        let (on, of, fma_all, live) = fused_terms8(org, dir, inv, tmin, tmax);
        let mut out = PacketBoxRays::EMPTY;
        for axis in 0..3 {
            _mm256_store_ps(out.org[axis].as_mut_ptr(), org[axis]);
            _mm256_store_ps(out.inv[axis].as_mut_ptr(), inv[axis]);
            _mm256_store_ps(out.oi_near[axis].as_mut_ptr(), on[axis]);
            _mm256_store_ps(out.oi_far[axis].as_mut_ptr(), of[axis]);
        }
        _mm256_store_ps(out.tmin.as_mut_ptr(), tmin);
        _mm256_store_ps(out.tmax.as_mut_ptr(), tmax);
        _mm256_store_ps(out.tie.as_mut_ptr(), _mm256_mul_ps(tmax, _mm256_set1_ps(TIE_SCALE)));
        out.fma = _mm256_movemask_ps(fma_all) as u32;
        out.live = _mm256_movemask_ps(live) as u32;
        let (sx, sy, sz) =
            (_mm256_movemask_ps(dir[0]) as u32, _mm256_movemask_ps(dir[1]) as u32, _mm256_movemask_ps(dir[2]) as u32);
        for k in 0..8 {
            let oct = (sx >> k & 1) | (sy >> k & 1) << 1 | (sz >> k & 1) << 2;
            out.octant[k] = oct;
            out.planes[k][..6].copy_from_slice(&PLANES[oct as usize]);
        }
        out
    }
}

// `box_ray` loads a ray as one vector: (origin, dir, tmin, tmax); it and `set_up8` store a
// `BoxRay` as two vectors.
const _: () = assert!(
    std::mem::size_of::<Ray>() == 32
        && std::mem::offset_of!(Ray, origin) == 0
        && std::mem::offset_of!(Ray, dir) == 12
        && std::mem::offset_of!(Ray, tmin) == 24
        && std::mem::offset_of!(Ray, tmax) == 28
        && std::mem::size_of::<BoxRay>() == 64
        && std::mem::offset_of!(BoxRay, org) == 0
        && std::mem::offset_of!(BoxRay, inv) == 12
        && std::mem::offset_of!(BoxRay, tmin) == 24
        && std::mem::offset_of!(BoxRay, octant) == 28
        && std::mem::offset_of!(BoxRay, oi_near) == 32
        && std::mem::offset_of!(BoxRay, oi_far) == 44
        && std::mem::offset_of!(BoxRay, fma) == 56
        && std::mem::offset_of!(BoxRay, live) == 57
        && std::mem::offset_of!(BoxRay, planes) == 58
);

/// `BoxRay::new` in one AVX2 register: the same operations in the same order per lane, so
/// the same values.
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
pub(super) unsafe fn box_ray8(ray: &Ray) -> BoxRay {
    // SAFETY: the caller guarantees AVX2; `Ray` is exactly 8 f32 (asserted above) and the two
    // stores write the two 32-byte halves of `out` (asserted layout); the flag bytes are
    // written after the second store.
    unsafe {
        let v = _mm256_loadu_ps((ray as *const Ray).cast::<f32>());
        let d = _mm256_permutevar8x32_ps(v, _mm256_setr_epi32(3, 4, 5, 3, 4, 5, 3, 4));
        let sign = _mm256_set1_ps(-0.0);
        let inf = _mm256_set1_ps(f32::INFINITY);
        let i = _mm256_div_ps(_mm256_set1_ps(1.0), d);
        let finite = |x: __m256| _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_andnot_ps(sign, x), inf);
        let big = _mm256_or_ps(_mm256_and_ps(d, sign), _mm256_set1_ps(f32::MAX));
        let inv = _mm256_blendv_ps(big, i, finite(i));
        let oi = _mm256_mul_ps(v, inv);
        let e = _mm256_add_ps(
            _mm256_mul_ps(_mm256_andnot_ps(sign, oi), _mm256_set1_ps(1.0 / 1048576.0)),
            _mm256_set1_ps(f32::MIN_POSITIVE),
        );
        let (on, of) = (_mm256_add_ps(oi, e), _mm256_sub_ps(oi, e));
        let spread = _mm256_setr_epi32(0, 0, 0, 0, 1, 2, 0, 0);
        let head = _mm256_blend_ps::<0b0011_1000>(v, _mm256_permutevar8x32_ps(inv, spread));
        let tail = _mm256_blend_ps::<0b0011_1000>(on, _mm256_permutevar8x32_ps(of, spread));
        // Lanes 6 and 7 hold the flags and plane offsets: zero until set below.
        let tail = _mm256_blend_ps::<0b1100_0000>(tail, _mm256_setzero_ps());
        let mut out = BoxRay::DEAD;
        let p = (&mut out as *mut BoxRay).cast::<f32>();
        _mm256_store_ps(p, head);
        _mm256_store_ps(p.add(8), tail);
        let vm = _mm256_movemask_ps(v) as u32;
        out.octant = vm >> 3 & 7;
        out.planes = PLANES[out.octant as usize];
        out.fma = _mm256_movemask_ps(finite(tail)) & 0x3f == 0x3f;
        let dir_nonzero = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_NEQ_UQ>(v, _mm256_setzero_ps())) & 0x38 != 0;
        out.live = _mm256_movemask_ps(finite(v)) & 0x3f == 0x3f && dir_nonzero && ray.tmin <= ray.tmax;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::simd::{BoxTest, Scalar, set_up_each};
    use crate::cpu::{Avx2, with_avx2};
    use glam::Vec3;

    /// Every field of the AVX2 set-up equals the scalar one (bit for bit, any NaN matching
    /// any NaN), including zero, negative zero, denormal, huge, infinite and NaN components.
    #[test]
    fn avx2_box_ray_matches_scalar() {
        let Some(avx) = Avx2::new() else { return };
        let vals = [0.0, -0.0, 1e-40, -1e-40, 1.0, -2.5, 3e38, -3e38, 1e-30, f32::INFINITY, f32::NAN, 7.25];
        let mut n = 0;
        for (i, &a) in vals.iter().enumerate() {
            for (j, &b) in vals.iter().enumerate() {
                for (k, &c) in vals.iter().enumerate() {
                    let o = Vec3::new(vals[(i + 4) % 12], b * 3.0, vals[(k + j) % 12]);
                    let ray = Ray { origin: o, dir: Vec3::new(a, b, c), tmin: vals[(i + j) % 12], tmax: 1e30 };
                    let (s, v) = (BoxRay::new(&ray), with_avx2(avx, |t| t.box_ray(&ray)));
                    let bits = |x: [f32; 3]| x.map(|v| if v.is_nan() { u32::MAX } else { v.to_bits() });
                    assert_eq!(bits(s.org), bits(v.org), "{ray:?}");
                    assert_eq!(bits(s.inv), bits(v.inv), "{ray:?}");
                    assert_eq!(bits(s.oi_near), bits(v.oi_near), "{ray:?}");
                    assert_eq!(bits(s.oi_far), bits(v.oi_far), "{ray:?}");
                    assert_eq!(s.tmin.to_bits(), v.tmin.to_bits(), "{ray:?}");
                    assert_eq!((s.octant, s.fma, s.live), (v.octant, v.fma, v.live), "{ray:?}");
                    assert_eq!(s.planes, v.planes, "{ray:?}");
                    n += s.live as u32;
                }
            }
        }
        assert!(n > 100, "too few live rays in the sample: {n}");
    }

    /// The eight-lane set-up gives every ray the scalar set-up's values (bit for bit, any NaN
    /// matching any NaN) and every live ray the scalar root-box answer, on rays with zero,
    /// negative zero, denormal, huge, infinite and NaN components and rays aimed at the box's
    /// corners and edges; groups of every length 1..=32 (partial groups take the scalar path
    /// for their tail), with and without a root box.
    #[test]
    fn avx2_set_up_matches_scalar() {
        let Some(avx) = Avx2::new() else { return };
        let root = RootBox::new(Vec3::new(-1.0, -2.0, 0.5), Vec3::new(3.0, 1.0, 0.75)).unwrap();
        let vals = [0.0, -0.0, 1e-40, -1e-40, 1.0, -2.5, 3e38, -3e38, 1e-30, f32::INFINITY, 0.6, 7.25, f32::NAN];
        let mut rays = Vec::new();
        for (i, &a) in vals.iter().enumerate() {
            for (j, &b) in vals.iter().enumerate() {
                for &c in &vals {
                    let o = Vec3::new(vals[(i + 4) % 13] - 0.5, b * 0.5 - 1.0, vals[(j + 7) % 13]);
                    let tmin = [0.0, 0.5, -0.0][(i + j) % 3];
                    rays.push(Ray { origin: o, dir: Vec3::new(a, b, c), tmin, tmax: vals[(i + j) % 13].abs() });
                }
            }
        }
        // Rays through the corners and edge midpoints of the (widened) box, from outside.
        let (lo, hi) = (Vec3::from(root.lo), Vec3::from(root.hi));
        for k in 0..27 {
            let f = Vec3::new((k % 3) as f32, (k / 3 % 3) as f32, (k / 9) as f32) * 0.5;
            let target = lo + (hi - lo) * f;
            for o in [Vec3::new(9.0, 8.0, -7.0), Vec3::new(-5.0, 0.1, 0.6), Vec3::new(0.0, -6.0, 0.7)] {
                rays.push(Ray { origin: o, dir: target - o, tmin: 0.0, tmax: f32::INFINITY });
                rays.push(Ray { origin: o, dir: target - o, tmin: 0.0, tmax: 1.0 });
            }
        }
        let bits = |x: [f32; 3]| x.map(|v| if v.is_nan() { u32::MAX } else { v.to_bits() });
        let mut checked = [0u32; 2];
        let (mut fast, mut slow) = ([BoxRay::DEAD; 32], [BoxRay::DEAD; 32]);
        for len in 1..=32 {
            for group in rays.chunks(len) {
                for root in [Some(&root), None] {
                    let n = group.len();
                    let got = with_avx2(avx, |t| t.set_up(root, group, &mut fast[..n]));
                    let want = set_up_each(Scalar, root, group, &mut slow[..n]);
                    for (i, r) in group.iter().enumerate() {
                        let (s, v) = (&slow[i], &fast[i]);
                        if s.live {
                            assert_eq!(got >> i & 1, want >> i & 1, "{r:?}");
                            checked[(want >> i & 1) as usize] += 1;
                        }
                        if got >> i & 1 == 0 {
                            // Not admitted: its set-up is not read.
                            continue;
                        }
                        assert_eq!(bits(s.org), bits(v.org), "{r:?}");
                        assert_eq!(bits(s.inv), bits(v.inv), "{r:?}");
                        assert_eq!(bits(s.oi_near), bits(v.oi_near), "{r:?}");
                        assert_eq!(bits(s.oi_far), bits(v.oi_far), "{r:?}");
                        assert_eq!(bits([s.tmin; 3]), bits([v.tmin; 3]), "{r:?}");
                        assert_eq!((s.octant, s.fma, s.live, s.planes), (v.octant, v.fma, v.live, v.planes), "{r:?}");
                    }
                }
            }
        }
        assert!(checked[0] > 1000 && checked[1] > 1000, "too few live rays in or out: {checked:?}");
    }
}
