//! Closest-hit and any-hit traversal of the 8-wide tree, generic over the box test so that
//! the scalar and SIMD paths share every other line (and therefore every decision).
use super::Bvh;
use super::boxtest::{BoxRay, BoxTest, TIE_SCALE};
use super::leaf::{LANES, Tri4};
use super::wide::{LEAF_BIT, WIDTH, leaf_range};
use crate::accel::triangle::{ShearedRay, intersect_sheared};
use crate::accel::{TraceCounters, sphere};
use crate::ray::{Hit, Ray};
use glam::Vec3;

/// Stack entries for trees up to this depth live in a fixed array; deeper trees (only
/// possible for adversarial inputs) use a heap stack.
pub const FIXED_STACK: usize = 128;

/// The closest-hit stack, node references and entry distances in separate arrays (the SIMD
/// path stores a node's hit children as one vector each).
pub struct Stack {
    pub nodes: Vec<u32>,
    pub dists: Vec<f32>,
}

impl Stack {
    pub fn new(len: usize) -> Stack {
        Stack { nodes: vec![0; len], dists: vec![0.0; len] }
    }
}

/// The closest hit so far.
pub(super) struct Best {
    pub(super) t: f32,
    prim: u32,
    u: f32,
    v: f32,
    found: bool,
}

impl Best {
    /// Nothing found yet within `[tmin, tmax]`.
    #[inline(always)]
    pub(super) fn new(tmax: f32) -> Best {
        Best { t: tmax, prim: u32::MAX, u: 0.0, v: 0.0, found: false }
    }

    #[inline(always)]
    pub(super) fn hit(&self) -> Option<Hit> {
        self.found.then_some(Hit { t: self.t, prim: self.prim, u: self.u, v: self.v })
    }
}

#[inline(always)]
pub fn closest_hit<B: BoxTest>(bvh: &Bvh, isa: B, ray: &Ray, c: &mut TraceCounters) -> Option<Hit> {
    if bvh.stack_need <= FIXED_STACK {
        let (mut nodes, mut dists) = ([0u32; FIXED_STACK], [0f32; FIXED_STACK]);
        closest_hit_with(bvh, isa, ray, &BoxRay::new(ray), c, &mut nodes, &mut dists)
    } else {
        let mut s = Stack::new(bvh.stack_need);
        closest_hit_with(bvh, isa, ray, &BoxRay::new(ray), c, &mut s.nodes, &mut s.dists)
    }
}

/// Closest hit with the ray's box-test values `br` (`BoxRay::new(ray)`) and a caller-provided
/// stack of at least `bvh.stack_need` entries (batches set up their rays ahead, so the
/// divisions of one ray overlap the traversal of the one before, and reuse one stack instead
/// of clearing a fresh one per ray).
///
/// Children are visited in the node's precomputed order for the ray's octant (nearest by
/// their entry corner, not by the ray's entry distance): no sort per node. The entry
/// distances still go on the stack, so a pop skips children beyond the closest hit so far.
#[inline(always)]
pub fn closest_hit_with<B: BoxTest>(
    bvh: &Bvh,
    isa: B,
    ray: &Ray,
    br: &BoxRay,
    c: &mut TraceCounters,
    nodes: &mut [u32],
    dists: &mut [f32],
) -> Option<Hit> {
    c.rays += 1;
    if !br.live {
        return None;
    }
    // The shear is set up at the first leaf: many rays never reach one.
    let mut sr = None;
    let mut best = Best { t: ray.tmax, prim: u32::MAX, u: 0.0, v: 0.0, found: false };
    let mut sp = 0usize;
    let mut cur = 0u32;
    let mut visited = 0u64;
    loop {
        if cur & LEAF_BIT == 0 {
            visited += 1;
            let node = &bvh.nodes[cur as usize];
            let (n, one) = isa.visit(node, br, br.octant, best.t, nodes, dists, sp);
            if n == 1 {
                // One child hit (the common case): no stack traffic.
                cur = one;
                continue;
            }
            if n > 1 {
                // The nearest is on top: take it, the others wait.
                sp += n as usize - 1;
                cur = one;
                for &r in &nodes[sp + 1 - n as usize..=sp] {
                    prefetch_child(bvh, isa, r);
                }
                continue;
            }
        } else {
            leaf_closest(bvh, isa, cur, sr.get_or_insert_with(|| ShearedRay::of(ray)), ray, &mut best, c);
        }
        // Pop the nearest pending child that can still hold something closer.
        loop {
            if sp == 0 {
                c.nodes += visited;
                return best.found.then_some(Hit { t: best.t, prim: best.prim, u: best.u, v: best.v });
            }
            sp -= 1;
            if dists[sp] <= best.t * TIE_SCALE {
                cur = nodes[sp];
                break;
            }
        }
    }
}

/// Starts loading the node or leaf block behind child reference `r`.
#[inline(always)]
pub(super) fn prefetch_child<B: BoxTest>(bvh: &Bvh, isa: B, r: u32) {
    if r & LEAF_BIT == 0 {
        if let Some(n) = bvh.nodes.get(r as usize) {
            isa.prefetch(n);
        }
    } else if let Some(b) = bvh.blocks.get(leaf_range(r).0 / LANES) {
        isa.prefetch(b);
    }
}

