//! Any-hit for packets of shadow rays: up to eight consecutive rays of the shadow queue, made
//! of whole runs of rays that leave one point (the `-l N` samples of one shading point toward
//! one light; the lane kernel queues them together). The packet is traversed once: one
//! stack, one node fetch and one decision per node for all of its rays, instead of one
//! traversal per ray that repeats the same loads and branches. Shadow rays of different points
//! still share the nodes near the light they all aim at, which is why whole runs are merged.
//!
//! Every ray still gets its own box test ([`BoxTest::test`] with its own [`BoxRay`], exactly
//! as in [`traverse::any_hit_with`]) and its own leaf tests (the same `leaf_any`); a ray
//! enters a child only if its own test of that child passed at every level above. So a ray
//! tests a subset of what its single-ray traversal could reach and the same leaves that
//! matter: the boolean is the single-ray one, bit for bit, whatever the ISA.
use super::Bvh;
use super::boxtest::{BoxRay, BoxTest};
use super::leaf::LANES;
use super::traverse::{self, lane_hit, prefetch_child};
use super::wide::{LEAF_BIT, WIDTH, leaf_range};
use crate::accel::TraceCounters;
use crate::accel::triangle::{ShearedRay, range_end};
use crate::ray::Ray;

/// Rays per packet at most (one byte of a ray mask per child; 8 x 8 masks transpose in a u64).
pub const PACKET: usize = 8;

/// Any-hit for `rays`, traced as packets of consecutive runs of rays with the same origin
/// (bit for bit, see [`run_len`]); a ray alone is traced as a single ray. `occluded[i]` as [`crate::accel::Intersector::any_hits`].
pub fn any_hits(bvh: &Bvh, rays: &[Ray], occluded: &mut [bool], c: &mut TraceCounters) {
    let mut stack =
        Stack { nodes: vec![0u32; bvh.stack_need], masks: vec![0u32; bvh.stack_need], leaf: [LeafRay::DEAD; PACKET] };
    // The loop is spelled out in the macro and every closure is `#[inline(always)]`: anything
    // left out of line would be compiled outside the AVX2 context (see `Bvh::closest_hits`).
    macro_rules! run {
        ($isa:expr) => {{
            let mut i = 0;
            while i < rays.len() {
                let n = run_len(&rays[i..]);
                if n == 1 {
                    occluded[i] = traverse::any_hit_with(bvh, $isa, &rays[i], c, &mut stack.nodes);
                } else {
                    packet_any(bvh, $isa, &rays[i..i + n], &mut occluded[i..i + n], c, &mut stack);
                }
                i += n;
            }
        }};
    }
    on_isa!(bvh, |t| run!(t))
}

/// The packet stack: node references and, per entry, the rays that entered it; and the
/// leaf-test set-up of the packet's rays (reused across packets: each packet marks which
/// entries it has written).
struct Stack {
    nodes: Vec<u32>,
    masks: Vec<u32>,
    leaf: [LeafRay; PACKET],
}

/// A ray's set-up for its leaf tests, made at its first leaf: the shear of the watertight
/// test and, for the SIMD filter, the same values the single-ray filter derives from it at
/// every leaf (the origin on the sheared axes, `range_end(tmax)`, the offsets of the axes'
/// rows in a [`super::leaf::Tri4`] corner), so a ray that tests several leaves derives them once.
#[derive(Clone, Copy, Debug)]
pub(super) struct LeafRay {
    pub(super) sr: ShearedRay,
    /// The origin's kx, ky, kz coordinates.
    pub(super) org: [f32; 3],
    pub(super) tmin: f32,
    pub(super) tmax: f32,
    /// `range_end(tmax)`.
    pub(super) tend: f32,
    /// Byte offsets `16 * axis` of the kx, ky, kz rows of a corner (`Tri4::c[corner]`).
    pub(super) rows: [u8; 3],
}

