//! The SIMD box tests. All `unsafe` of the BVH lives here: each kernel can only be reached
//! through a [`crate::cpu`] token whose constructor checked the CPU at run time.
use super::boxtest::{
    BoxRay, BoxTest, EXIT_SCALE, Frustum, PLANES, PREFETCH_BYTES, RootBox, TIE_SCALE, far, near, set_up_each,
};
use super::leaf::Tri4;
use super::packet::{PACKET, PacketBoxRays, PacketShear, PacketTest, TriRays};
use super::wide::{Node8, WIDTH};
use crate::accel::triangle::{ShearedRay, range_end};
use crate::cpu::{Avx2, Sse};
use crate::geometry::Ray;
use crate::geometry::error_bound::gamma;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

#[cfg(target_arch = "x86_64")]
impl BoxTest for Sse {
    #[inline(always)]
    fn prefetch_at(self, p: *const u8) {
        prefetch_lines(p);
    }

    #[inline(always)]
    fn test(self, node: &Node8, r: &BoxRay, oct: u32, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        // SAFETY: `Sse` exists only if SSE4.1 was detected; loads/stores are unaligned ones on
        // in-bounds arrays of 8 f32 at offsets 0 and 4 (`BoxRay` plane indices are < 6).
        unsafe {
            let mut mask = 0u32;
            for half in 0..2 {
                let o = half * 4;
                let lane = |plane: usize, axis: usize| {
                    let p = _mm_loadu_ps(node.b.as_ptr().add(plane).cast::<f32>().add(o));
                    _mm_mul_ps(_mm_sub_ps(p, _mm_set1_ps(r.org[axis])), _mm_set1_ps(r.inv[axis]))
                };
                let t0 = lane(near(oct, 0), 0);
                let t1 = lane(near(oct, 1), 1);
                let t2 = lane(near(oct, 2), 2);
                let u0 = lane(far(oct, 0), 0);
                let u1 = lane(far(oct, 1), 1);
                let u2 = lane(far(oct, 2), 2);
                let enter = _mm_max_ps(_mm_max_ps(_mm_max_ps(t0, t1), t2), _mm_set1_ps(r.tmin));
                let exit = _mm_min_ps(
                    _mm_mul_ps(_mm_min_ps(_mm_min_ps(u0, u1), u2), _mm_set1_ps(EXIT_SCALE)),
                    _mm_set1_ps(tmax * TIE_SCALE),
                );
                _mm_storeu_ps(tnear.as_mut_ptr().add(o), enter);
                mask |= (_mm_movemask_ps(_mm_cmple_ps(enter, exit)) as u32) << o;
            }
            mask
        }
    }

    #[inline(always)]
    fn tri_filter(self, blk: &Tri4, sr: &ShearedRay, tmin: f32, tmax: f32, lanes: u32) -> u32 {
        // SAFETY: `Sse` exists only if SSE4.1 was detected.
        unsafe { tri_filter4(blk, sr, tmin, tmax) & lanes }
    }
}

#[cfg(target_arch = "x86_64")]
impl PacketTest for Sse {
    #[inline(always)]
    fn tri_filter_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, lanes: u32) -> u32 {
        let _ = ray;
        // SAFETY: `Sse` exists only if SSE4.1 was detected.
        unsafe { tri_filter4_lane(blk, p, k % PACKET) & lanes }
    }
}

#[cfg(target_arch = "x86_64")]
impl BoxTest for Avx2 {
    #[inline(always)]
    fn prefetch_at(self, p: *const u8) {
        prefetch_lines(p);
    }

    #[inline(always)]
    fn test(self, node: &Node8, r: &BoxRay, oct: u32, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        self.test_form(node, r, oct, r.fma, tmax, tnear)
    }

    #[inline(always)]
    fn test_form(self, node: &Node8, r: &BoxRay, oct: u32, fma: bool, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        // SAFETY: `Avx2` exists only if AVX2 and FMA were detected; the store is unaligned on
        // an array of exactly 8 f32.
        unsafe {
            debug_assert_eq!((oct, fma), (r.octant, r.fma));
            let (enter, hit) = slab8(node, r, tmax, fma);
            _mm256_storeu_ps(tnear.as_mut_ptr(), enter);
            _mm256_movemask_ps(hit) as u32
        }
    }

