//! Closest hit for packets of coherent rays: up to eight rays of a batch with one direction
//! octant (camera rays of neighbouring pixels, or one pixel's jittered samples) traverse the
//! tree together. One stack, one node fetch and one leaf-or-inner decision per node serve
//! the whole packet, where single rays repeat the same loads and the same hard-to-predict
//! loop exits once each.
//!
//! Each ray keeps its own closest hit: it enters a child only when its own box test of that
//! child passes against its own closest `t` so far (the same test, same operands and same
//! rounding as its single-ray traversal), a popped entry keeps only the rays whose own entry
//! distance is still within their own closest `t`, and leaves are tested per ray with the
//! single-ray leaf test. The children are visited front to back in the node's precomputed
//! order for the shared octant. The visiting order of leaves may differ from a single ray's,
//! but the result does not depend on it: the closest hit is the smallest `(t, id)` (ties go
//! to the lower primitive id in `leaf_closest`), and no box holding a hit within
//! `TIE_SCALE` of the closest `t` is ever culled. So every ray gets exactly its single-ray hit.
use super::Bvh;
use super::boxtest::{BoxRay, BoxTest, Scalar, TIE_SCALE};
use super::packet::transpose8;
use super::simd::{Avx2, Sse};
use super::traverse::{Best, leaf_closest, prefetch_child};
use super::wide::{LEAF_BIT, Node8, WIDTH};
use crate::accel::TraceCounters;
use crate::accel::triangle::ShearedRay;
use crate::ray::{Hit, Ray};

/// Rays per packet at most (one byte of a ray mask per child).
pub const PACKET: usize = 8;

/// Shortest run of consecutive same-octant rays traced as a packet; shorter runs (what
/// incoherent rays, e.g. diffuse bounces, nearly always give) take the single-ray path.
pub const MIN_PACKET: usize = 4;

/// One `f32` per packet lane (ray), aligned for whole-vector loads and stores.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
pub struct Lanes(pub [f32; PACKET]);

/// A packet's box-test values: each ray's [`BoxRay`], and the same values lane by lane
/// (transposed once per packet) for the SIMD kernel that tests one child for all rays.
pub struct PacketRays {
    pub br: [BoxRay; PACKET],
    pub org: [Lanes; 3],
    pub inv: [Lanes; 3],
    pub oi_near: [Lanes; 3],
    pub oi_far: [Lanes; 3],
    pub tmin: Lanes,
    /// The octant every ray of the packet has.
    pub octant: u32,
    /// Whether every live ray uses the fused slab form (else the kernel tests ray by ray).
    pub fma: bool,
}

impl PacketRays {
    #[inline(always)]
    fn new(br: &[BoxRay]) -> PacketRays {
        let mut p = PacketRays {
            br: [BoxRay::DEAD; PACKET],
            org: [Lanes::default(); 3],
            inv: [Lanes::default(); 3],
            oi_near: [Lanes::default(); 3],
            oi_far: [Lanes::default(); 3],
            tmin: Lanes::default(),
            octant: br[0].octant,
            fma: true,
        };
        for (k, b) in br.iter().enumerate().take(PACKET) {
            p.br[k] = *b;
            for a in 0..3 {
                p.org[a].0[k] = b.org[a];
                p.inv[a].0[k] = b.inv[a];
                p.oi_near[a].0[k] = b.oi_near[a];
                p.oi_far[a].0[k] = b.oi_far[a];
            }
            p.tmin.0[k] = b.tmin;
            p.fma &= b.fma;
        }
        p
    }
}

/// The packet kernels of an instruction set.
pub trait PacketTest: BoxTest {
    /// Tests the children of `node` for the rays in `active`, each against its own `tmax`
    /// (its closest hit so far): byte `i` of the result holds the rays entering child `i`
    /// (each bit exactly [`BoxTest::test`] of that ray alone), `dists[i]` their entry
    /// distances (lanes of rays not entering are unspecified).
    #[inline(always)]
    fn test_packet(self, node: &Node8, p: &PacketRays, active: u32, tmax: &Lanes, dists: &mut [Lanes; WIDTH]) -> u64 {
        test_rays(self, node, p, active, tmax, dists)
    }

