//! The SIMD triangle filter and the eight-ray triangle test, with exactly the scalar
//! watertight test's operations (same operands, same order, never fused).
use super::setup::transpose_rays8;
use crate::accel::bvh::simd::{PACKET, PacketShear, TriRays};
use crate::accel::bvh::tree::Tri4;
use crate::accel::triangle::ShearedRay;
use crate::geometry::Ray;
use crate::geometry::error_bound::gamma;
use std::arch::x86_64::*;

/// The watertight test of `crate::accel::triangle::intersect_sheared` up to its range check
/// (`end` is `range_end(tmax)`), on four triangles at once with the same operations in the
/// same order (separate multiply and add, never fused), so a lane it rejects is one the
/// scalar test rejects too. Lanes with an edge function of exactly zero are kept: only the
/// scalar f64 recomputation settles them.
///
/// # Safety
/// The CPU must have SSE4.1.
#[inline(always)]
pub(super) unsafe fn tri_filter4(blk: &Tri4, sr: &ShearedRay, tmin: f32, end: f32) -> u32 {
    // SAFETY: the caller guarantees SSE4.1.
    unsafe {
        let (a, b, c) = sheared_corners4(blk, sr);
        filter4_tail(a, b, c, _mm_set1_ps(sr.sz), tmin, end)
    }
}

/// The corners of the four triangles of `blk` sheared for the ray set up as `sr` (x, y, z
/// each): (p[kx] - o[kx] - sx * z, p[ky] - o[ky] - sy * z, z) with z = p[kz] - o[kz], the
/// scalar test's operations.
///
/// # Safety
/// The CPU must have SSE4.1.
#[inline(always)]
unsafe fn sheared_corners4(blk: &Tri4, sr: &ShearedRay) -> ([__m128; 3], [__m128; 3], [__m128; 3]) {
    // SAFETY: the caller guarantees SSE4.1; loads are aligned (`Tri4` is 64-byte aligned and
    // each lane array is 16 bytes at a multiple of 16).
    unsafe {
        let (kx, ky, kz) = (sr.kx, sr.ky, sr.kz);
        let [okx, oky, okz] = sr.org_k;
        let (ox, oy, oz) = (_mm_set1_ps(okx), _mm_set1_ps(oky), _mm_set1_ps(okz));
        let (sx, sy) = (_mm_set1_ps(sr.sx), _mm_set1_ps(sr.sy));
        let corner = |c: usize| {
            let p = &blk.c[c];
            let z = _mm_sub_ps(_mm_load_ps(p[kz].as_ptr()), oz);
            let x = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(p[kx].as_ptr()), ox), _mm_mul_ps(sx, z));
            let y = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(p[ky].as_ptr()), oy), _mm_mul_ps(sy, z));
            [x, y, z]
        };
        (corner(0), corner(1), corner(2))
    }
}

/// [`tri_filter4`] for lane `k` of a packet's leaf set-up: the same values, read from it, and
/// the range end `end`.
///
/// # Safety
/// The CPU must have SSE4.1; `k` < 8.
#[inline(always)]
pub(super) unsafe fn tri_filter4_lane(blk: &Tri4, p: &PacketShear, k: usize, end: f32) -> u32 {
    // SAFETY: the caller guarantees SSE4.1 and `k` < 8.
    unsafe {
        let (a, b, c, sz) = sheared_corners4_lane(blk, p, k);
        filter4_tail(a, b, c, sz, p.tmin[k], end)
    }
}

/// The corners of the four triangles of `blk` sheared for lane `k` of `p` (x, y, z each, the
/// operations of [`tri_filter4`]'s corners with the set-up's rows), and that lane's `sz`.
///
/// # Safety
/// The CPU must have SSE4.1; `k` < 8.
#[inline(always)]
unsafe fn sheared_corners4_lane(
    blk: &Tri4,
    p: &PacketShear,
    k: usize,
) -> ([__m128; 3], [__m128; 3], [__m128; 3], __m128) {
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
        (corner(0), corner(1), corner(2), sz)
    }
}

/// The whole watertight test (`intersect_sheared`) of the four triangles of `blk` for lane `k`
/// of `p`, with the closest hit so far at `tmax` and `end` = `range_end(tmax)`: bit `l` of the
/// result is triangle `l` (not ray `l` as in [`tri_rays8`]). See [`hits4_tail`].
///
/// # Safety
/// The CPU must have SSE4.1; `k` < 8.
#[inline(always)]
pub(super) unsafe fn tri_hits4_lane(blk: &Tri4, p: &PacketShear, k: usize, tmax: f32, end: f32) -> TriRays {
    // SAFETY: the caller guarantees SSE4.1 and `k` < 8.
    unsafe {
        let (a, b, c, sz) = sheared_corners4_lane(blk, p, k);
        let shear = Shear { sx: p.shear[0][k], sy: p.shear[1][k], sz, tmin: p.tmin[k], tmax, end };
        hits4_tail(a, b, c, shear)
    }
}