    #[inline(always)]
    fn box_ray(self, ray: &Ray) -> BoxRay {
        // SAFETY: `Avx2` exists only if AVX2 was detected.
        unsafe { box_ray8(ray) }
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn visit(
        self,
        node: &Node8,
        r: &BoxRay,
        oct: u32,
        fma: bool,
        tmax: f32,
        nodes: &mut [u32; WIDTH],
        dists: &mut [f32; WIDTH],
    ) -> (u32, u32) {
        // SAFETY: `Avx2` exists only if AVX2 and FMA were detected; the loads are unaligned
        // ones of 8 u32 inside `node`, the stores go to arrays of exactly 8 entries;
        // `COMPRESS` is indexed by an 8-bit mask.
        unsafe {
            debug_assert_eq!((oct, fma), (r.octant, r.fma));
            let (enter, hit) = slab8(node, r, tmax, fma);
            let mask = _mm256_movemask_ps(hit) as u32;
            let n = mask.count_ones();
            if n == 1 {
                return (1, node.child[mask.trailing_zeros() as usize]);
            }
            if n > 1 {
                return (n, push_ordered(node, oct, enter, hit, n, nodes, dists).0);
            }
            (n, 0)
        }
    }

    #[inline(always)]
    fn visit_frustum(
        self,
        node: &Node8,
        f: &Frustum,
        tmax: f32,
        nodes: &mut [u32; WIDTH],
        dists: &mut [f32; WIDTH],
        slots: &mut [u32; WIDTH],
    ) -> u32 {
        // SAFETY: `Avx2` exists only if AVX2 and FMA were detected; `push_ordered` and the
        // store write arrays of exactly 8 entries.
        unsafe {
            let (enter, hit) = frustum8(node, f, tmax);
            let n = _mm256_movemask_ps(hit).count_ones();
            if n > 0 {
                let idx = push_ordered(node, f.octant, enter, hit, n, nodes, dists).1;
                // The permutation's indices carry other octants' bits above the low three.
                _mm256_storeu_si256(slots.as_mut_ptr().cast(), _mm256_and_si256(idx, _mm256_set1_epi32(7)));
            }
            n
        }
    }

    #[inline(always)]
    fn set_up(self, root: Option<&RootBox>, rays: &[Ray], out: &mut [BoxRay]) -> u32 {
        let mut mask = 0;
        for (k, (eight, o)) in rays.chunks(8).zip(out.chunks_mut(8)).enumerate() {
            let m = match (<&[Ray; 8]>::try_from(eight), o.len()) {
                // SAFETY: `Avx2` exists only if AVX2 was detected.
                (Ok(eight), 8) => unsafe { set_up8(root, eight, o.try_into().expect("eight set-ups")) },
                _ => set_up_each(self, root, eight, o),
            };
            mask |= m << (8 * k);
        }
        mask
    }

    #[inline(always)]
    fn tri_filter(self, blk: &Tri4, sr: &ShearedRay, tmin: f32, tmax: f32, lanes: u32) -> u32 {
        // SAFETY: `Avx2` exists only if AVX2 (hence SSE4.1) was detected.
        unsafe { tri_filter4(blk, sr, tmin, tmax) & lanes }
    }
}

#[cfg(target_arch = "x86_64")]
impl PacketTest for Avx2 {
    #[inline(always)]
    fn tri_filter_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, lanes: u32) -> u32 {
        let _ = ray;
        // SAFETY: `Avx2` exists only if AVX2 (hence SSE4.1) was detected.
        unsafe { tri_filter4_lane(blk, p, k % PACKET) & lanes }
    }

    #[inline(always)]
    fn packet_shear(self, rays: &[Ray]) -> PacketShear {
        match <&[Ray; 8]>::try_from(rays) {
            // SAFETY: `Avx2` exists only if AVX2 was detected.
            Ok(eight) => unsafe { shear8(eight) },
            Err(_) => PacketShear::each(rays),
        }
    }

    #[inline(always)]
    fn slot_rays(self, node: &Node8, slot: usize, p: &PacketBoxRays, oct: u32, closest: &[f32; PACKET]) -> u32 {
        // SAFETY: `Avx2` exists only if AVX2 was detected; `slot` < 8 indexes the node's rows.
        unsafe { slot_rays8(node, slot % WIDTH, p, oct, closest) }
    }

    #[inline(always)]
    fn tri_rays(self, blk: &Tri4, lane: usize, p: &PacketShear, closest: &[f32; PACKET]) -> Option<TriRays> {
        // SAFETY: `Avx2` exists only if AVX2 was detected; `lane` < 4 indexes the block's rows.
        Some(unsafe { tri_rays8(blk, lane % 4, p, closest) })
    }

    #[inline(always)]
    fn packet_box_rays(self, rays: &[Ray]) -> PacketBoxRays {
        match <&[Ray; 8]>::try_from(rays) {
            // SAFETY: `Avx2` exists only if AVX2 was detected.
            Ok(eight) => unsafe { box_rays8(eight) },
            Err(_) => PacketBoxRays::each(self, rays),
        }
    }

    #[inline(always)]
    fn test_lane(self, node: &Node8, p: &PacketBoxRays, k: usize) -> u32 {
        // SAFETY: `Avx2` exists only if AVX2 and FMA were detected.
        unsafe { _mm256_movemask_ps(slab8_lane(node, p, k % PACKET)) as u32 }
    }
}