    /// The rays of `mask` whose entry distance `d` is within their closest hit (`d <= tmax *
    /// TIE_SCALE`, the single-ray traversal's pop test).
    #[inline(always)]
    fn cull(self, d: &Lanes, tmax: &Lanes, mask: u32) -> u32 {
        let mut keep = 0;
        for k in 0..PACKET {
            keep |= ((d.0[k] <= tmax.0[k] * TIE_SCALE) as u32) << k;
        }
        keep & mask
    }
}

/// [`PacketTest::test_packet`] ray by ray with the instruction set's own node test.
#[inline(always)]
fn test_rays<B: BoxTest>(
    isa: B,
    node: &Node8,
    p: &PacketRays,
    active: u32,
    tmax: &Lanes,
    dists: &mut [Lanes; WIDTH],
) -> u64 {
    let mut rows = 0u64;
    let mut m = active;
    let mut tnear = [0f32; WIDTH];
    while m != 0 {
        let k = m.trailing_zeros() as usize;
        m &= m - 1;
        let hm = isa.test(node, &p.br[k], p.octant, tmax.0[k], &mut tnear);
        rows |= (hm as u64) << (8 * k);
        for (d, &t) in dists.iter_mut().zip(&tnear) {
            d.0[k] = t;
        }
    }
    transpose8(rows)
}

impl PacketTest for Scalar {}
impl PacketTest for Sse {}

#[cfg(target_arch = "x86_64")]
impl PacketTest for Avx2 {
    #[inline(always)]
    fn test_packet(self, node: &Node8, p: &PacketRays, active: u32, tmax: &Lanes, dists: &mut [Lanes; WIDTH]) -> u64 {
        if !p.fma {
            return test_rays(self, node, p, active, tmax, dists);
        }
        // SAFETY: `Avx2` exists only if AVX2 and FMA were detected; every load and store is
        // of a 32-byte aligned `Lanes` or of 8 u32 inside `node`.
        unsafe { avx2::test_packet(node, p, active, tmax, dists) }
    }