/// [`tri_hits4_lane`] for a ray's own set-up `sr`, range from `tmin` to `tmax` (`end` =
/// `range_end(tmax)`).
///
/// # Safety
/// The CPU must have SSE4.1.
#[inline(always)]
pub(super) unsafe fn tri_hits4(blk: &Tri4, sr: &ShearedRay, tmin: f32, tmax: f32, end: f32) -> TriRays {
    // SAFETY: the caller guarantees SSE4.1.
    unsafe {
        let (a, b, c) = sheared_corners4(blk, sr);
        let shear = Shear { sx: sr.sx, sy: sr.sy, sz: _mm_set1_ps(sr.sz), tmin, tmax, end };
        hits4_tail(a, b, c, shear)
    }
}

/// A ray's shear and range as [`hits4_tail`] reads them (`sz` broadcast).
struct Shear {
    sx: f32,
    sy: f32,
    sz: __m128,
    tmin: f32,
    tmax: f32,
    end: f32,
}

#[inline(always)]
unsafe fn abs4(x: __m128) -> __m128 {
    // SAFETY: the caller guarantees SSE4.1.
    unsafe { _mm_andnot_ps(_mm_set1_ps(-0.0), x) }
}

/// `|a|.max(|b|).max(|c|)`, as the scalar test's `amax` (no NaN reaches it).
#[inline(always)]
unsafe fn amax4(a: __m128, b: __m128, c: __m128) -> __m128 {
    // SAFETY: the caller guarantees SSE4.1.
    unsafe { _mm_max_ps(_mm_max_ps(abs4(a), abs4(b)), abs4(c)) }
}