/// Ray fields of eight rays, one register per field (lane k = ray k): origin x, y, z,
/// direction x, y, z, tmin, tmax.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn transpose_rays8(rays: &[Ray; 8]) -> [__m256; 8] {
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
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn transpose8(r: [__m256; 8]) -> [__m256; 8] {
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
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn inv8(dir: [__m256; 3]) -> [__m256; 3] {
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
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn fused_terms8(
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
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn set_up8(root: Option<&RootBox>, rays: &[Ray; 8], out: &mut [BoxRay; 8]) -> u32 {
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
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn box_rays8(rays: &[Ray; 8]) -> PacketBoxRays {
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

/// [`slab8`]'s hit lanes for lane `k` of a packet (the same operations on the same values).
///
/// # Safety
/// The CPU must have AVX2 and FMA; `k` < 8.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn slab8_lane(node: &Node8, p: &PacketBoxRays, k: usize) -> __m256 {
    // SAFETY: the caller guarantees AVX2 and FMA; each load reads 8 f32 of `node.b` at a
    // byte offset `32 * plane` with plane < 6 (`planes[k]` is `PLANES[octant]` or zero),
    // unaligned loads.
    unsafe {
        let base = node.b.as_ptr().cast::<u8>();
        let pl = &p.planes[k];
        let plane = |i: usize| _mm256_loadu_ps(base.add(pl[i] as usize).cast::<f32>());
        let b = |a: &[[f32; 8]; 3], axis: usize| _mm256_set1_ps(a[axis][k]);
        let (t0, t1, t2, u0, u1, u2);
        if p.fma >> k & 1 != 0 {
            t0 = _mm256_fmsub_ps(plane(0), b(&p.inv, 0), b(&p.oi_near, 0));
            t1 = _mm256_fmsub_ps(plane(1), b(&p.inv, 1), b(&p.oi_near, 1));
            t2 = _mm256_fmsub_ps(plane(2), b(&p.inv, 2), b(&p.oi_near, 2));
            u0 = _mm256_fmsub_ps(plane(3), b(&p.inv, 0), b(&p.oi_far, 0));
            u1 = _mm256_fmsub_ps(plane(4), b(&p.inv, 1), b(&p.oi_far, 1));
            u2 = _mm256_fmsub_ps(plane(5), b(&p.inv, 2), b(&p.oi_far, 2));
        } else {
            t0 = _mm256_mul_ps(_mm256_sub_ps(plane(0), b(&p.org, 0)), b(&p.inv, 0));
            t1 = _mm256_mul_ps(_mm256_sub_ps(plane(1), b(&p.org, 1)), b(&p.inv, 1));
            t2 = _mm256_mul_ps(_mm256_sub_ps(plane(2), b(&p.org, 2)), b(&p.inv, 2));
            u0 = _mm256_mul_ps(_mm256_sub_ps(plane(3), b(&p.org, 0)), b(&p.inv, 0));
            u1 = _mm256_mul_ps(_mm256_sub_ps(plane(4), b(&p.org, 1)), b(&p.inv, 1));
            u2 = _mm256_mul_ps(_mm256_sub_ps(plane(5), b(&p.org, 2)), b(&p.inv, 2));
        }
        let enter = _mm256_max_ps(_mm256_max_ps(t0, t1), _mm256_max_ps(t2, _mm256_set1_ps(p.tmin[k])));
        exit_hit(enter, [u0, u1, u2], _mm256_set1_ps(p.tie[k]))
    }
}

/// Entry distances and hit lanes of the eight children of `node` (AVX2 + FMA slab test; `fma`
/// is `r.fma`: the fused form when its terms are finite).
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn slab8(node: &Node8, r: &BoxRay, tmax: f32, fma: bool) -> (__m256, __m256) {
    // SAFETY: the caller guarantees AVX2 and FMA; each load reads 8 f32 of `node.b` at a
    // byte offset `32 * plane` with plane < 6 (`BoxRay::planes` is always `PLANES[octant]`),
    // unaligned loads.
    unsafe {
        let base = node.b.as_ptr().cast::<u8>();
        let plane = |k: usize| _mm256_loadu_ps(base.add(r.planes[k] as usize).cast::<f32>());
        let (t0, t1, t2, u0, u1, u2);
        if fma {
            // One fused op per plane (see `boxtest::fma_terms` for why this stays safe).
            let d = |k: usize, axis: usize, oi: &[f32; 3]| {
                _mm256_fmsub_ps(plane(k), _mm256_set1_ps(r.inv[axis]), _mm256_set1_ps(oi[axis]))
            };
            t0 = d(0, 0, &r.oi_near);
            t1 = d(1, 1, &r.oi_near);
            t2 = d(2, 2, &r.oi_near);
            u0 = d(3, 0, &r.oi_far);
            u1 = d(4, 1, &r.oi_far);
            u2 = d(5, 2, &r.oi_far);
        } else {
            let d = |k: usize, axis: usize| {
                _mm256_mul_ps(_mm256_sub_ps(plane(k), _mm256_set1_ps(r.org[axis])), _mm256_set1_ps(r.inv[axis]))
            };
            t0 = d(0, 0);
            t1 = d(1, 1);
            t2 = d(2, 2);
            u0 = d(3, 0);
            u1 = d(4, 1);
            u2 = d(5, 2);
        }
        // A shallow tree of the exact max (no operand is NaN: `inv` is finite and non-zero
        // and the fused terms finite), and `enter <= min(min(u0, u1, u2) * EXIT_SCALE, tmax *
        // TIE_SCALE)` as four compares (see `exit_hit`), so fewer dependent steps per node
        // with the same answer.
        let enter = _mm256_max_ps(_mm256_max_ps(t0, t1), _mm256_max_ps(t2, _mm256_set1_ps(r.tmin)));
        (enter, exit_hit(enter, [u0, u1, u2], _mm256_set1_ps(tmax * TIE_SCALE)))
    }
}

/// The lanes where `enter <= min(min(u0, u1, u2) * EXIT_SCALE, tie)`, by one compare per
/// term: rounding is monotone, so `min(u) * EXIT_SCALE` equals `min(u * EXIT_SCALE)` bit for
/// bit and the answer is the same, but the scaled exits are ready when the entry is (its max
/// tree is as deep as the min tree), so the node step waits one compare and two ands after
/// the entry instead of two mins, a multiply and a compare after the exits.
///
/// # Safety
/// The CPU must have AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn exit_hit(enter: __m256, u: [__m256; 3], tie: __m256) -> __m256 {
    // SAFETY: the caller guarantees AVX; register operations only.
    unsafe {
        let scale = _mm256_set1_ps(EXIT_SCALE);
        let le = |u: __m256| _mm256_cmp_ps::<_CMP_LE_OQ>(enter, _mm256_mul_ps(u, scale));
        _mm256_and_ps(
            _mm256_and_ps(le(u[0]), le(u[1])),
            _mm256_and_ps(le(u[2]), _mm256_cmp_ps::<_CMP_LE_OQ>(enter, tie)),
        )
    }
}

/// Pushes the `n` (> 0) children of `node` hit per `hit`, in the node's order for octant
/// `oct` (far to near), with their `enter` distances; returns the nearest (the last pushed)
/// and the slots pushed (lane `k`: the slot of the `k`-th pushed child, for `k < n`).
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn push_ordered(
    node: &Node8,
    oct: u32,
    enter: __m256,
    hit: __m256,
    n: u32,
    nodes: &mut [u32; WIDTH],
    dists: &mut [f32; WIDTH],
) -> (u32, __m256i) {
    // SAFETY: the caller guarantees AVX2; the loads are unaligned ones of 8 u32 inside
    // `node`, the stores go to arrays of exactly 8 entries; `COMPRESS` is indexed by an 8-bit
    // mask.
    unsafe {
        // Slots in the octant's order (far to near); `permutevar8x32` reads only the low
        // three bits of each index, so the other octants' bits need no masking.
        let order = _mm256_srl_epi32(_mm256_loadu_si256(node.perm.as_ptr().cast()), _mm_cvtsi32_si128(3 * oct as i32));
        let sorted_hit = _mm256_movemask_ps(_mm256_permutevar8x32_ps(hit, order)) as usize;
        // Then the hit ones packed to the front, keeping that order.
        let pack = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(COMPRESS[sorted_hit] as i64));
        let idx = _mm256_permutevar8x32_epi32(order, pack);
        let child = _mm256_permutevar8x32_epi32(_mm256_loadu_si256(node.child.as_ptr().cast()), idx);
        _mm256_storeu_si256(nodes.as_mut_ptr().cast(), child);
        _mm256_storeu_ps(dists.as_mut_ptr(), _mm256_permutevar8x32_ps(enter, idx));
        // The nearest (the last pushed) from the register, not back from the stack.
        let top = _mm256_permutevar8x32_epi32(child, _mm256_set1_epi32(n as i32 - 1));
        (_mm256_cvtsi256_si32(top) as u32, idx)
    }
}

/// [`Frustum::span`] of the eight children of `node` at once (the same operations per lane),
/// and the lanes the packet may enter within `tmax`.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn frustum8(node: &Node8, f: &Frustum, tmax: f32) -> (__m256, __m256) {
    // SAFETY: the caller guarantees AVX2; each load reads 8 f32 of `node.b` at a byte offset
    // `32 * plane` with plane < 6 (`Frustum::planes` is `PLANES[octant]`), unaligned loads.
    unsafe {
        let base = node.b.as_ptr().cast::<u8>();
        let plane = |k: usize| _mm256_loadu_ps(base.add(f.planes[k] as usize).cast::<f32>());
        let (lo, hi) = (|a: usize| _mm256_set1_ps(f.inv_lo[a]), |a: usize| _mm256_set1_ps(f.inv_hi[a]));
        let d = |k: usize, axis: usize| _mm256_sub_ps(plane(k), _mm256_set1_ps(f.org[axis]));
        let near = |axis: usize| {
            let d = d(axis, axis);
            _mm256_min_ps(_mm256_mul_ps(d, lo(axis)), _mm256_mul_ps(d, hi(axis)))
        };
        let far = |axis: usize| {
            let d = d(axis + 3, axis);
            _mm256_max_ps(_mm256_mul_ps(d, lo(axis)), _mm256_mul_ps(d, hi(axis)))
        };
        let enter = _mm256_max_ps(_mm256_max_ps(near(0), near(1)), _mm256_max_ps(near(2), _mm256_set1_ps(f.tmin)));
        (enter, exit_hit(enter, [far(0), far(1), far(2)], _mm256_set1_ps(tmax * TIE_SCALE)))
    }
}

/// For each 8-bit mask, the indices of its set bits in increasing order, one per byte from
/// the lowest (the rest zero): the lane permutation that packs the selected lanes to the front.
static COMPRESS: [u64; 256] = {
    let mut t = [0u64; 256];
    let mut m = 0;
    while m < 256 {
        let (mut k, mut lane) = (0, 0);
        while lane < 8 {
            if m >> lane & 1 == 1 {
                t[m] |= (lane as u64) << (8 * k);
                k += 1;
            }
            lane += 1;
        }
        m += 1;
    }
    t
};

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
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn box_ray8(ray: &Ray) -> BoxRay {
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

/// Prefetches the [`PREFETCH_BYTES`] from `p` into all cache levels.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn prefetch_lines(p: *const u8) {
    let mut off = 0;
    while off < PREFETCH_BYTES {
        // SAFETY: a prefetch is a hint that never faults, whatever the address; SSE (which
        // has the instruction) is part of x86-64.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(off).cast::<i8>()) };
        off += 64;
    }
}

/// The watertight test of `crate::accel::triangle::intersect_sheared` up to its range check,
/// on four triangles at once with the same operations in the same order (separate multiply
/// and add, never fused), so a lane it rejects is one the scalar test rejects too. Lanes with
/// an edge function of exactly zero are kept: only the scalar f64 recomputation settles them.
///
/// # Safety
/// The CPU must have SSE4.1.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn tri_filter4(blk: &Tri4, sr: &ShearedRay, tmin: f32, tmax: f32) -> u32 {
    // SAFETY: the caller guarantees SSE4.1; loads are aligned (`Tri4` is 64-byte aligned and
    // each lane array is 16 bytes at a multiple of 16).
    unsafe {
        let (kx, ky, kz) = (sr.kx, sr.ky, sr.kz);
        let [okx, oky, okz] = sr.org_k;
        let (ox, oy, oz) = (_mm_set1_ps(okx), _mm_set1_ps(oky), _mm_set1_ps(okz));
        let (sx, sy, sz) = (_mm_set1_ps(sr.sx), _mm_set1_ps(sr.sy), _mm_set1_ps(sr.sz));
        // Sheared corner: (x, y, z) = (p[kx] - o[kx] - sx * az, p[ky] - o[ky] - sy * az, p[kz] - o[kz]).
        let corner = |c: usize| {
            let p = &blk.c[c];
            let z = _mm_sub_ps(_mm_load_ps(p[kz].as_ptr()), oz);
            let x = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(p[kx].as_ptr()), ox), _mm_mul_ps(sx, z));
            let y = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(p[ky].as_ptr()), oy), _mm_mul_ps(sy, z));
            [x, y, z]
        };
        filter4_tail(corner(0), corner(1), corner(2), sz, tmin, range_end(tmax))
    }
}

