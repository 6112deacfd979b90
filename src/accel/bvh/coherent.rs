//! Closest hits of coherent rays: runs of rays that leave one point with nearly parallel
//! directions in one octant (a pinhole camera's samples of one pixel, or of a block of
//! neighbouring pixels). Such a packet is traversed once: one box test per node for all of
//! its rays, by the interval of their reciprocal directions ([`Frustum`]), one stack and one
//! visiting order. Only at the leaves is each ray tested on its own, with its own closest
//! hit so far (rays whose own entry could not come before their closest hit are skipped).
//!
//! The packet's test enters every box that any of its rays' own (unfused) tests would enter
//! (see [`Frustum`]), with the largest closest-hit distance of the packet, so each ray's
//! leaf tests cover every leaf its single-ray traversal could find a closer hit in; the
//! closest hit does not depend on the order leaves are tested in (ties go to the lower
//! primitive id at any order), so each ray's hit is its single-ray hit, bit for bit.
use super::Bvh;
use super::boxtest::{BoxRay, Frustum, TIE_SCALE};
use super::leaf::Tri4;
use super::packet::{PACKET, PacketBoxRays, PacketShear, PacketTest};
use super::traverse::{Best, closest_in_block, lane_hit, prefetch_child};
use super::wide::{LEAF_BIT, WIDTH, leaf_range};
use crate::accel::TraceCounters;
use crate::geometry::{Hit, Ray};

/// Rays per packet at most (a 4 x 4 block of pixels, or two pixels of eight samples).
pub const COHERENT: usize = 16;

/// A set of a packet's rays (bit `k`: ray `k`).
type Rays = u32;
const _: () = assert!(COHERENT <= Rays::BITS as usize && COHERENT.is_multiple_of(PACKET));

/// Groups of [`PACKET`] rays in a packet: the SIMD kernels take one group at a time.
const GROUPS: usize = COHERENT / PACKET;

/// Rays a packet needs at least: the packet's node test costs about two single-ray tests.
pub const MIN_RAYS: usize = 4;

/// Smallest cosine of the angle between a packet's first direction and any other's. Wider
/// packets enter boxes few of their rays hit, and every ray then tests those leaves; camera
/// rays of neighbouring pixels are far closer (a 4 x 4 block of an 800 x 600 image with a 45
/// degree field of view spans 0.3 degrees).
const MIN_COS: f32 = 0.9995;

/// How many leading rays of `prep` (box-test values of `rays[slot[i]]`) form a packet with
/// the first one (at most [`COHERENT`]): live, from the same origin, in the same octant and
/// within the cone of [`MIN_COS`].
#[inline(always)]
pub(super) fn packet_len(rays: &[Ray], slot: &[u8], prep: &[BoxRay]) -> usize {
    let lead = &prep[0];
    if !lead.live {
        return 1;
    }
    let d0 = rays[slot[0] as usize].dir;
    let l0 = d0.length_squared();
    let mut n = 1;
    while n < prep.len().min(COHERENT) && Frustum::joins(lead, &prep[n]) {
        let d = rays[slot[n] as usize].dir;
        let dot = d0.dot(d);
        if !(dot > 0.0 && dot * dot >= MIN_COS * MIN_COS * l0 * d.length_squared()) {
            break;
        }
        n += 1;
    }
    n
}

/// The stack of packets: node references, the packet's entry distances and the rays that
/// may enter each (bit `k`: ray `k`).
pub(super) struct PacketStack {
    nodes: Vec<u32>,
    dists: Vec<f32>,
    rays: Vec<Rays>,
    /// The block of the leaf being tested, when the tree's leaves index their corners.
    leaf: Tri4,
}

impl PacketStack {
    pub(super) fn new(bvh: &Bvh) -> PacketStack {
        let n = bvh.stack_need + WIDTH;
        PacketStack { nodes: vec![0; n], dists: vec![0.0; n], rays: vec![0; n], leaf: Tri4::default() }
    }
}