/// The rest of `intersect_sheared` from the sheared corners `a`, `b`, `c` on, four triangles
/// at once: the operations are the scalar test's, same operands, same order, never fused, down
/// to the bound on t's rounding error, so a hit it finishes is the scalar one bit for bit; only
/// lanes with an edge function of exactly zero (the scalar test's f64 recomputation) are left
/// `unsure`. Padding lanes are computed like the others: the caller masks them.
///
/// # Safety
/// The CPU must have SSE4.1.
#[inline(always)]
unsafe fn hits4_tail(a: [__m128; 3], b: [__m128; 3], c: [__m128; 3], r: Shear) -> TriRays {
    // SAFETY: the caller guarantees SSE4.1; the stores are unaligned ones of 4 f32 into
    // arrays of 8.
    unsafe {
        let ([ax, ay, az], [bx, by, bz], [cx, cy, cz]) = (a, b, c);
        let (sz, tmax, end) = (r.sz, r.tmax, r.end);
        let sign = _mm_set1_ps(-0.0);
        let zero = _mm_setzero_ps();
        let tmin = _mm_set1_ps(r.tmin);
        let u = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
        let v = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
        let w = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
        let on_edge = _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(u, zero), _mm_cmpeq_ps(v, zero)), _mm_cmpeq_ps(w, zero));
        // As in `filter4_tail`; here a lane is accepted only with a finite, non-zero det (the
        // scalar test's check), so u, v, w are finite and the sign test by min and max is
        // exactly the scalar one.
        let neg = _mm_cmplt_ps(_mm_min_ps(_mm_min_ps(u, v), w), zero);
        let pos = _mm_cmpgt_ps(_mm_max_ps(_mm_max_ps(u, v), w), zero);
        let det = _mm_add_ps(_mm_add_ps(u, v), w);
        let det_abs = _mm_andnot_ps(sign, det);
        let det_ok = _mm_and_ps(_mm_cmpneq_ps(det, zero), _mm_cmplt_ps(det_abs, _mm_set1_ps(f32::INFINITY)));
        // The corners' depths `sz * z`, as the scalar test's `az`, `bz`, `cz`.
        let (da, db, dc) = (_mm_mul_ps(sz, az), _mm_mul_ps(sz, bz), _mm_mul_ps(sz, cz));
        let tt = _mm_add_ps(_mm_add_ps(_mm_mul_ps(u, da), _mm_mul_ps(v, db)), _mm_mul_ps(w, dc));
        let tt_s = _mm_xor_ps(tt, _mm_and_ps(det, sign));
        let out_of_range = _mm_or_ps(
            _mm_cmplt_ps(tt_s, _mm_mul_ps(tmin, det_abs)),
            _mm_cmpgt_ps(tt_s, _mm_mul_ps(_mm_set1_ps(end), det_abs)),
        );
        let accept = _mm_andnot_ps(_mm_or_ps(_mm_and_ps(neg, pos), out_of_range), det_ok);
        let mut out = TriRays::undecided(_mm_movemask_ps(on_edge) as u32);
        let clean = _mm_andnot_ps(on_edge, accept);
        if _mm_movemask_ps(clean) == 0 {
            return out;
        }
        let inv = _mm_div_ps(_mm_set1_ps(1.0), det);
        let t_hit = _mm_mul_ps(tt, inv);
        let in_range = _mm_and_ps(_mm_cmpge_ps(t_hit, tmin), _mm_cmple_ps(t_hit, _mm_set1_ps(tmax)));
        let hit = _mm_and_ps(clean, in_range);
        if _mm_movemask_ps(hit) == 0 {
            return out;
        }
        // `near <= gamma(3) * far && t <= t_error_bound(..)` rejects, as in the scalar test.
        let near = _mm_min_ps(_mm_min_ps(da, db), dc);
        let far = amax4(da, db, dc);
        let reaches_back = _mm_cmple_ps(near, _mm_mul_ps(_mm_set1_ps(gamma(3)), far));
        let (max_x, max_y, max_z, max_e) = (amax4(ax, bx, cx), amax4(ay, by, cy), far, amax4(u, v, w));
        let max_z_world = _mm_div_ps(max_z, abs4(sz));
        let delta_z = _mm_mul_ps(_mm_set1_ps(gamma(3)), max_z);
        let (sx_abs, sy_abs) = (_mm_set1_ps(r.sx.abs()), _mm_set1_ps(r.sy.abs()));
        let delta_x = _mm_mul_ps(_mm_set1_ps(gamma(5)), _mm_add_ps(max_x, _mm_mul_ps(sx_abs, max_z_world)));
        let delta_y = _mm_mul_ps(_mm_set1_ps(gamma(5)), _mm_add_ps(max_y, _mm_mul_ps(sy_abs, max_z_world)));
        let delta_e = _mm_mul_ps(
            _mm_set1_ps(2.0),
            _mm_add_ps(
                _mm_add_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(gamma(2)), max_x), max_y), _mm_mul_ps(delta_y, max_x)),
                _mm_mul_ps(delta_x, max_y),
            ),
        );
        let bound = _mm_mul_ps(
            _mm_mul_ps(
                _mm_set1_ps(3.0),
                _mm_add_ps(
                    _mm_add_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(gamma(3)), max_e), max_z), _mm_mul_ps(delta_e, max_z)),
                    _mm_mul_ps(delta_z, max_e),
                ),
            ),
            abs4(inv),
        );
        let behind = _mm_and_ps(reaches_back, _mm_cmple_ps(t_hit, bound));
        out.exact = _mm_movemask_ps(_mm_andnot_ps(behind, hit)) as u32;
        _mm_storeu_ps(out.t.as_mut_ptr(), t_hit);
        _mm_storeu_ps(out.u.as_mut_ptr(), _mm_mul_ps(v, inv));
        _mm_storeu_ps(out.v.as_mut_ptr(), _mm_mul_ps(w, inv));
        out
    }
}

/// [`PacketShear::set`] (that is [`ShearedRay::of`]) of eight rays at once, one ray per
/// lane: the same comparisons choose the axes (NaN compares false in both), the same
/// divisions give `sx`, `sy`, `sz`, so the same values.
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
pub(super) unsafe fn shear8(rays: &[Ray; 8]) -> PacketShear {
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
        // Rows by table, not by branches: a group of random directions mispredicted them.
        for (k, rows) in out.rows.iter_mut().enumerate() {
            let kz = 2 - 2 * (b0 >> k & 1) - (b1 >> k & 1);
            *rows = ROWS[(2 * kz + (bn >> k & 1)) as usize % 6];
        }
        out
    }
}

/// The rows `[16 kx, 16 ky, 16 kz, 0]` for dominant axis `kz` (row `2 kz`) and with `kx`, `ky`
/// swapped for a negative direction along it (row `2 kz + 1`), as `ShearedRay::of` picks them.
const ROWS: [[u8; 4]; 6] =
    [[16, 32, 0, 0], [32, 16, 0, 0], [32, 0, 16, 0], [0, 32, 16, 0], [0, 16, 32, 0], [16, 0, 32, 0]];