/// [`tri_filter4`] for lane `k` of a packet's leaf set-up: the same values, read from it.
///
/// # Safety
/// The CPU must have SSE4.1; `k` < 8.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn tri_filter4_lane(blk: &Tri4, p: &PacketShear, k: usize) -> u32 {
    // SAFETY: the caller guarantees SSE4.1; loads are aligned ones of 16 bytes at offsets
    // `p.rows[k][i]`, which are 16 * axis with axis < 3 (`PacketShear`), inside a corner's
    // three rows of 16 bytes (`Tri4` is 64-byte aligned).
    unsafe {
        let r = &p.rows[k];
        let (ra, rb, rc) = (r[0] as usize, r[1] as usize, r[2] as usize);
        let (ox, oy, oz) = (_mm_set1_ps(p.org[0][k]), _mm_set1_ps(p.org[1][k]), _mm_set1_ps(p.org[2][k]));
        let (sx, sy, sz) = (_mm_set1_ps(p.shear[0][k]), _mm_set1_ps(p.shear[1][k]), _mm_set1_ps(p.shear[2][k]));
        // As in `tri_filter4`, with the rows at the set-up's offsets.
        let corner = |c: usize| {
            let q = blk.c[c].as_ptr().cast::<u8>();
            let z = _mm_sub_ps(_mm_load_ps(q.add(rc).cast::<f32>()), oz);
            let x = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(q.add(ra).cast::<f32>()), ox), _mm_mul_ps(sx, z));
            let y = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(q.add(rb).cast::<f32>()), oy), _mm_mul_ps(sy, z));
            [x, y, z]
        };
        let (a, b, c) = (corner(0), corner(1), corner(2));
        filter4_tail(a, b, c, sz, p.tmin[k], p.tend[k])
    }
}