impl LeafRay {
    const DEAD: LeafRay = LeafRay {
        sr: ShearedRay { org: glam::Vec3::ZERO, kx: 0, ky: 1, kz: 2, sx: 0.0, sy: 0.0, sz: 0.0 },
        org: [0.0; 3],
        tmin: 0.0,
        tmax: 0.0,
        tend: 0.0,
        rows: [0, 16, 32],
    };

    #[inline(always)]
    fn new(ray: &Ray) -> LeafRay {
        let sr = ShearedRay::of(ray);
        let o = sr.org.to_array();
        let (kx, ky, kz) = (sr.kx % 3, sr.ky % 3, sr.kz % 3);
        LeafRay {
            sr,
            org: [o[kx], o[ky], o[kz]],
            tmin: ray.tmin,
            tmax: ray.tmax,
            tend: range_end(ray.tmax),
            rows: [16 * kx as u8, 16 * ky as u8, 16 * kz as u8],
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
#[inline(always)]
fn packet_any<B: BoxTest>(
    bvh: &Bvh,
    isa: B,
    rays: &[Ray],
    occluded: &mut [bool],
    c: &mut TraceCounters,
    stack: &mut Stack,
) {
    let n = rays.len().min(PACKET);
    c.rays += n as u64;
    let mut br = [BoxRay::DEAD; PACKET];
    let mut live = 0u32;
    for k in 0..n {
        br[k] = isa.box_ray(&rays[k]);
        live |= (br[k].live as u32) << k;
    }
    // The leaf set-up of a ray is made at its first leaf (as in the single-ray traversal).
    let mut ready = 0u32;
    let mut hit = 0u32;
    let (mut sp, mut cur, mut cur_rays) = (0usize, 0u32, live);
    let mut tnear = [0f32; WIDTH];
    let (mut visited, mut tests) = (0u64, 0u64);
    'trace: loop {
        let active = cur_rays & !hit;
        if active != 0 {
            let node = &bvh.nodes[cur as usize];
            // Row k: the children ray k enters.
            let (mut rows, mut any) = (0u64, 0u32);
            let mut m = active;
            while m != 0 {
                let k = m.trailing_zeros() as usize;
                m &= m - 1;
                visited += 1;
                let hm = isa.test(node, &br[k], br[k].octant, rays[k].tmax, &mut tnear);
                rows |= (hm as u64) << (8 * k);
                any |= hm;
            }
            if any.count_ones() > 1 {
                let mut m = any;
                while m != 0 {
                    prefetch_child(bvh, isa, node.child[m.trailing_zeros() as usize]);
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
                    stack.masks[sp] = entered;
                    sp += 1;
                    continue;
                }
                let (first, count) = leaf_range(child);
                let blk = &bvh.blocks[first / LANES];
                // As `leaf_any`: the filter's triangle lanes and every other lane, then the
                // exact test in lane order up to the first hit.
                let others = ((1u32 << count) - 1) & !blk.tri_lanes;
                let mut m = entered & !hit;
                while m != 0 {
                    let k = m.trailing_zeros() as usize;
                    m &= m - 1;
                    tests += count as u64;
                    if ready >> k & 1 == 0 {
                        stack.leaf[k] = LeafRay::new(&rays[k]);
                        ready |= 1 << k;
                    }
                    let lr = &stack.leaf[k];
                    let mut cand = isa.tri_filter_leaf(blk, lr, blk.tri_lanes) | others;
                    while cand != 0 {
                        let lane = cand.trailing_zeros() as usize;
                        cand &= cand - 1;
                        if lane_hit(bvh, blk, first, lane, &lr.sr, &rays[k], rays[k].tmax).is_some() {
                            hit |= 1 << k;
                            break;
                        }
                    }
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
        cur_rays = stack.masks[sp];
    }
    c.nodes += visited;
    c.prim_tests += tests;
    for (k, o) in occluded.iter_mut().enumerate().take(n) {
        *o = hit >> k & 1 != 0;
    }
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
