//! Whether a ray hits anything (shadow rays).
//!
//! Leaf children of a node are tested as soon as the node is (before any inner child is
//! entered): a shadow ray ends at its first hit, and a leaf costs one filter while an inner
//! child costs at least another node. Only inner children go on the stack, in no order.
use super::leaf::shear;
use super::{BigStack, SmallStack, Stack, Walker};
use crate::accel::TraceCounters;
use crate::accel::bvh::Bvh;
use crate::accel::bvh::simd::{BoxRay, BoxTest, PacketTest, WithKernels};
use crate::accel::bvh::tree::{LEAF_BIT, WIDTH, leaf_range};
use crate::geometry::Ray;

/// [`crate::accel::Intersector::any_hit`] of one ray, on a stack of its own.
pub struct AnyHit<'a> {
    pub bvh: &'a Bvh,
    pub ray: &'a Ray,
    pub counters: &'a mut TraceCounters,
}

impl WithKernels for AnyHit<'_> {
    type Output = bool;

    #[inline(always)]
    fn run<K: PacketTest>(self, isa: K) -> bool {
        let AnyHit { bvh, ray, counters } = self;
        if SmallStack::holds(bvh.stack_need) {
            Walker::new(bvh, isa, &mut SmallStack::new(), counters).any(ray)
        } else {
            Walker::new(bvh, isa, &mut *BigStack::<()>::boxed(), counters).any(ray)
        }
    }
}

/// [`crate::accel::Intersector::any_hits`]: the rays one by one on one stack.
pub struct AnyHits<'a> {
    pub bvh: &'a Bvh,
    pub rays: &'a [Ray],
    pub occluded: &'a mut [bool],
    pub counters: &'a mut TraceCounters,
}

impl WithKernels for AnyHits<'_> {
    type Output = ();

    #[inline(always)]
    fn run<K: PacketTest>(self, isa: K) {
        let AnyHits { bvh, rays, occluded, counters } = self;
        let mut stack = BigStack::<()>::boxed();
        let mut w = Walker::new(bvh, isa, &mut *stack, counters);
        for (r, o) in rays.iter().zip(occluded.iter_mut()) {
            *o = w.any(r);
        }
    }
}

impl<K: BoxTest, const N: usize, X: Copy + Default> Walker<'_, K, &mut Stack<N, X>> {
    /// Whether `ray` hits anything, on a stack that [`Stack::holds`] the tree's
    /// `stack_need`.
    #[inline(always)]
    pub fn any(&mut self, ray: &Ray) -> bool {
        debug_assert!(Stack::<N, X>::holds(self.t.bvh.stack_need));
        let br = &self.t.isa.box_ray(ray);
        self.counters.rays += 1;
        if !br.live {
            return false;
        }
        // The loop compiled once per form of the box test (no branch on it per node).
        if br.fma { self.any_form(ray, br, true) } else { self.any_form(ray, br, false) }
    }

    /// The loop of [`Walker::any`] for a live ray; `fma` is `br.fma`.
    #[inline(always)]
    fn any_form(&mut self, ray: &Ray, br: &BoxRay, fma: bool) -> bool {
        let t = self.t;
        let (bvh, isa) = (t.bvh, t.isa);
        // The node array in a local: the tree sits behind the walker, so the compiler would
        // reload it after every store to the stack.
        let nodes = &bvh.nodes[..];
        let stack = &mut *self.stack;
        let mut sr = None;
        let mut sp = 0usize;
        let mut cur = 0u32;
        let mut tnear = [0f32; WIDTH];
        let (mut visited, mut tests) = (0u64, 0u64);
        let hit = 'trace: loop {
            visited += 1;
            let node = &nodes[cur as usize];
            let mut mask = isa.test_form(node, br, br.octant, fma, ray.tmax, &mut tnear);
            if !bvh.cached && mask.count_ones() > 1 {
                let mut m = mask;
                while m != 0 {
                    t.prefetch_child(node.child[m.trailing_zeros() as usize]);
                    m &= m - 1;
                }
            }
            while mask != 0 {
                let i = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let child = node.child[i];
                if child & LEAF_BIT == 0 {
                    stack.nodes[sp & Stack::<N, X>::MASK] = child;
                    sp += 1;
                    continue;
                }
                tests += leaf_range(child).1 as u64;
                let sr = shear(&mut sr, ray);
                if t.leaf_any(child, sr, ray, &mut stack.leaf) {
                    break 'trace true;
                }
            }
            if sp == 0 {
                break false;
            }
            sp -= 1;
            cur = stack.nodes[sp & Stack::<N, X>::MASK];
        };
        self.counters.nodes += visited;
        self.counters.prim_tests += tests;
        hit
    }
}