/// [`PacketShear::set`] (that is [`ShearedRay::of`]) of eight rays at once, one ray per
/// lane: the same comparisons choose the axes (NaN compares false in both), the same
/// divisions give `sx`, `sy`, `sz`, so the same values.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn shear8(rays: &[Ray; 8]) -> PacketShear {
    // SAFETY: the caller guarantees AVX2; the stores are aligned ones of 8 f32 into the
    // 32-byte aligned arrays of `out`.
    unsafe {
        let f = transpose_rays8(rays);
        let ([ox, oy, oz], [dx, dy, dz], tmax) = ([f[0], f[1], f[2]], [f[3], f[4], f[5]], f[7]);
        let sign = _mm256_set1_ps(-0.0);
        let (ax, ay, az) = (_mm256_andnot_ps(sign, dx), _mm256_andnot_ps(sign, dy), _mm256_andnot_ps(sign, dz));
        // kz = 0 where |x| >= |y| and |x| >= |z|, else 1 where |y| >= |z|, else 2.
        let m0 = _mm256_and_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(ax, ay), _mm256_cmp_ps::<_CMP_GE_OQ>(ax, az));
        let m1 = _mm256_andnot_ps(m0, _mm256_cmp_ps::<_CMP_GE_OQ>(ay, az));
        // Per lane: (x, y, z) picked as (v[kx], v[ky], v[kz]) before the swap: kz = 0 gives
        // (1, 2, 0), kz = 1 gives (2, 0, 1), kz = 2 gives (0, 1, 2).
        let pick = |x: __m256, y: __m256, z: __m256| {
            (
                _mm256_blendv_ps(_mm256_blendv_ps(x, z, m1), y, m0),
                _mm256_blendv_ps(_mm256_blendv_ps(y, x, m1), z, m0),
                _mm256_blendv_ps(_mm256_blendv_ps(z, y, m1), x, m0),
            )
        };
        let (dkx, dky, dkz) = pick(dx, dy, dz);
        let (okx, oky, okz) = pick(ox, oy, oz);
        // A negative d[kz] swaps kx and ky (keeps the winding).
        let neg = _mm256_cmp_ps::<_CMP_LT_OQ>(dkz, _mm256_setzero_ps());
        let (dkx, dky) = (_mm256_blendv_ps(dkx, dky, neg), _mm256_blendv_ps(dky, dkx, neg));
        let (okx, oky) = (_mm256_blendv_ps(okx, oky, neg), _mm256_blendv_ps(oky, okx, neg));
        let mut out = PacketShear::EMPTY;
        _mm256_store_ps(out.org[0].as_mut_ptr(), okx);
        _mm256_store_ps(out.org[1].as_mut_ptr(), oky);
        _mm256_store_ps(out.org[2].as_mut_ptr(), okz);
        _mm256_store_ps(out.shear[0].as_mut_ptr(), _mm256_div_ps(dkx, dkz));
        _mm256_store_ps(out.shear[1].as_mut_ptr(), _mm256_div_ps(dky, dkz));
        _mm256_store_ps(out.shear[2].as_mut_ptr(), _mm256_div_ps(_mm256_set1_ps(1.0), dkz));
        _mm256_store_ps(out.tmin.as_mut_ptr(), f[6]);
        // range_end(tmax) = tmax + |tmax| * 8 eps.
        let tend = _mm256_add_ps(tmax, _mm256_mul_ps(_mm256_andnot_ps(sign, tmax), _mm256_set1_ps(8.0 * f32::EPSILON)));
        _mm256_store_ps(out.tend.as_mut_ptr(), tend);
        let (b0, b1, bn) =
            (_mm256_movemask_ps(m0) as u32, _mm256_movemask_ps(m1) as u32, _mm256_movemask_ps(neg) as u32);
        for k in 0..8 {
            let (kx, ky, kz) = if b0 >> k & 1 != 0 {
                (1u8, 2u8, 0u8)
            } else if b1 >> k & 1 != 0 {
                (2, 0, 1)
            } else {
                (0, 1, 2)
            };
            let (kx, ky) = if bn >> k & 1 != 0 { (ky, kx) } else { (kx, ky) };
            out.rows[k] = [16 * kx, 16 * ky, 16 * kz, 0];
        }
        out
    }
}

