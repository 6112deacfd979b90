//! The x86-64 kernels: the SSE4.1 and AVX2 implementations of the kernel traits. All the
//! `unsafe` of the traversal lives below this module: each kernel can only be reached through a
//! [`crate::cpu`] token whose constructor checked the CPU at run time.
mod boxes;
mod setup;
mod triangles;

use super::{
    BoxRay, BoxTest, EXIT_SCALE, Frustum, PACKET, PREFETCH_BYTES, PacketBoxRays, PacketShear, PacketTest, RootBox,
    TIE_SCALE, TriRays, far, near, set_up_each,
};
use crate::accel::bvh::tree::{Node8, Tri4, WIDTH};
use crate::accel::triangle::ShearedRay;
use crate::cpu::{Avx2, Sse};
use crate::geometry::Ray;
use boxes::{frustum8, push_ordered, slab8, slab8_lane, slot_rays8};
use setup::{box_ray8, box_rays8, set_up8};
use std::arch::x86_64::*;
use triangles::{shear8, tri_filter4, tri_filter4_lane, tri_hits4, tri_hits4_lane, tri_rays8};

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
    fn tri_filter(self, blk: &Tri4, sr: &ShearedRay, tmin: f32, end: f32, lanes: u32) -> u32 {
        // SAFETY: `Sse` exists only if SSE4.1 was detected.
        unsafe { tri_filter4(blk, sr, tmin, end) & lanes }
    }

    #[inline(always)]
    fn tri_hits(self, blk: &Tri4, sr: &ShearedRay, tmin: f32, tmax: f32, end: f32) -> Option<TriRays> {
        // SAFETY: `Sse` exists only if SSE4.1 was detected.
        Some(unsafe { tri_hits4(blk, sr, tmin, tmax, end) })
    }
}

impl PacketTest for Sse {
    #[inline(always)]
    fn tri_filter_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, end: f32, lanes: u32) -> u32 {
        let _ = ray;
        // SAFETY: `Sse` exists only if SSE4.1 was detected.
        unsafe { tri_filter4_lane(blk, p, k % PACKET, end) & lanes }
    }

    #[inline(always)]
    fn tri_hits_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, tmax: f32, end: f32) -> Option<TriRays> {
        let _ = ray;
        // SAFETY: `Sse` exists only if SSE4.1 was detected; `k % PACKET` < 8.
        Some(unsafe { tri_hits4_lane(blk, p, k % PACKET, tmax, end) })
    }
}

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
    fn visit(
        self,
        node: &Node8,
        r: &BoxRay,
        fma: bool,
        tmax: f32,
        nodes: &mut [u32; WIDTH],
        dists: &mut [f32; WIDTH],
    ) -> (u32, u32) {
        let oct = r.octant;
        // SAFETY: `Avx2` exists only if AVX2 and FMA were detected; the loads are unaligned
        // ones of 8 u32 inside `node`, the stores go to arrays of exactly 8 entries;
        // `COMPRESS` is indexed by an 8-bit mask.
        unsafe {
            debug_assert_eq!(fma, r.fma);
            let (enter, hit) = slab8(node, r, tmax, fma);
            let mask = _mm256_movemask_ps(hit) as u32;
            let n = mask.count_ones();
            if n == 1 {
                // `& 7`: the slot of a one-bit mask of eight lanes, without a bounds check.
                return (1, node.child[mask.trailing_zeros() as usize & 7]);
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
    fn tri_filter(self, blk: &Tri4, sr: &ShearedRay, tmin: f32, end: f32, lanes: u32) -> u32 {
        // SAFETY: `Avx2` exists only if AVX2 (hence SSE4.1) was detected.
        unsafe { tri_filter4(blk, sr, tmin, end) & lanes }
    }

    #[inline(always)]
    fn tri_hits(self, blk: &Tri4, sr: &ShearedRay, tmin: f32, tmax: f32, end: f32) -> Option<TriRays> {
        // SAFETY: `Avx2` exists only if AVX2 (hence SSE4.1) was detected.
        Some(unsafe { tri_hits4(blk, sr, tmin, tmax, end) })
    }
}

impl PacketTest for Avx2 {
    #[inline(always)]
    fn tri_filter_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, end: f32, lanes: u32) -> u32 {
        let _ = ray;
        // SAFETY: `Avx2` exists only if AVX2 (hence SSE4.1) was detected.
        unsafe { tri_filter4_lane(blk, p, k % PACKET, end) & lanes }
    }

    #[inline(always)]
    fn tri_hits_lane(self, blk: &Tri4, p: &PacketShear, k: usize, ray: &Ray, tmax: f32, end: f32) -> Option<TriRays> {
        let _ = ray;
        // SAFETY: `Avx2` exists only if AVX2 (hence SSE4.1) was detected; `k % PACKET` < 8.
        Some(unsafe { tri_hits4_lane(blk, p, k % PACKET, tmax, end) })
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

/// Prefetches the [`PREFETCH_BYTES`] from `p` into all cache levels.
#[inline(always)]
fn prefetch_lines(p: *const u8) {
    let mut off = 0;
    while off < PREFETCH_BYTES {
        crate::cpu::prefetch_at(p.wrapping_add(off));
        off += 64;
    }
}