/// Closest hits of a packet: `out[k]` for `rays[k]` (at most [`COHERENT`], all joined by
/// [`packet_len`]), whose bounds are `f`.
///
/// At a node with a leaf among the children the packet enters, each such child also takes
/// the box test of each ray (eight rays at a time, each with its own closest hit), so a leaf
/// is tested only by the rays that enter it; inner children pass those sets on.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn closest_packet<B: PacketTest>(
    bvh: &Bvh,
    isa: B,
    rays: &[Ray],
    f: &Frustum,
    out: &mut [Option<Hit>],
    counters: &mut TraceCounters,
    stack: &mut PacketStack,
) {
    let m = rays.len();
    debug_assert!((1..=COHERENT).contains(&m) && out.len() == m);
    debug_assert!(stack.nodes.len() >= bvh.stack_need + WIDTH);
    counters.rays += m as u64;
    let mut best: [Best; COHERENT] =
        std::array::from_fn(|k| Best::new(rays.get(k).map_or(f32::NEG_INFINITY, |r| r.tmax)));
    // The rays' shears are set up at the first leaf, eight at a time.
    let mut shears: Option<[PacketShear; GROUPS]> = None;
    // And their box-test values at the first node with leaf children.
    let mut boxes: Option<[PacketBoxRays; GROUPS]> = None;
    // The largest closest-hit distance of the packet: what a box must be entered within.
    let mut reach = farthest(&best[..m]);
    let all = Rays::MAX >> (Rays::BITS as usize - m);
    let (mut sp, mut cur, mut entry, mut act) = (0usize, 0u32, f.tmin, all);
    let (mut visited, mut tests) = (0u64, 0u64);
    let mut slots = [0u32; WIDTH];
    loop {
        if cur & LEAF_BIT == 0 {
            visited += 1;
            let node = &bvh.nodes[cur as usize];
            let top: &mut [u32; WIDTH] = (&mut stack.nodes[sp..sp + WIDTH]).try_into().expect("eight entries");
            let dists: &mut [f32; WIDTH] = (&mut stack.dists[sp..sp + WIDTH]).try_into().expect("eight entries");
            let n = isa.visit_frustum(node, f, reach, &mut *top, &mut *dists, &mut slots) as usize;
            if n > 0 {
                let sets = &mut stack.rays[sp..sp + n];
                if top[..n].iter().any(|&c| c & LEAF_BIT != 0) {
                    // Rays per child, from each ray's own test, eight rays at a time.
                    if boxes.is_none() {
                        let mut b = [PacketBoxRays::EMPTY; GROUPS];
                        for (g, b) in b.iter_mut().enumerate() {
                            *b = isa.packet_box_rays(eighth(rays, g));
                        }
                        boxes = Some(b);
                    }
                    let Some(boxes) = &boxes else { unreachable!("set above") };
                    sets.fill(0);
                    for (h, p) in boxes.iter().enumerate() {
                        let lanes = act >> (PACKET * h) & 0xff;
                        if lanes != 0 {
                            let mut closest = [0f32; PACKET];
                            for (c, b) in closest.iter_mut().zip(&best[PACKET * h..]) {
                                *c = b.t;
                            }
                            for (set, &slot) in sets.iter_mut().zip(&slots) {
                                let rays = isa.slot_rays(node, slot as usize, p, f.octant, &closest) & lanes;
                                *set |= (rays as Rays) << (PACKET * h);
                            }
                        }
                    }
                } else {
                    sets.fill(act);
                }
                for &r in top.iter().take(n) {
                    prefetch_child(bvh, isa, r);
                }
                // The pending children go on the stack, the nearest is taken now.
                sp += n - 1;
                (cur, entry, act) = (top[n - 1], dists[n - 1], stack.rays[sp]);
                if act != 0 {
                    continue;
                }
            }
        } else {
            let (first, count) = leaf_range(cur);
            let blk = bvh.block(first, &mut stack.leaf);
            // `entry` is at most each ray's own entry distance: past its closest hit, a ray's
            // own test would not enter the leaf.
            let mut todo = act;
            let mut cull = act;
            while cull != 0 {
                let k = cull.trailing_zeros() as usize;
                cull &= cull - 1;
                if entry > best[k].t * TIE_SCALE {
                    todo &= !(1 << k);
                }
            }
            tests += (todo.count_ones() as usize * count) as u64;
            // (Not in a closure: one compiled out of line would leave the AVX2 context.)
            if shears.is_none() {
                let mut p = [PacketShear::EMPTY; GROUPS];
                for (g, p) in p.iter_mut().enumerate() {
                    *p = isa.packet_shear(eighth(rays, g));
                }
                shears = Some(p);
            }
            let Some(shears) = &shears else { unreachable!("set above") };
            for (h, p) in shears.iter().enumerate() {
                let lanes = todo >> (PACKET * h) & 0xff;
                if lanes != 0 {
                    let at = PACKET * h;
                    leaf_rays(bvh, isa, blk, count, p, lanes, &rays[at..], &mut best[at..at + PACKET]);
                }
            }
            reach = farthest(&best[..m]);
        }
        // Pop the nearest pending child that some ray may still find something closer in.
        loop {
            if sp == 0 {
                counters.nodes += visited;
                counters.prim_tests += tests;
                for (o, b) in out.iter_mut().zip(&best) {
                    *o = b.hit();
                }
                return;
            }
            sp -= 1;
            if stack.rays[sp] != 0 && stack.dists[sp] <= reach * TIE_SCALE {
                (cur, entry, act) = (stack.nodes[sp], stack.dists[sp], stack.rays[sp]);
                break;
            }
        }
    }
}