/// [`PacketTest::tri_rays`]: [`tri_filter4`]'s operations for triangle `lane` of `blk` and
/// the eight rays of `p`, one ray per lane (the corner broadcast, the ray's values in its
/// lane, all rays with the axes of lane 0), with `tend` = `range_end(closest)` per lane; then,
/// for the rays it keeps without an exact-zero edge function, the rest of
/// `intersect_sheared`'s operations (the division, the exact range check, the test of
/// whether the triangle reaches back to the origin's depth).
///
/// # Safety
/// The CPU must have AVX2; `lane` < 4.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn tri_rays8(blk: &Tri4, lane: usize, p: &PacketShear, closest: &[f32; PACKET]) -> TriRays {
    // SAFETY: the caller guarantees AVX2; the loads are unaligned ones of 8 f32 from arrays of
    // exactly 8; `rows` are 16 * axis with axis < 3, so the corner indices are in bounds.
    unsafe {
        let r = &p.rows[0];
        let (kx, ky, kz) = ((r[0] / 16) as usize % 3, (r[1] / 16) as usize % 3, (r[2] / 16) as usize % 3);
        // No closures here: one compiled out of line would leave the AVX2 context.
        let o = [
            _mm256_loadu_ps(p.org[0].as_ptr()),
            _mm256_loadu_ps(p.org[1].as_ptr()),
            _mm256_loadu_ps(p.org[2].as_ptr()),
        ];
        let sh = [_mm256_loadu_ps(p.shear[0].as_ptr()), _mm256_loadu_ps(p.shear[1].as_ptr())];
        let sz = _mm256_loadu_ps(p.shear[2].as_ptr());
        let k = (kx, ky, kz);
        let [ax, ay, az] = sheared_corner8(&blk.c[0], lane, k, o, sh);
        let [bx, by, bz] = sheared_corner8(&blk.c[1], lane, k, o, sh);
        let [cx, cy, cz] = sheared_corner8(&blk.c[2], lane, k, o, sh);
        // From here `filter4_tail` lane for lane, with each ray's own range.
        let sign = _mm256_set1_ps(-0.0);
        let (tmin, tmax) = (_mm256_loadu_ps(p.tmin.as_ptr()), _mm256_loadu_ps(closest.as_ptr()));
        let tend = _mm256_add_ps(tmax, _mm256_mul_ps(_mm256_andnot_ps(sign, tmax), _mm256_set1_ps(8.0 * f32::EPSILON)));
        let u = _mm256_sub_ps(_mm256_mul_ps(cx, by), _mm256_mul_ps(cy, bx));
        let v = _mm256_sub_ps(_mm256_mul_ps(ax, cy), _mm256_mul_ps(ay, cx));
        let w = _mm256_sub_ps(_mm256_mul_ps(bx, ay), _mm256_mul_ps(by, ax));
        let zero = _mm256_setzero_ps();
        let on_edge = _mm256_or_ps(
            _mm256_or_ps(_mm256_cmp_ps::<_CMP_EQ_OQ>(u, zero), _mm256_cmp_ps::<_CMP_EQ_OQ>(v, zero)),
            _mm256_cmp_ps::<_CMP_EQ_OQ>(w, zero),
        );
        let neg = _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_min_ps(_mm256_min_ps(u, v), w), zero);
        let pos = _mm256_cmp_ps::<_CMP_GT_OQ>(_mm256_max_ps(_mm256_max_ps(u, v), w), zero);
        let det = _mm256_add_ps(_mm256_add_ps(u, v), w);
        let det_abs = _mm256_andnot_ps(sign, det);
        let det_ok = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_NEQ_OQ>(det, zero),
            _mm256_cmp_ps::<_CMP_LT_OQ>(det_abs, _mm256_set1_ps(f32::INFINITY)),
        );
        // The corners' depths `sz * z`, as the scalar test's `az`, `bz`, `cz`.
        let (da, db, dc) = (_mm256_mul_ps(sz, az), _mm256_mul_ps(sz, bz), _mm256_mul_ps(sz, cz));
        let tt = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(u, da), _mm256_mul_ps(v, db)), _mm256_mul_ps(w, dc));
        let tt_s = _mm256_xor_ps(tt, _mm256_and_ps(det, sign));
        let out_of_range = _mm256_or_ps(
            _mm256_cmp_ps::<_CMP_LT_OQ>(tt_s, _mm256_mul_ps(tmin, det_abs)),
            _mm256_cmp_ps::<_CMP_GT_OQ>(tt_s, _mm256_mul_ps(tend, det_abs)),
        );
        let accept = _mm256_andnot_ps(_mm256_or_ps(_mm256_and_ps(neg, pos), out_of_range), det_ok);
        let mut out = TriRays {
            exact: 0,
            unsure: _mm256_movemask_ps(on_edge) as u32,
            t: [0.0; PACKET],
            u: [0.0; PACKET],
            v: [0.0; PACKET],
        };
        // Accepted means det is finite and non-zero, so u, v, w are not NaN and the sign test
        // by min and max was the scalar one exactly; most triangles keep no ray at all.
        let clean = _mm256_andnot_ps(on_edge, accept);
        if _mm256_movemask_ps(clean) != 0 {
            let inv = _mm256_div_ps(_mm256_set1_ps(1.0), det);
            let t_hit = _mm256_mul_ps(tt, inv);
            let in_range =
                _mm256_and_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(t_hit, tmin), _mm256_cmp_ps::<_CMP_LE_OQ>(t_hit, tmax));
            // The scalar test's `near <= gamma(3) * far` (then the t bound decides): no NaN
            // reaches here with `in_range` set (a NaN depth makes t NaN).
            let near = _mm256_min_ps(_mm256_min_ps(da, db), dc);
            let far = _mm256_max_ps(
                _mm256_max_ps(_mm256_andnot_ps(sign, da), _mm256_andnot_ps(sign, db)),
                _mm256_andnot_ps(sign, dc),
            );
            let ahead = _mm256_cmp_ps::<_CMP_GT_OQ>(near, _mm256_mul_ps(_mm256_set1_ps(gamma(3)), far));
            let hit = _mm256_and_ps(clean, in_range);
            out.exact = _mm256_movemask_ps(_mm256_and_ps(hit, ahead)) as u32;
            out.unsure |= _mm256_movemask_ps(_mm256_andnot_ps(ahead, hit)) as u32;
            _mm256_storeu_ps(out.t.as_mut_ptr(), t_hit);
            _mm256_storeu_ps(out.u.as_mut_ptr(), _mm256_mul_ps(v, inv));
            _mm256_storeu_ps(out.v.as_mut_ptr(), _mm256_mul_ps(w, inv));
        }
        out
    }
}