/// Lanes of leaf `r` that need the scalar test (the SIMD kernels drop certain misses), with
/// the leaf's first slot and block.
#[inline(always)]
fn leaf_candidates<'a, B: BoxTest>(
    bvh: &'a Bvh,
    isa: B,
    r: u32,
    sr: &ShearedRay,
    tmin: f32,
    tmax: f32,
) -> (usize, u32, &'a Tri4) {
    let (first, count) = leaf_range(r);
    let all = (1u32 << count) - 1;
    let blk = &bvh.blocks[first / LANES];
    (first, isa.tri_filter(blk, sr, tmin, tmax, blk.tri_lanes) | (all & !blk.tri_lanes), blk)
}

/// The exact test of lane `lane` of a leaf. Triangle corners come from the block the filter
/// just read (the same values as `prims`, already in cache); only spheres read `prims`.
#[inline(always)]
pub(super) fn lane_hit(
    bvh: &Bvh,
    blk: &Tri4,
    first: usize,
    lane: usize,
    sr: &ShearedRay,
    ray: &Ray,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    if blk.tri_lanes >> lane & 1 != 0 {
        let corner = |k: usize| Vec3::new(blk.c[k][0][lane], blk.c[k][1][lane], blk.c[k][2][lane]);
        intersect_sheared(sr, ray.tmin, tmax, corner(0), corner(1), corner(2))
    } else {
        sphere_hit(ray, tmax, &bvh.prims[first + lane])
    }
}

#[inline(always)]
pub(super) fn leaf_closest<B: BoxTest>(
    bvh: &Bvh,
    isa: B,
    r: u32,
    sr: &ShearedRay,
    ray: &Ray,
    best: &mut Best,
    c: &mut TraceCounters,
) {
    c.prim_tests += leaf_range(r).1 as u64;
    let (first, mut cand, blk) = leaf_candidates(bvh, isa, r, sr, ray.tmin, best.t);
    while cand != 0 {
        let lane = cand.trailing_zeros() as usize;
        cand &= cand - 1;
        if let Some((t, u, v)) = lane_hit(bvh, blk, first, lane, sr, ray, best.t) {
            let id = bvh.ids[first + lane];
            if !best.found || t < best.t || (t == best.t && id < best.prim) {
                *best = Best { t, prim: id, u, v, found: true };
            }
        }
    }
}

/// Spheres are stored in the leaf arrays as (centre, (radius, 0, 0), unused).
#[inline(always)]
fn sphere_hit(ray: &Ray, tmax: f32, p: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
    let r = Ray { tmax, ..*ray };
    sphere::intersect(&r, p[0], p[1].x).map(|t| (t, 0.0, 0.0))
}

#[inline(always)]
pub fn any_hit<B: BoxTest>(bvh: &Bvh, isa: B, ray: &Ray, c: &mut TraceCounters) -> bool {
    if bvh.stack_need <= FIXED_STACK {
        let mut fixed = [0u32; FIXED_STACK];
        any_hit_with(bvh, isa, ray, c, &mut fixed)
    } else {
        any_hit_with(bvh, isa, ray, c, &mut vec![0u32; bvh.stack_need])
    }
}

/// Any hit with a caller-provided stack of at least `bvh.stack_need` entries.
///
/// Leaf children of a node are tested as soon as the node is (before any inner child is
/// entered): a shadow ray ends at its first hit, and a leaf costs one filter while an inner
/// child costs at least another node. Only inner children go on the stack, in no order.
#[inline(always)]
pub fn any_hit_with<B: BoxTest>(bvh: &Bvh, isa: B, ray: &Ray, c: &mut TraceCounters, stack: &mut [u32]) -> bool {
    let br = &isa.box_ray(ray);
    c.rays += 1;
    if !br.live {
        return false;
    }
    let mut sr = None;
    let mut sp = 0usize;
    let mut cur = 0u32;
    let mut tnear = [0f32; WIDTH];
    let (mut visited, mut tests) = (0u64, 0u64);
    let hit = 'trace: loop {
        visited += 1;
        let node = &bvh.nodes[cur as usize];
        let mut mask = isa.test(node, br, br.octant, ray.tmax, &mut tnear);
        if mask.count_ones() > 1 {
            let mut m = mask;
            while m != 0 {
                prefetch_child(bvh, isa, node.child[m.trailing_zeros() as usize]);
                m &= m - 1;
            }
        }
        while mask != 0 {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            let child = node.child[i];
            if child & LEAF_BIT == 0 {
                stack[sp] = child;
                sp += 1;
                continue;
            }
            tests += leaf_range(child).1 as u64;
            let sr = sr.get_or_insert_with(|| ShearedRay::of(ray));
            if leaf_any(bvh, isa, child, sr, ray) {
                break 'trace true;
            }
        }
        if sp == 0 {
            break false;
        }
        sp -= 1;
        cur = stack[sp];
    };
    c.nodes += visited;
    c.prim_tests += tests;
    hit
}

/// Whether any primitive of leaf `r` is hit in `[ray.tmin, ray.tmax]`.
#[inline(always)]
fn leaf_any<B: BoxTest>(bvh: &Bvh, isa: B, r: u32, sr: &ShearedRay, ray: &Ray) -> bool {
    let (first, mut cand, blk) = leaf_candidates(bvh, isa, r, sr, ray.tmin, ray.tmax);
    while cand != 0 {
        let lane = cand.trailing_zeros() as usize;
        cand &= cand - 1;
        if lane_hit(bvh, blk, first, lane, sr, ray, ray.tmax).is_some() {
            return true;
        }
    }
    false
}
