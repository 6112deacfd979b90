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
use super::boxtest::{BoxRay, BoxTest, Frustum, TIE_SCALE};
use super::traverse::{Best, Stack, closest_in_block, prefetch_child};
use super::wide::{LEAF_BIT, leaf_range};
use crate::accel::TraceCounters;
use crate::accel::triangle::ShearedRay;
use crate::geometry::{Hit, Ray};

/// Rays per packet at most (a 4 x 4 block of pixels, or two pixels of eight samples).
pub const COHERENT: usize = 16;

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

/// Closest hits of a packet: `out[k]` for `rays[k]` (at most [`COHERENT`], all joined by
/// [`packet_len`]), whose bounds are `f`, with a stack that [`Stack::holds`] the tree.
#[inline(always)]
pub(super) fn closest_packet<B: BoxTest, const N: usize>(
    bvh: &Bvh,
    isa: B,
    rays: &[Ray],
    f: &Frustum,
    out: &mut [Option<Hit>],
    counters: &mut TraceCounters,
    stack: &mut Stack<N>,
) {
    let m = rays.len();
    debug_assert!((1..=COHERENT).contains(&m) && out.len() == m && Stack::<N>::holds(bvh.stack_need));
    counters.rays += m as u64;
    let mut best: [Best; COHERENT] =
        std::array::from_fn(|k| Best::new(rays.get(k).map_or(f32::NEG_INFINITY, |r| r.tmax)));
    // Each ray's shear is set up at its first leaf.
    let mut sheared: [Option<ShearedRay>; COHERENT] = [None; COHERENT];
    // The largest closest-hit distance of the packet: what a box must be entered within.
    let mut reach = best[..m].iter().fold(f32::NEG_INFINITY, |r, b| r.max(b.t));
    let (mut sp, mut cur, mut entry) = (0usize, 0u32, f.tmin);
    let (mut visited, mut tests) = (0u64, 0u64);
    loop {
        if cur & LEAF_BIT == 0 {
            visited += 1;
            let node = &bvh.nodes[cur as usize];
            let (pushed, dists) = stack.above(sp);
            let n = isa.visit_frustum(node, f, reach, pushed, dists) as usize;
            if n > 0 {
                // The nearest is on top: take it, the others wait.
                cur = pushed[n - 1];
                entry = dists[n - 1];
                if n > 1 {
                    for &r in pushed.iter().take(n) {
                        prefetch_child(bvh, isa, r);
                    }
                }
                sp += n - 1;
                continue;
            }
        } else {
            let (first, count) = leaf_range(cur);
            let blk = bvh.block(first, &mut stack.leaf);
            let mut r = f32::NEG_INFINITY;
            for k in 0..m {
                // `entry` is at most this ray's own entry distance: past its closest hit,
                // its own test would not enter the leaf.
                if entry <= best[k].t * TIE_SCALE {
                    let ray = &rays[k];
                    let sr = sheared[k].get_or_insert_with(|| ShearedRay::of(ray));
                    tests += count as u64;
                    closest_in_block(bvh, isa, blk, count, sr, ray, &mut best[k]);
                }
                r = r.max(best[k].t);
            }
            reach = r;
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
            let at = sp & Stack::<N>::MASK;
            if stack.dists[at] <= reach * TIE_SCALE {
                cur = stack.nodes[at];
                entry = stack.dists[at];
                break;
            }
        }
    }
}