/// [`PacketTest::tri_rays`]: [`tri_filter4`]'s operations for triangle `lane` of `blk` and
/// the eight rays of `p`, one ray per lane (the corner broadcast, the ray's values in its
/// lane, all rays with the axes of lane 0), with `tend` = `range_end(closest)` per lane; then,
/// for the rays it keeps without an exact-zero edge function, the rest of
/// `intersect_sheared`'s operations (the division, the exact range check, the test of
/// whether the triangle reaches back to the origin's depth).
///
/// # Safety
/// The CPU must have AVX2; `lane` < 4.
#[inline(always)]
pub(super) unsafe fn tri_rays8(blk: &Tri4, lane: usize, p: &PacketShear, closest: &[f32; PACKET]) -> TriRays {
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
        let mut out = TriRays::undecided(_mm256_movemask_ps(on_edge) as u32);
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

/// Corner `q` (lane `lane` of its rows) sheared for eight rays with axes `(kx, ky, kz)`,
/// origins `o` (kx, ky, kz coordinates) and shears `sh` (sx, sy): the operations of
/// [`tri_filter4`]'s corners, one ray per lane.
///
/// # Safety
/// The CPU must have AVX2; `lane` < 4 and the axes < 3.
#[inline(always)]
pub(super) unsafe fn sheared_corner8(
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
#[inline(always)]
pub(super) unsafe fn filter4_tail(
    a: [__m128; 3],
    b: [__m128; 3],
    c: [__m128; 3],
    sz: __m128,
    tmin: f32,
    tend: f32,
) -> u32 {
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
        // Not rejected for a zero or non-finite det (the scalar test rejects those lanes, and
        // they are rare: testing it here cost every leaf four operations).
        let reject = _mm_or_ps(_mm_and_ps(neg, pos), out_of_range);
        _mm_movemask_ps(_mm_andnot_ps(on_edge, reject)) as u32 ^ 0xf
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::triangle::{intersect_sheared, range_end};
    use crate::cpu::Sse;
    use crate::sampling::Sampler;
    use glam::Vec3;

    /// A coordinate: with probability `share` one of the special values (zeros of both signs,
    /// tiny, subnormal, huge and near-overflowing), else uniform in [-2, 2).
    fn coordinate(s: &mut Sampler, share: f32) -> f32 {
        const SPECIAL: [f32; 12] = [0.0, -0.0, 1.0, -1.0, 0.5, 1e-30, -1e-30, 1e-40, 1e20, -1e20, 3e38, -3e38];
        if s.next_f32() < share {
            SPECIAL[(s.next_f32() * SPECIAL.len() as f32) as usize % SPECIAL.len()]
        } else {
            (s.next_f32() - 0.5) * 4.0
        }
    }

    fn point(s: &mut Sampler, share: f32) -> Vec3 {
        Vec3::new(coordinate(s, share), coordinate(s, share), coordinate(s, share))
    }

    /// Four triangles of such coordinates, and their block.
    fn random_block(s: &mut Sampler, share: f32) -> ([[Vec3; 3]; 4], Tri4) {
        let tris: [[Vec3; 3]; 4] = std::array::from_fn(|_| std::array::from_fn(|_| point(s, share)));
        let mut blk = Tri4 { tri_lanes: 0b1111, ..Default::default() };
        for (lane, t) in tris.iter().enumerate() {
            for (corner, p) in t.iter().enumerate() {
                for axis in 0..3 {
                    blk.c[corner][axis][lane] = p[axis];
                }
            }
        }
        (tris, blk)
    }

    /// A point a ray aims at on or near triangle `t`: a corner, an edge's midpoint, or anywhere.
    fn target(s: &mut Sampler, share: f32, t: &[Vec3; 3]) -> Vec3 {
        match (s.next_f32() * 3.0) as u32 {
            0 => t[1],
            1 => (t[1] + t[2]) * 0.5,
            _ => point(s, share),
        }
    }

    /// The SIMD triangle filter never drops a lane the scalar watertight test hits: rays
    /// through shared vertices and along edges (edge functions exactly zero), triangles with
    /// zero, tiny, huge and overflowing coordinates (edge functions of inf and NaN), rays
    /// starting on the triangle, and ranges that end on it.
    #[test]
    fn triangle_filter_keeps_every_scalar_hit() {
        let Some(_) = Sse::new() else { return };
        let mut s = Sampler::for_sample(11, 0, 0);
        let (mut hits, mut checked) = (0, 0);
        for _ in 0..40_000 {
            let (tris, blk) = random_block(&mut s, 0.3);
            // Aimed at a corner, at an edge's midpoint, or anywhere; from anywhere or from
            // the triangle's first corner.
            let t = &tris[(s.next_f32() * 4.0) as usize % 4];
            let target = target(&mut s, 0.3, t);
            let origin = if s.next_f32() < 0.2 { t[0] } else { point(&mut s, 0.3) };
            let ray = Ray::new(origin, target - origin);
            if !crate::accel::triangle::ShearedRay::traceable(&ray) {
                continue;
            }
            let sr = ShearedRay::of(&ray);
            let tmax = if s.next_f32() < 0.3 { 1.0 } else { f32::INFINITY };
            // SAFETY: SSE4.1 was detected above.
            let kept = unsafe { tri_filter4(&blk, &sr, 0.0, range_end(tmax)) };
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

    /// The whole SIMD test gives the scalar watertight test's hit bit for bit wherever it
    /// settles a lane, and leaves undecided only lanes with an edge function of exactly zero:
    /// random and special coordinates, rays through corners and edge midpoints, rays that
    /// start on a triangle (the bound on t's rounding error decides those), short and open
    /// ranges; from a ray's own set-up and from a packet's lane alike.
    #[test]
    fn whole_triangle_test_is_the_scalar_test() {
        let Some(_) = Sse::new() else { return };
        let mut s = Sampler::for_sample(12, 0, 0);
        let (mut exact, mut unsure, mut reaching, mut leaving) = (0, 0, 0, 0);
        for _ in 0..40_000 {
            let (tris, blk) = random_block(&mut s, 0.2);
            let own = (s.next_f32() * 4.0) as usize % 4;
            let t = &tris[own];
            let target = target(&mut s, 0.2, t);
            let from_inside = s.next_f32() < 0.2;
            // From anywhere, from a corner, or from a point inside the triangle (a ray leaving
            // the surface it starts on).
            let origin = match (from_inside, s.next_f32() < 0.25) {
                (true, _) => (t[0] + t[1] + t[2]) / 3.0,
                (false, true) => t[0],
                _ => point(&mut s, 0.2),
            };
            let ray = Ray::new(origin, target - origin);
            if !crate::accel::triangle::ShearedRay::traceable(&ray) {
                continue;
            }
            let sr = ShearedRay::of(&ray);
            let tmax = [1.0, 0.5, f32::INFINITY][(s.next_f32() * 3.0) as usize % 3];
            let mut p = PacketShear::EMPTY;
            p.set(3, &ray);
            // SAFETY: SSE4.1 was detected above; lane 3 < 8.
            let (h, hl) = unsafe {
                (tri_hits4(&blk, &sr, 0.0, tmax, range_end(tmax)), tri_hits4_lane(&blk, &p, 3, tmax, range_end(tmax)))
            };
            for (lane, t) in tris.iter().enumerate() {
                let want = intersect_sheared(&sr, 0.0, tmax, t[0], t[1], t[2]);
                let bits = |x: (f32, f32, f32)| [x.0.to_bits(), x.1.to_bits(), x.2.to_bits()];
                for h in [&h, &hl] {
                    if h.exact >> lane & 1 != 0 {
                        let got = (h.t[lane], h.u[lane], h.v[lane]);
                        assert_eq!(want.map(bits), Some(bits(got)), "lane {lane} of {tris:?}, {ray:?} (tmax {tmax})");
                    } else if h.unsure >> lane & 1 == 0 {
                        assert!(want.is_none(), "lane {lane} of {tris:?} missed for {ray:?} (tmax {tmax}): {want:?}");
                    }
                }
                assert_eq!((h.exact >> lane & 1, h.unsure >> lane & 1), (hl.exact >> lane & 1, hl.unsure >> lane & 1));
                exact += h.exact >> lane & 1;
                unsure += h.unsure >> lane & 1;
                // Settled hits on triangles that reach back to the origin's depth (the bound on
                // t's rounding error decided them), and rays leaving their own triangle.
                let depth = |p: Vec3| sr.sz * (p - origin).to_array()[sr.kz];
                let d = t.map(depth);
                let near = d[0].min(d[1]).min(d[2]);
                let far = d[0].abs().max(d[1].abs()).max(d[2].abs());
                reaching += (h.exact >> lane & 1 != 0 && near <= gamma(3) * far) as u32;
                leaving += (from_inside && lane == own && want.is_none() && h.unsure >> lane & 1 == 0) as u32;
            }
        }
        assert!(
            exact > 3_000 && unsure > 100 && reaching > 100 && leaving > 1_000,
            "{exact} settled ({reaching} reaching back), {unsure} undecided, {leaving} leaving their triangle"
        );
    }
}
