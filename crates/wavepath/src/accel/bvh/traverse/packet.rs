//! Any-hit for packets of shadow rays: up to eight consecutive rays of the shadow queue, made
//! of whole runs of rays that leave one point (the `-l N` samples of one shading point toward
//! one light; the lane kernel queues them together). The packet is traversed once: one
//! stack, one node fetch and one decision per node for all of its rays, instead of one
//! traversal per ray that repeats the same loads and branches. Shadow rays of different points
//! still share the nodes near the light they all aim at, which is why whole runs are merged.
//!
//! Every ray still gets its own box test (its own [`BoxRay`] values, the same operations as
//! [`BoxTest::test`] in the single-ray any hit) and its own leaf tests (the filter and
//! exact test of `leaf_any`, or, where more rays than triangles enter a leaf, the eight-ray
//! kernel whose hits are that exact test's); a ray enters a child only if its own test of
//! that child passed at every level above. So a ray tests a subset of what its single-ray
//! traversal could reach and the same leaves that matter: the boolean is the single-ray one,
//! bit for bit, whatever the ISA.
//!
//! Per-ray set-up is done for the whole packet at once ([`PacketBoxRays`] at the start,
//! [`PacketShear`] at the first leaf; on AVX2 one ray per lane, with each lane's operations
//! those of the single-ray set-up, so the same values), and the leaf filter starts from the
//! set-up instead of deriving the shear's values again at every leaf. On CBbunny that took
//! the shadow stage from 779 to 640 instructions per ray (docs/decisions.md, "Shadow packets").
use super::{BigStack, Tracer, Walker};
use crate::accel::TraceCounters;
use crate::accel::bvh::Bvh;
use crate::accel::bvh::simd::{PACKET, PacketShear, PacketTest, WithKernels};
use crate::accel::bvh::tree::{LEAF_BIT, Tri4, leaf_range};
use crate::geometry::Ray;

/// [`crate::accel::Intersector::any_hits_packets`]: consecutive runs of rays with the same
/// origin traced as packets (bit for bit, see [`run_len`]); a ray alone is traced as a
/// single ray. `occluded[i]` as [`crate::accel::Intersector::any_hits`].
pub struct ShadowPackets<'a> {
    pub bvh: &'a Bvh,
    pub rays: &'a [Ray],
    pub occluded: &'a mut [bool],
    pub counters: &'a mut TraceCounters,
}

impl WithKernels for ShadowPackets<'_> {
    type Output = ();

    #[inline(always)]
    fn run<K: PacketTest>(self, isa: K) {
        let ShadowPackets { bvh, rays, occluded, counters } = self;
        // One stack for the packets and the rays alone.
        let mut stack = BigStack::<u32>::boxed();
        let mut i = 0;
        while i < rays.len() {
            let n = run_len(&rays[i..]);
            if n == 1 {
                occluded[i] = Walker::new(bvh, isa, &mut *stack, &mut *counters).any(&rays[i]);
            } else {
                Walker::new(bvh, isa, &mut *stack, &mut *counters)
                    .shadow_packet(&rays[i..i + n], &mut occluded[i..i + n]);
            }
            i += n;
        }
    }
}

/// Length of the next packet: whole runs of rays with one origin (the shadow rays of one
/// point), as many as fit in [`PACKET`] (a longer run is split). Rays of a few points share
/// the nodes near the light they all aim at, so merging runs measured ~10% faster on CBbunny
/// than one point per packet.
#[inline(always)]
fn run_len(rays: &[Ray]) -> usize {
    let mut n = run_len1(rays);
    while n < rays.len() {
        let m = run_len1(&rays[n..]);
        if n + m > PACKET {
            break;
        }
        n += m;
    }
    n
}

/// Number of leading rays (at most [`PACKET`]) that share the first ray's origin.
#[inline(always)]
fn run_len1(rays: &[Ray]) -> usize {
    let o = rays[0].origin;
    let mut n = 1;
    while n < PACKET && n < rays.len() {
        let p = rays[n].origin;
        if p.x.to_bits() != o.x.to_bits() || p.y.to_bits() != o.y.to_bits() || p.z.to_bits() != o.z.to_bits() {
            break;
        }
        n += 1;
    }
    n
}

/// Transposes an 8 x 8 bit matrix held as bit `8 r + c` (row `r` in byte `r`): afterwards byte
/// `c` holds column `c` (Hacker's Delight, `transpose8`).
#[inline(always)]
pub(super) fn transpose8(mut x: u64) -> u64 {
    let t = (x ^ (x >> 7)) & 0x00AA_00AA_00AA_00AA;
    x ^= t ^ (t << 7);
    let t = (x ^ (x >> 14)) & 0x0000_CCCC_0000_CCCC;
    x ^= t ^ (t << 14);
    let t = (x ^ (x >> 28)) & 0x0000_0000_F0F0_F0F0;
    x ^= t ^ (t << 28);
    x
}