    #[inline(always)]
    fn cull(self, d: &Lanes, tmax: &Lanes, mask: u32) -> u32 {
        // SAFETY: `Avx2` exists only if AVX2 was detected; aligned loads of two `Lanes`.
        unsafe { avx2::cull(d, tmax, mask) }
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl PacketTest for Avx2 {}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{Lanes, PacketRays, TIE_SCALE};
    use crate::accel::bvh::boxtest::EXIT_SCALE;
    use crate::accel::bvh::wide::{EMPTY, Node8, WIDTH};
    use std::arch::x86_64::*;

    /// One child at a time for all eight rays (a lane per ray), in the fused form of the
    /// single-ray kernel (`simd::slab8`): per lane the same `fmsub(plane, inv, oi)`, the same
    /// max/min trees and the same two compares, so the same bits and entry distances.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[inline(always)]
    pub unsafe fn test_packet(
        node: &Node8,
        p: &PacketRays,
        active: u32,
        tmax: &Lanes,
        dists: &mut [Lanes; WIDTH],
    ) -> u64 {
        // SAFETY: the caller guarantees AVX2 and FMA; `Lanes` is 32-byte aligned, plane
        // indices are below 6 (`BoxRay::planes` is `PLANES[octant]`), slot indices below 8.
        unsafe {
            let ld = |l: &Lanes| _mm256_load_ps(l.0.as_ptr());
            let planes = &p.br[0].planes;
            let base = node.b.as_ptr().cast::<u8>();
            let at = |k: usize, slot: usize| *base.add(planes[k] as usize + 4 * slot).cast::<f32>();
            let (ix, iy, iz) = (ld(&p.inv[0]), ld(&p.inv[1]), ld(&p.inv[2]));
            let (nx, ny, nz) = (ld(&p.oi_near[0]), ld(&p.oi_near[1]), ld(&p.oi_near[2]));
            let (fx, fy, fz) = (ld(&p.oi_far[0]), ld(&p.oi_far[1]), ld(&p.oi_far[2]));
            let tmin = ld(&p.tmin);
            let tmax = _mm256_mul_ps(ld(tmax), _mm256_set1_ps(TIE_SCALE));
            let scale = _mm256_set1_ps(EXIT_SCALE);
            let children = _mm256_loadu_si256(node.child.as_ptr().cast());
            let empty =
                _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(children, _mm256_set1_epi32(EMPTY as i32))));
            let mut slots = !empty as u32 & 0xff;
            let mut cols = 0u64;
            while slots != 0 {
                let i = slots.trailing_zeros() as usize;
                slots &= slots - 1;
                let d = |k: usize, inv: __m256, oi: __m256| _mm256_fmsub_ps(_mm256_set1_ps(at(k, i)), inv, oi);
                let (t0, t1, t2) = (d(0, ix, nx), d(1, iy, ny), d(2, iz, nz));
                let (u0, u1, u2) = (d(3, ix, fx), d(4, iy, fy), d(5, iz, fz));
                let enter = _mm256_max_ps(_mm256_max_ps(t0, t1), _mm256_max_ps(t2, tmin));
                let exit = _mm256_mul_ps(_mm256_min_ps(_mm256_min_ps(u0, u1), u2), scale);
                let hit =
                    _mm256_and_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit), _mm256_cmp_ps::<_CMP_LE_OQ>(enter, tmax));
                _mm256_store_ps(dists[i].0.as_mut_ptr(), enter);
                cols |= ((_mm256_movemask_ps(hit) as u32 & active) as u64) << (8 * i);
            }
            cols
        }
    }

    /// [`super::PacketTest::cull`] for eight lanes at once.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[inline(always)]
    pub unsafe fn cull(d: &Lanes, tmax: &Lanes, mask: u32) -> u32 {
        // SAFETY: the caller guarantees AVX2; aligned loads of two `Lanes`.
        unsafe {
            let t = _mm256_mul_ps(_mm256_load_ps(tmax.0.as_ptr()), _mm256_set1_ps(TIE_SCALE));
            let keep = _mm256_cmp_ps::<_CMP_LE_OQ>(_mm256_load_ps(d.0.as_ptr()), t);
            _mm256_movemask_ps(keep) as u32 & mask
        }
    }
}

/// The packet stack: node references, per entry the rays that entered it and their entry
/// distances.
pub struct Stack {
    nodes: Vec<u32>,
    masks: Vec<u32>,
    dists: Vec<Lanes>,
}

impl Stack {
    pub fn new(len: usize) -> Stack {
        Stack { nodes: vec![0; len], masks: vec![0; len], dists: vec![Lanes::default(); len] }
    }
}

/// Length of the run of rays starting at `br[0]` that can form a packet: live, the same
/// octant, at most [`PACKET`].
#[inline(always)]
pub fn run_len(br: &[BoxRay]) -> usize {
    let first = &br[0];
    if !first.live {
        return 1;
    }
    let mut n = 1;
    while n < PACKET && n < br.len() && br[n].live && br[n].octant == first.octant {
        n += 1;
    }
    n
}