/// [`PacketTest::slot_rays`]: the unfused slab test of `Scalar` for child `slot` of `node`,
/// one ray per lane, the same operations per lane (so the same answers).
///
/// # Safety
/// The CPU must have AVX2; `slot` < 8.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn slot_rays8(node: &Node8, slot: usize, p: &PacketBoxRays, oct: u32, closest: &[f32; PACKET]) -> u32 {
    // SAFETY: the caller guarantees AVX2; the loads are unaligned ones of 8 f32 from arrays of
    // exactly 8; the plane indices are below 6 (`near`, `far`) and `slot` < 8.
    unsafe {
        let org = [
            _mm256_loadu_ps(p.org[0].as_ptr()),
            _mm256_loadu_ps(p.org[1].as_ptr()),
            _mm256_loadu_ps(p.org[2].as_ptr()),
        ];
        let inv = [
            _mm256_loadu_ps(p.inv[0].as_ptr()),
            _mm256_loadu_ps(p.inv[1].as_ptr()),
            _mm256_loadu_ps(p.inv[2].as_ptr()),
        ];
        let mut t = [_mm256_setzero_ps(); 3];
        let mut u = [_mm256_setzero_ps(); 3];
        for axis in 0..3 {
            let n = _mm256_set1_ps(node.b[near(oct, axis)][slot]);
            let f = _mm256_set1_ps(node.b[far(oct, axis)][slot]);
            t[axis] = _mm256_mul_ps(_mm256_sub_ps(n, org[axis]), inv[axis]);
            u[axis] = _mm256_mul_ps(_mm256_sub_ps(f, org[axis]), inv[axis]);
        }
        let enter = _mm256_max_ps(_mm256_max_ps(t[0], t[1]), _mm256_max_ps(t[2], _mm256_loadu_ps(p.tmin.as_ptr())));
        let bound = _mm256_mul_ps(_mm256_loadu_ps(closest.as_ptr()), _mm256_set1_ps(TIE_SCALE));
        _mm256_movemask_ps(exit_hit(enter, u, bound)) as u32 & p.live
    }
}

/// Corner `q` (lane `lane` of its rows) sheared for eight rays with axes `(kx, ky, kz)`,
/// origins `o` (kx, ky, kz coordinates) and shears `sh` (sx, sy): the operations of
/// [`tri_filter4`]'s corners, one ray per lane.
///
/// # Safety
/// The CPU must have AVX2; `lane` < 4 and the axes < 3.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn sheared_corner8(
    q: &[[f32; 4]; 3],
    lane: usize,
    (kx, ky, kz): (usize, usize, usize),
    o: [__m256; 3],
    sh: [__m256; 2],
) -> [__m256; 3] {
    // SAFETY: the caller guarantees AVX2; no memory access but the bounds-checked reads.
    unsafe {
        let z = _mm256_sub_ps(_mm256_set1_ps(q[kz][lane]), o[2]);
        let x = _mm256_sub_ps(_mm256_sub_ps(_mm256_set1_ps(q[kx][lane]), o[0]), _mm256_mul_ps(sh[0], z));
        let y = _mm256_sub_ps(_mm256_sub_ps(_mm256_set1_ps(q[ky][lane]), o[1]), _mm256_mul_ps(sh[1], z));
        [x, y, z]
    }
}

