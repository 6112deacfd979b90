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
use glam::Vec3;

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

    /// [`trace_group`] with this instruction set (out of line in the AVX2 path, see
    /// `closest_group_avx2`).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn trace_group(
        self,
        bvh: &Bvh,
        rs: &[Ray],
        hs: &mut [Option<Hit>],
        prep: &[BoxRay],
        slot: &[u8],
        starts: u32,
        c: &mut TraceCounters,
        stacks: &mut Stacks,
    ) {
        trace_group(bvh, self, rs, hs, prep, slot, starts, c, stacks)
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

    #[inline(always)]
    fn trace_group(
        self,
        bvh: &Bvh,
        rs: &[Ray],
        hs: &mut [Option<Hit>],
        prep: &[BoxRay],
        slot: &[u8],
        starts: u32,
        c: &mut TraceCounters,
        stacks: &mut Stacks,
    ) {
        // SAFETY: `Avx2` exists only if AVX2, FMA, BMI1 and POPCNT were detected.
        unsafe { avx2::closest_group_avx2(bvh, self, rs, hs, prep, slot, starts, c, stacks) }
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl PacketTest for Avx2 {}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{Avx2, BoxRay, Bvh, Hit, Lanes, PacketRays, Ray, Stacks, TIE_SCALE, TraceCounters};
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

    /// [`super::trace_group`] compiled with the features of `simd::with_avx2`, out of line,
    /// called only for groups where a packet may start: inlined into the batch loop, the
    /// packet code made the single-ray traversal of every group slower (register allocation
    /// and layout of the shared loop; measured on the dragon's diffuse rays, where packets
    /// are rare: -4 to -7%). One call per group of 32 rays costs nothing measurable.
    #[target_feature(enable = "avx2,fma,bmi1,popcnt")]
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    pub fn closest_group_avx2(
        bvh: &Bvh,
        tok: Avx2,
        rs: &[Ray],
        hs: &mut [Option<Hit>],
        prep: &[BoxRay],
        slot: &[u8],
        starts: u32,
        c: &mut TraceCounters,
        stacks: &mut Stacks,
    ) {
        super::trace_group(bvh, tok, rs, hs, prep, slot, starts, c, stacks)
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

/// The stacks of a batch: single rays' and packets'.
pub struct Stacks {
    pub single: Box<super::traverse::BigStack>,
    pub packet: Stack,
}

impl Stacks {
    pub fn new(len: usize) -> Stacks {
        Stacks { single: super::traverse::BigStack::boxed(), packet: Stack::new(len) }
    }
}

/// Cosine of the widest angle between a packet's first direction and any other. Camera rays
/// of neighbouring pixels (or one pixel's samples) lie within a fraction of a degree; diffuse
/// bounces of neighbouring points often share an octant (their normals are alike) but spread
/// over the hemisphere, and as packets they cost more than alone (measured: +8% instructions
/// on the dragon's diffuse rays with the octant test only).
pub const MIN_COS: f32 = 0.99;

/// Whether direction `d` lies within [`MIN_COS`] of `d0` (compared in squares, no roots).
#[inline(always)]
fn in_cone(d0: Vec3, d: Vec3) -> bool {
    let dot = d0.dot(d);
    dot >= 0.0 && dot * dot >= d0.length_squared() * (MIN_COS * MIN_COS) * d.length_squared()
}

/// Neighbouring pairs [`mostly_coherent`] looks at, spread evenly over the batch.
const PROBES: usize = 16;

/// Whether packets may pay in this batch: at least a quarter of [`PROBES`] pairs of
/// neighbouring rays share an octant and lie within [`MIN_COS`]. Camera rays in pixel blocks
/// pass nearly every probe, diffuse bounces almost none (one wrong guess only costs speed,
/// never changes a hit).
pub fn mostly_coherent(rays: &[Ray]) -> bool {
    if rays.len() < 2 * MIN_PACKET {
        return false;
    }
    let step = (rays.len() - 1) / PROBES.min(rays.len() - 1);
    let close = (0..PROBES.min(rays.len() - 1))
        .filter(|&k| {
            let (a, b) = (rays[k * step].dir, rays[k * step + 1].dir);
            super::wide::octant(a.to_array()) == super::wide::octant(b.to_array()) && in_cone(a, b)
        })
        .count();
    4 * close >= PROBES.min(rays.len() - 1)
}

/// Length of the run of prepared rays starting at `br[0]` (ray `rs[slot[0]]`, where
/// [`run_starts`] allows a packet) that can form a packet: live, the same octant, directions
/// within [`MIN_COS`] of the first; at most [`PACKET`].
#[inline(always)]
pub fn run_len(br: &[BoxRay], rs: &[Ray], slot: &[u8]) -> usize {
    let first = &br[0];
    let d0 = rs[slot[0] as usize].dir;
    let mut n = 1;
    while n < PACKET
        && n < br.len()
        && br[n].live
        && br[n].octant == first.octant
        && in_cone(d0, rs[slot[n] as usize].dir)
    {
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

/// Bit `j` set when prepared rays `j .. j + MIN_PACKET` are live and share ray `j`'s octant
/// (where a packet may start), computed without a branch per ray: incoherent rays (diffuse
/// bounces) rarely have such runs, and a per-ray test of the next ray's octant was a
/// mispredicted branch per ray (-3% on the dragon's diffuse rays).
#[inline(always)]
pub fn run_starts(prep: &[BoxRay]) -> u32 {
    let mut same = 0u32;
    for (j, w) in prep.windows(2).enumerate() {
        same |= ((w[0].octant == w[1].octant) as u32 & w[0].live as u32 & w[1].live as u32) << j;
    }
    let mut starts = same;
    for k in 1..MIN_PACKET - 1 {
        starts &= same >> k;
    }
    starts
}

/// [`run_starts`] of the prepared rays `prep` (ray `rs[slot[j]]` for `prep[j]`), or 0 when
/// no start has its next [`MIN_PACKET`] rays within [`MIN_COS`] of the first: diffuse
/// bounces of neighbouring points often share octants (a third of the dragon's groups of 32
/// had such runs) but almost never pass the cone, and a group without a packet stays in the
/// caller's single-ray loop. (The first start that passes is enough: the group path checks
/// each packet again.)
#[inline(always)]
pub fn coherent_starts(prep: &[BoxRay], rs: &[Ray], slot: &[u8]) -> u32 {
    let starts = run_starts(prep);
    let mut m = starts;
    while m != 0 {
        let j = m.trailing_zeros() as usize;
        m &= m - 1;
        if run_len(&prep[j..j + MIN_PACKET], rs, &slot[j..j + MIN_PACKET]) >= MIN_PACKET {
            return starts;
        }
    }
    0
}

/// Traces the prepared rays of one batch group: `prep[j]` are the box-test values of ray
/// `rs[slot[j]]` (the rays that passed the root-box test, in batch order; at most 32), and
/// `starts` is [`run_starts`] of them. Runs of at least [`MIN_PACKET`] coherent rays
/// ([`run_len`]) go as packets, every other ray alone.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn trace_group<B: PacketTest>(
    bvh: &Bvh,
    isa: B,
    rs: &[Ray],
    hs: &mut [Option<Hit>],
    prep: &[BoxRay],
    slot: &[u8],
    starts: u32,
    c: &mut TraceCounters,
    stacks: &mut Stacks,
) {
    let n = prep.len();
    let stack = &mut stacks.single;
    let mut j = 0;
    loop {
        // Single rays up to the next place a packet may start.
        let pending = if j < 32 { starts & (u32::MAX << j) } else { 0 };
        let next = if pending == 0 { n } else { pending.trailing_zeros() as usize };
        for k in j..next {
            let i = slot[k] as usize;
            hs[i] = super::traverse::closest_hit_with(bvh, isa, &rs[i], &prep[k], c, stack);
        }
        if next >= n {
            break;
        }
        let len = run_len(&prep[next..], rs, &slot[next..]);
        if len >= MIN_PACKET {
            let mut pr = [rs[slot[next] as usize]; PACKET];
            for k in 1..len {
                pr[k] = rs[slot[next + k] as usize];
            }
            let mut ph = [None; PACKET];
            closest_packet(bvh, isa, &pr[..len], &prep[next..next + len], &mut ph[..len], c, &mut stacks.packet);
            for k in 0..len {
                hs[slot[next + k] as usize] = ph[k];
            }
            j = next + len;
        } else {
            let i = slot[next] as usize;
            hs[i] = super::traverse::closest_hit_with(bvh, isa, &rs[i], &prep[next], c, stack);
            j = next + 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn ray(dir: Vec3) -> Ray {
        Ray { origin: Vec3::ZERO, dir, tmin: 0.0, tmax: f32::INFINITY }
    }

    /// Camera rays across a 64x64 image with a 40 degree field of view are neighbours within
    /// a fraction of a degree; directions spread over the sphere by the golden angle (like
    /// diffuse bounces of unrelated points) are not; a batch too short for a packet never is.
    #[test]
    fn camera_rays_are_coherent_and_spread_rays_are_not() {
        let camera: Vec<Ray> = (0..64 * 64)
            .map(|i| {
                let (x, y) = ((i % 64) as f32 / 64.0 - 0.5, (i / 64) as f32 / 64.0 - 0.5);
                ray(Vec3::new(x * 0.73, y * 0.73, -1.0))
            })
            .collect();
        assert!(mostly_coherent(&camera));
        let spread: Vec<Ray> = (0..4096)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f32 + 0.5) / 4096.0;
                let phi = i as f32 * 2.399_963;
                let r = (1.0 - z * z).sqrt();
                ray(Vec3::new(r * phi.cos(), r * phi.sin(), z))
            })
            .collect();
        assert!(!mostly_coherent(&spread));
        assert!(!mostly_coherent(&camera[..2 * MIN_PACKET - 1]));
        assert!(mostly_coherent(&camera[..2 * MIN_PACKET]));
    }
}