/// Closest hits of `rays` (1..=[`PACKET`] live rays of one octant, box-test values `br`)
/// traced as one packet; `hits[k]` is what [`super::traverse::closest_hit_with`] gives ray `k`.
#[inline(always)]
pub fn closest_packet<B: PacketTest>(
    bvh: &Bvh,
    isa: B,
    rays: &[Ray],
    br: &[BoxRay],
    hits: &mut [Option<Hit>],
    c: &mut TraceCounters,
    stack: &mut Stack,
) {
    let n = rays.len().min(PACKET);
    c.rays += n as u64;
    let p = PacketRays::new(&br[..n]);
    let live = (0..n).fold(0u32, |m, k| m | (br[k].live as u32) << k);
    let mut best: [Best; PACKET] = std::array::from_fn(|k| Best::new(rays.get(k).map_or(0.0, |r| r.tmax)));
    let mut tmax = Lanes([0.0; PACKET]);
    for (t, r) in tmax.0.iter_mut().zip(&rays[..n]) {
        *t = r.tmax;
    }
    let mut sr = [None::<ShearedRay>; PACKET];
    let mut dists = [Lanes::default(); WIDTH];
    let (mut sp, mut cur, mut cur_rays) = (0usize, 0u32, live);
    let mut visited = 0u64;
    let oct = p.octant;
    'trace: loop {
        if cur & LEAF_BIT == 0 {
            visited += cur_rays.count_ones() as u64;
            let node = &bvh.nodes[cur as usize];
            let cols = isa.test_packet(node, &p, cur_rays, &tmax, &mut dists);
            if cols != 0 {
                // Children entered by any ray, far to near in the octant's order: the
                // nearest ends on top.
                let top = sp;
                for k in node.perm {
                    let slot = (k >> (3 * oct) & 7) as usize;
                    let m = (cols >> (8 * slot)) as u32 & 0xff;
                    if m != 0 {
                        stack.nodes[sp] = node.child[slot];
                        stack.masks[sp] = m;
                        stack.dists[sp] = dists[slot];
                        sp += 1;
                    }
                }
                if sp - top > 1 {
                    for &r in &stack.nodes[top..sp] {
                        prefetch_child(bvh, isa, r);
                    }
                }
                // The nearest is taken at once (every ray in its mask just entered it).
                sp -= 1;
                cur = stack.nodes[sp];
                cur_rays = stack.masks[sp];
                continue 'trace;
            }
        } else {
            let mut m = cur_rays;
            while m != 0 {
                let k = m.trailing_zeros() as usize;
                m &= m - 1;
                let s = sr[k].get_or_insert_with(|| ShearedRay::of(&rays[k]));
                leaf_closest(bvh, isa, cur, s, &rays[k], &mut best[k], c);
                tmax.0[k] = best[k].t;
            }
        }
        // Pop the nearest pending entry that some ray can still use.
        loop {
            if sp == 0 {
                break 'trace;
            }
            sp -= 1;
            let m = isa.cull(&stack.dists[sp], &tmax, stack.masks[sp]);
            if m != 0 {
                cur = stack.nodes[sp];
                cur_rays = m;
                break;
            }
        }
    }
    c.nodes += visited;
    for (k, h) in hits.iter_mut().enumerate().take(n) {
        *h = best[k].hit();
    }
}

/// Traces the prepared rays of one batch group: `prep[j]` are the box-test values of ray
/// `rs[slot[j]]` (the rays that passed the root-box test, in batch order). Runs of at least
/// [`MIN_PACKET`] live same-octant rays go as packets, every other ray alone.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn trace_group<B: PacketTest>(
    bvh: &Bvh,
    isa: B,
    rs: &[Ray],
    hs: &mut [Option<Hit>],
    prep: &[BoxRay],
    slot: &[u8],
    c: &mut TraceCounters,
    stack: &mut super::traverse::Stack,
    pstack: &mut Stack,
) {
    let mut j = 0;
    while j < prep.len() {
        let len = run_len(&prep[j..]);
        if len >= MIN_PACKET {
            let mut pr = [rs[slot[j] as usize]; PACKET];
            for k in 1..len {
                pr[k] = rs[slot[j + k] as usize];
            }
            let mut ph = [None; PACKET];
            closest_packet(bvh, isa, &pr[..len], &prep[j..j + len], &mut ph[..len], c, pstack);
            for k in 0..len {
                hs[slot[j + k] as usize] = ph[k];
            }
        } else {
            for k in j..j + len {
                let i = slot[k] as usize;
                hs[i] = super::traverse::closest_hit_with(
                    bvh,
                    isa,
                    &rs[i],
                    &prep[k],
                    c,
                    &mut stack.nodes,
                    &mut stack.dists,
                );
            }
        }
        j += len;
    }
}