/// The rest of [`tri_filter4`] from the sheared corners `a`, `b`, `c` (x, y, z each) on:
/// edge functions, signs, determinant and range check (`tend` = `range_end(tmax)`), the same
/// operations in the same order, shared by single rays ([`tri_filter4`]) and packets.
///
/// # Safety
/// The CPU must have SSE4.1.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn filter4_tail(a: [__m128; 3], b: [__m128; 3], c: [__m128; 3], sz: __m128, tmin: f32, tend: f32) -> u32 {
    // SAFETY: the caller guarantees SSE4.1; no memory access.
    unsafe {
        let ([ax, ay, az], [bx, by, bz], [cx, cy, cz]) = (a, b, c);
        let u = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
        let v = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
        let w = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
        let zero = _mm_setzero_ps();
        let on_edge = _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(u, zero), _mm_cmpeq_ps(v, zero)), _mm_cmpeq_ps(w, zero));
        // Signs mixed: some edge function below zero and some above. By min and max: a result
        // that is not NaN is one of u, v, w, so "min < 0" implies the scalar "u < 0 || v < 0 ||
        // w < 0" (likewise max), and a NaN compares false: never a rejection the scalar test
        // would not make.
        let neg = _mm_cmplt_ps(_mm_min_ps(_mm_min_ps(u, v), w), zero);
        let pos = _mm_cmpgt_ps(_mm_max_ps(_mm_max_ps(u, v), w), zero);
        let det = _mm_add_ps(_mm_add_ps(u, v), w);
        let sign = _mm_set1_ps(-0.0);
        let det_abs = _mm_andnot_ps(sign, det);
        // det != 0 and finite (NaN fails the ordered compare).
        let det_ok = _mm_and_ps(_mm_cmpneq_ps(det, zero), _mm_cmplt_ps(det_abs, _mm_set1_ps(f32::INFINITY)));
        let tt = _mm_add_ps(
            _mm_add_ps(_mm_mul_ps(u, _mm_mul_ps(sz, az)), _mm_mul_ps(v, _mm_mul_ps(sz, bz))),
            _mm_mul_ps(w, _mm_mul_ps(sz, cz)),
        );
        // (tt, det) with the sign of det folded in; det is non-zero and not NaN where it matters.
        let tt_s = _mm_xor_ps(tt, _mm_and_ps(det, sign));
        let out_of_range = _mm_or_ps(
            _mm_cmplt_ps(tt_s, _mm_mul_ps(_mm_set1_ps(tmin), det_abs)),
            _mm_cmpgt_ps(tt_s, _mm_mul_ps(_mm_set1_ps(tend), det_abs)),
        );
        let accept = _mm_andnot_ps(_mm_or_ps(_mm_and_ps(neg, pos), out_of_range), det_ok);
        let keep = _mm_or_ps(on_edge, accept);
        _mm_movemask_ps(keep) as u32
    }
}

// Other architectures: the tokens are never constructed; the impls only keep the code generic.
#[cfg(not(target_arch = "x86_64"))]
impl BoxTest for Sse {
    fn test(self, node: &Node8, r: &BoxRay, oct: u32, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        super::boxtest::Scalar.test(node, r, oct, tmax, tnear)
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl BoxTest for Avx2 {
    fn test(self, node: &Node8, r: &BoxRay, oct: u32, tmax: f32, tnear: &mut [f32; WIDTH]) -> u32 {
        super::boxtest::Scalar.test(node, r, oct, tmax, tnear)
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl PacketTest for Sse {}

#[cfg(not(target_arch = "x86_64"))]
impl PacketTest for Avx2 {}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::accel::triangle::intersect_sheared;
    use crate::cpu::with_avx2;
    use crate::sampling::Sampler;
    use glam::Vec3;

    /// The SIMD triangle filter never drops a lane the scalar watertight test hits: rays
    /// through shared vertices and along edges (edge functions exactly zero), triangles with
    /// zero, tiny, huge and overflowing coordinates (edge functions of inf and NaN), rays
    /// starting on the triangle, and ranges that end on it.
    #[test]
    fn triangle_filter_keeps_every_scalar_hit() {
        let Some(_) = Sse::new() else { return };
        let special = [0.0, -0.0, 1.0, -1.0, 0.5, 1e-30, -1e-30, 1e-40, 1e20, -1e20, 3e38, -3e38];
        let mut s = Sampler::for_sample(11, 0, 0);
        let pick = |s: &mut Sampler| -> f32 {
            if s.next_f32() < 0.3 {
                special[(s.next_f32() * special.len() as f32) as usize % special.len()]
            } else {
                (s.next_f32() - 0.5) * 4.0
            }
        };
        let (mut hits, mut checked) = (0, 0);
        for _ in 0..40_000 {
            let tris: [[Vec3; 3]; 4] =
                std::array::from_fn(|_| std::array::from_fn(|_| Vec3::new(pick(&mut s), pick(&mut s), pick(&mut s))));
            let mut blk = Tri4 { tri_lanes: 0b1111, ..Default::default() };
            for (lane, t) in tris.iter().enumerate() {
                for (corner, p) in t.iter().enumerate() {
                    for axis in 0..3 {
                        blk.c[corner][axis][lane] = p[axis];
                    }
                }
            }
            // Aimed at a corner, at an edge's midpoint, or anywhere; from anywhere or from
            // the triangle's first corner.
            let t = &tris[(s.next_f32() * 4.0) as usize % 4];
            let target = match (s.next_f32() * 3.0) as u32 {
                0 => t[1],
                1 => (t[1] + t[2]) * 0.5,
                _ => Vec3::new(pick(&mut s), pick(&mut s), pick(&mut s)),
            };
            let origin = if s.next_f32() < 0.2 { t[0] } else { Vec3::new(pick(&mut s), pick(&mut s), pick(&mut s)) };
            let ray = Ray::new(origin, target - origin);
            if !crate::accel::triangle::ShearedRay::traceable(&ray) {
                continue;
            }
            let sr = ShearedRay::of(&ray);
            let tmax = if s.next_f32() < 0.3 { 1.0 } else { f32::INFINITY };
            // SAFETY: SSE4.1 was detected above.
            let kept = unsafe { tri_filter4(&blk, &sr, 0.0, tmax) };
            for (lane, t) in tris.iter().enumerate() {
                checked += 1;
                if intersect_sheared(&sr, 0.0, tmax, t[0], t[1], t[2]).is_some() {
                    hits += 1;
                    assert!(kept >> lane & 1 == 1, "lane {lane} of {tris:?} dropped for {ray:?} (tmax {tmax})");
                }
            }
        }
        assert!(hits > 4_000 && checked > 100_000, "{hits} hits in {checked} tests: the rays miss too often");
    }

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
                    let want = set_up_each(crate::accel::bvh::boxtest::Scalar, root, group, &mut slow[..n]);
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
