//! The AVX2 box tests: a node's eight children against one ray, a packet's frustum, or one
//! child against eight rays; and the ordered push of the children hit.
use crate::accel::bvh::simd::{BoxRay, EXIT_SCALE, Frustum, PACKET, PacketBoxRays, TIE_SCALE, far, near};
use crate::accel::bvh::tree::{Node8, WIDTH};
use std::arch::x86_64::*;

/// [`slab8`]'s hit lanes for lane `k` of a packet (the same operations on the same values).
///
/// # Safety
/// The CPU must have AVX2 and FMA; `k` < 8.
#[inline(always)]
pub(super) unsafe fn slab8_lane(node: &Node8, p: &PacketBoxRays, k: usize) -> __m256 {
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
#[inline(always)]
pub(super) unsafe fn slab8(node: &Node8, r: &BoxRay, tmax: f32, fma: bool) -> (__m256, __m256) {
    // SAFETY: the caller guarantees AVX2 and FMA; each load reads 8 f32 of `node.b` at a
    // byte offset `32 * plane` with plane < 6 (`BoxRay::planes` is always `PLANES[octant]`),
    // unaligned loads.
    unsafe {
        let base = node.b.as_ptr().cast::<u8>();
        let plane = |k: usize| _mm256_loadu_ps(base.add(r.planes[k] as usize).cast::<f32>());
        let (t0, t1, t2, u0, u1, u2);
        if fma {
            // One fused op per plane (see `simd::ray::fma_terms` for why this stays safe).
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
#[inline(always)]
pub(super) unsafe fn exit_hit(enter: __m256, u: [__m256; 3], tie: __m256) -> __m256 {
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
#[inline(always)]
pub(super) unsafe fn push_ordered(
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
#[inline(always)]
pub(super) unsafe fn frustum8(node: &Node8, f: &Frustum, tmax: f32) -> (__m256, __m256) {
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

/// [`PacketTest::slot_rays`]: the unfused slab test of `Scalar` for child `slot` of `node`,
/// one ray per lane, the same operations per lane (so the same answers).
///
/// # Safety
/// The CPU must have AVX2; `slot` < 8.
#[inline(always)]
pub(super) unsafe fn slot_rays8(
    node: &Node8,
    slot: usize,
    p: &PacketBoxRays,
    oct: u32,
    closest: &[f32; PACKET],
) -> u32 {
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