/// The leaf tests of the rays `lanes` (bit `k`: `rays[k]`, lane `k` of `p`) in `blk`, a leaf
/// of `count` primitives, each ray with its own closest hit so far (`best[k]`). Where the
/// instruction set has the kernel and the rays share their axes, each triangle is filtered
/// for all the rays at once; the filter's survivors take the exact test ray by ray, in any
/// order (the closest hit does not depend on it).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn leaf_rays<B: PacketTest>(
    bvh: &Bvh,
    isa: B,
    blk: &Tri4,
    count: usize,
    p: &PacketShear,
    lanes: u32,
    rays: &[Ray],
    best: &mut [Best],
) {
    let lead = lanes.trailing_zeros() as usize;
    let mut shared = true;
    let mut rest = lanes;
    while rest != 0 {
        shared &= p.rows[rest.trailing_zeros() as usize] == p.rows[lead];
        rest &= rest - 1;
    }
    let mut lead_shear = *p;
    if shared {
        // The kernel reads the axes of lane 0.
        lead_shear.rows[0] = p.rows[lead];
        let mut closest = [0f32; PACKET];
        for (c, b) in closest.iter_mut().zip(best.iter()) {
            *c = b.t;
        }
        for lane in 0..count {
            let tri = blk.tri_lanes >> lane & 1 != 0;
            let Some(mut cand) =
                (if tri { isa.tri_filter_rays(blk, lane, &lead_shear, &closest) } else { Some(lanes) })
            else {
                break;
            };
            cand &= lanes;
            while cand != 0 {
                let k = cand.trailing_zeros() as usize;
                cand &= cand - 1;
                let ray = &rays[k];
                if let Some(h) = lane_hit(bvh, blk, lane, &p.sheared(k, ray), ray, best[k].t) {
                    best[k].offer(h, blk.ids[lane]);
                    closest[k] = best[k].t;
                }
            }
            if lane + 1 == count {
                return;
            }
        }
    }
    // Ray by ray (no kernel, or rays of different axes).
    let mut rest = lanes;
    while rest != 0 {
        let k = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        closest_in_block(bvh, isa, blk, count, &p.sheared(k, &rays[k]), &rays[k], &mut best[k]);
    }
}

/// The largest closest-hit distance of `best` (none is NaN).
#[inline(always)]
fn farthest(best: &[Best]) -> f32 {
    let mut r = f32::NEG_INFINITY;
    for b in best {
        if b.t > r {
            r = b.t;
        }
    }
    r
}

/// Rays `8 g ..` of `rays`, at most eight (empty past the end).
#[inline(always)]
fn eighth(rays: &[Ray], g: usize) -> &[Ray] {
    let start = (PACKET * g).min(rays.len());
    &rays[start..(start + PACKET).min(rays.len())]
}
