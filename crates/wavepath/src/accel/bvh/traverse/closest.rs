//! Closest hit of one ray.
//!
//! Children are visited in the node's precomputed order for the ray's octant (nearest by
//! their entry corner, not by the ray's entry distance): no sort per node. The entry
//! distances still go on the stack, so a pop skips children beyond the closest hit so far.
//!
//! The leaf tests' set-up (the watertight test's shear) is made before the traversal, for
//! eight rays at once ([`PacketTest::packet_shear`]), and each ray reads its lane. Made
//! lazily at a ray's first leaf, one ray at a time, it cost a diffuse ray about 50
//! instructions and a branch the predictor missed every fifth leaf.
use super::leaf::Best;
use super::{BigStack, SmallStack, Stack, Walker};
use crate::accel::TraceCounters;
use crate::accel::bvh::Bvh;
use crate::accel::bvh::simd::{BoxRay, PacketShear, PacketTest, TIE_SCALE, WithKernels};
use crate::accel::bvh::tree::{LEAF_BIT, leaf_range};
use crate::geometry::{Hit, Ray};

/// [`crate::accel::Intersector::closest_hit`] of one ray, on a stack of its own.
pub struct ClosestHit<'a> {
    pub bvh: &'a Bvh,
    pub ray: &'a Ray,
    pub counters: &'a mut TraceCounters,
}

impl WithKernels for ClosestHit<'_> {
    type Output = Option<Hit>;

    #[inline(always)]
    fn run<K: PacketTest>(self, isa: K) -> Option<Hit> {
        let ClosestHit { bvh, ray, counters } = self;
        let sh = isa.packet_shear(std::slice::from_ref(ray));
        if SmallStack::holds(bvh.stack_need) {
            Walker::new(bvh, isa, &mut SmallStack::new(), counters).closest(ray, &BoxRay::new(ray), &sh, 0)
        } else {
            Walker::new(bvh, isa, &mut *BigStack::<()>::boxed(), counters).closest(ray, &BoxRay::new(ray), &sh, 0)
        }
    }
}

impl<K: PacketTest, const N: usize, X: Copy + Default> Walker<'_, K, &mut Stack<N, X>> {
    /// Closest hit of `ray`, whose box-test values are `br` (`BoxRay::new(ray)`) and leaf-test
    /// set-up lane `k` of `sh`, on a stack that [`Stack::holds`] the tree's `stack_need`.
    #[inline(always)]
    pub fn closest(&mut self, ray: &Ray, br: &BoxRay, sh: &PacketShear, k: usize) -> Option<Hit> {
        debug_assert!(Stack::<N, X>::holds(self.t.bvh.stack_need));
        self.counters.rays += 1;
        if !br.live {
            return None;
        }
        // The loop compiled once per form of the box test (no branch on it per node).
        let mut f = Flight::new(ray, br, sh, k, 0);
        if br.fma {
            while !f.step(self, true) {}
        } else {
            while !f.step(self, false) {}
        }
        self.counters.nodes += f.visited;
        f.best.hit()
    }
}

/// One ray's closest-hit traversal in progress, advanced a node or a leaf at a time (so
/// that the interleaved loop can keep three in flight).
pub struct Flight<'r> {
    ray: &'r Ray,
    br: &'r BoxRay,
    /// The leaf-test set-up of the ray's group of eight, and the ray's lane in it.
    sh: &'r PacketShear,
    lane: usize,
    /// Where the hit goes (the ray's place in its group).
    pub slot: usize,
    pub best: Best,
    sp: usize,
    cur: u32,
    pub visited: u64,
}

impl<'r> Flight<'r> {
    #[inline(always)]
    pub fn new(ray: &'r Ray, br: &'r BoxRay, sh: &'r PacketShear, lane: usize, slot: usize) -> Self {
        Flight { ray, br, sh, lane, slot, best: Best::new(ray.tmax), sp: 0, cur: 0, visited: 0 }
    }

    /// Visits the current node, or tests the current leaf and pops the nearest pending child
    /// that can still hold something closer; true when the ray is done. `fma` is `br.fma`
    /// (a constant where the caller's loop is compiled once per form).
    #[inline(always)]
    pub fn step<K: PacketTest, const N: usize, X: Copy + Default>(
        &mut self,
        w: &mut Walker<'_, K, &mut Stack<N, X>>,
        fma: bool,
    ) -> bool {
        let t = w.t;
        let (bvh, isa) = (t.bvh, t.isa);
        let stack = &mut *w.stack;
        if self.cur & LEAF_BIT == 0 {
            self.visited += 1;
            let node = &bvh.nodes[self.cur as usize];
            let (pushed, dists) = stack.above(self.sp);
            let (n, one) = isa.visit(node, self.br, fma, self.best.t, pushed, dists);
            if n == 1 {
                // One child hit (the common case): no stack traffic.
                self.cur = one;
                return false;
            }
            if n > 1 {
                // The nearest is on top: take it, the others wait.
                self.sp += n as usize - 1;
                self.cur = one;
                if !bvh.cached {
                    for &r in pushed.iter().take(n as usize) {
                        t.prefetch_child(r);
                    }
                }
                return false;
            }
        } else {
            w.counters.prim_tests += leaf_range(self.cur).1 as u64;
            t.leaf_closest_lane(self.cur, self.sh, self.lane, self.ray, &mut self.best, &mut stack.leaf);
        }
        loop {
            if self.sp == 0 {
                return true;
            }
            self.sp -= 1;
            let at = self.sp & Stack::<N, X>::MASK;
            if stack.dists[at] <= self.best.t * TIE_SCALE {
                self.cur = stack.nodes[at];
                return false;
            }
        }
    }

    /// [`Flight::step`] with the form of the ray's box test chosen per step (a branch that
    /// follows the ray: the fused form nearly always).
    #[inline(always)]
    pub fn step_any_form<K: PacketTest, const N: usize, X: Copy + Default>(
        &mut self,
        w: &mut Walker<'_, K, &mut Stack<N, X>>,
    ) -> bool {
        if self.br.fma { self.step(w, true) } else { self.step(w, false) }
    }
}