/// Any-hit for 2..=[`PACKET`] rays at once (see the module comment).
impl<K: PacketTest> Walker<'_, K, &mut BigStack<u32>> {
    #[inline(always)]
    pub fn shadow_packet(&mut self, rays: &[Ray], occluded: &mut [bool]) {
        let t = self.t;
        let (bvh, isa) = (t.bvh, t.isa);
        // The node array in a local: the tree sits behind the walker, so the compiler would
        // reload it after every store to the stack.
        let nodes = &bvh.nodes[..];
        let stack = &mut *self.stack;
        let counters = &mut *self.counters;
        let n = rays.len().min(PACKET);
        counters.rays += n as u64;
        let pb = isa.packet_box_rays(&rays[..n]);
        let live = pb.live;
        // The leaf set-up is made at the packet's first leaf (many rays never reach one), with
        // whether all its live rays share their shear axes (then the eight-ray triangle kernel,
        // which reads the axes of lane 0, may test a triangle for all of them at once).
        let mut shear: Option<(PacketShear, bool)> = None;
        let mut hit = 0u32;
        let (mut sp, mut cur, mut cur_rays) = (0usize, 0u32, live);
        let (mut visited, mut tests) = (0u64, 0u64);
        'trace: loop {
            let active = cur_rays & !hit;
            if active != 0 {
                let node = &nodes[cur as usize];
                // Row k: the children ray k enters.
                let (mut rows, mut any) = (0u64, 0u32);
                visited += active.count_ones() as u64;
                let mut m = active;
                while m != 0 {
                    let k = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let hm = isa.test_lane(node, &pb, k);
                    rows |= (hm as u64) << (8 * k);
                    any |= hm;
                }
                if any.count_ones() > 1 {
                    let mut m = any;
                    while m != 0 {
                        t.prefetch_child(node.child[m.trailing_zeros() as usize]);
                        m &= m - 1;
                    }
                }
                // Column i: the rays that enter child i.
                let cols = transpose8(rows);
                while any != 0 {
                    let i = any.trailing_zeros() as usize;
                    any &= any - 1;
                    let child = node.child[i];
                    let entered = (cols >> (8 * i)) as u32 & 0xff;
                    if child & LEAF_BIT == 0 {
                        stack.nodes[sp] = child;
                        stack.rays[sp] = entered;
                        sp += 1;
                        continue;
                    }
                    let (first, count) = leaf_range(child);
                    let blk = bvh.block(first, &mut stack.leaf);
                    // As `leaf_any`, ray by ray, unless the eight-ray kernel takes the leaf.
                    let mut m = entered & !hit;
                    if m == 0 {
                        continue;
                    }
                    tests += (count as u32 * m.count_ones()) as u64;
                    let (sh, shared) = &*shear.get_or_insert_with(|| {
                        let mut sh = isa.packet_shear(&rays[..n]);
                        let lead = live.trailing_zeros() as usize % PACKET;
                        let mut rest = live;
                        let mut shared = true;
                        while rest != 0 {
                            shared &= sh.rows[rest.trailing_zeros() as usize] == sh.rows[lead];
                            rest &= rest - 1;
                        }
                        sh.rows[0] = sh.rows[lead];
                        (sh, shared)
                    });
                    // More rays than triangles: each triangle for all the rays at once (without
                    // the kernel, the rays go on ray by ray below).
                    if *shared
                        && m.count_ones() as usize > count
                        && let Some(h) = leaf_any_rays(t, LeafRays { blk, count, sh, rays, tmax: &pb.tmax }, m)
                    {
                        hit |= h;
                        m = 0;
                    }
                    while m != 0 {
                        let k = m.trailing_zeros() as usize;
                        m &= m - 1;
                        hit |= (t.block_any_lane(blk, sh, k, &rays[k], sh.tend[k]) as u32) << k;
                    }
                    if hit == live {
                        break 'trace;
                    }
                }
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            cur = stack.nodes[sp];
            cur_rays = stack.rays[sp];
        }
        counters.nodes += visited;
        counters.prim_tests += tests;
        for (k, o) in occluded.iter_mut().enumerate().take(n) {
            *o = hit >> k & 1 != 0;
        }
    }
}

/// A leaf's block as a packet tests it: `count` primitives of `blk`, and the packet's rays
/// with their leaf set-up `sh` and range ends `tmax`.
#[derive(Clone, Copy)]
struct LeafRays<'a> {
    blk: &'a Tri4,
    count: usize,
    sh: &'a PacketShear,
    rays: &'a [Ray],
    tmax: &'a [f32; PACKET],
}

/// The rays of `m` (bit `k`: `rays[k]`, lane `k` of `sh`, range end `tmax[k]`) that hit a
/// primitive of `blk`, a leaf of `count`, each triangle tested for all of them at once by
/// [`PacketTest::tri_rays`] (its hits are the exact test's; the rays it leaves undecided and
/// the other primitives take the exact test ray by ray). None where the instruction set has
/// no such kernel.
#[inline(always)]
fn leaf_any_rays<K: PacketTest>(t: Tracer<'_, K>, leaf: LeafRays<'_>, mut m: u32) -> Option<u32> {
    let LeafRays { blk, count, sh, rays, tmax } = leaf;
    let mut hit = 0;
    for lane in 0..count {
        let mut unsure = m;
        if blk.tri_lanes >> lane & 1 != 0 {
            let r = t.isa.tri_rays(blk, lane, sh, tmax)?;
            hit |= t.kept(r.exact & m, blk.ids[lane], &r, rays);
            unsure &= r.unsure & !hit;
        }
        while unsure != 0 {
            let k = unsure.trailing_zeros() as usize;
            unsure &= unsure - 1;
            if let Some((_, u, v)) = t.lane_hit(blk, lane, &sh.sheared(k, &rays[k]), &rays[k], rays[k].tmax)
                && t.isa.keeps(blk.ids[lane], u, v, &rays[k])
            {
                hit |= 1 << k;
            }
        }
        m &= !hit;
        if m == 0 {
            break;
        }
    }
    Some(hit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transpose8_swaps_rows_and_columns() {
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..1000 {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let x = s ^ (s >> 29);
            let t = transpose8(x);
            for r in 0..8 {
                for c in 0..8 {
                    assert_eq!(x >> (8 * r + c) & 1, t >> (8 * c + r) & 1, "{x:#x} ({r}, {c})");
                }
            }
        }
    }
}
