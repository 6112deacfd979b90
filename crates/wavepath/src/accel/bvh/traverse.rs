//! Closest-hit and any-hit traversal of the 8-wide tree, generic over the box test so that
//! the scalar and SIMD paths share every other line (and therefore every decision).
use super::Bvh;
use super::boxtest::{BoxRay, BoxTest, TIE_SCALE};
use super::leaf::Tri4;
use super::wide::{LEAF_BIT, WIDTH, leaf_range};
use crate::accel::triangle::{ShearedRay, intersect_sheared};
use crate::accel::{TraceCounters, sphere};
use crate::geometry::{Hit, Ray};
use glam::Vec3;

/// Stack entries for trees up to this depth live in a small array; deeper trees use a
/// [`BIG_STACK`] one on the heap.
pub const FIXED_STACK: usize = 128;

/// Entries of the largest stack: enough for any tree [`Bvh::build`] makes (SAH splits stop
/// at 48 levels and median splits below halve the count, so fewer than 80 levels of
/// [`WIDTH`] entries each; the build asserts it).
pub const BIG_STACK: usize = 1024;

/// A traversal stack of `N - WIDTH` entries: node references and (closest hit only) entry
/// distances, in separate arrays (the SIMD path stores a node's hit children as one vector
/// each).
pub struct Stack<const N: usize> {
    pub nodes: [u32; N],
    pub dists: [f32; N],
    /// The block of the leaf being tested, when the tree's leaves index their corners.
    pub leaf: Tri4,
}

impl<const N: usize> Stack<N> {
    /// Positions are taken modulo `N - WIDTH` (a power of two), which never wraps (a
    /// traversal only uses a stack that [`Stack::holds`] its tree's `stack_need`) but lets the
    /// compiler drop every bounds check in the loop: the eight entries above any position
    /// are inside the arrays.
    pub(super) const MASK: usize = {
        assert!(N > WIDTH && (N - WIDTH).is_power_of_two());
        N - WIDTH - 1
    };

    pub fn new() -> Self {
        Stack { nodes: [0; N], dists: [0.0; N], leaf: Tri4::default() }
    }

    pub fn boxed() -> Box<Self> {
        Box::new(Self::new())
    }

    /// Whether a tree needing `need` entries fits.
    pub const fn holds(need: usize) -> bool {
        need <= N - WIDTH
    }

    /// The eight entries from position `sp` on.
    #[inline(always)]
    pub(super) fn above(&mut self, sp: usize) -> (&mut [u32; WIDTH], &mut [f32; WIDTH]) {
        let at = sp & Self::MASK;
        let n = (&mut self.nodes[at..at + WIDTH]).try_into().expect("eight entries");
        let d = (&mut self.dists[at..at + WIDTH]).try_into().expect("eight entries");
        (n, d)
    }
}

impl<const N: usize> Default for Stack<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// The stack of single rays in shallow trees.
pub type SmallStack = Stack<{ FIXED_STACK + WIDTH }>;
/// The stack of batches (and of single rays in deep trees).
pub type BigStack = Stack<{ BIG_STACK + WIDTH }>;

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

    /// Takes a hit at `t` (barycentrics `u`, `v`) on primitive `id` if it is closer, or as
    /// close with a lower id: the same closest hit whatever order the hits come in.
    #[inline(always)]
    pub(super) fn offer(&mut self, (t, u, v): (f32, f32, f32), id: u32) {
        if !self.found || t < self.t || (t == self.t && id < self.prim) {
            *self = Best { t, prim: id, u, v, found: true };
        }
    }

    #[inline(always)]
    pub(super) fn hit(&self) -> Option<Hit> {
        self.found.then_some(Hit { t: self.t, prim: self.prim, u: self.u, v: self.v })
    }
}

#[inline(always)]
pub fn closest_hit<B: BoxTest>(bvh: &Bvh, isa: B, ray: &Ray, counters: &mut TraceCounters) -> Option<Hit> {
    if SmallStack::holds(bvh.stack_need) {
        closest_hit_with(bvh, isa, ray, &BoxRay::new(ray), counters, &mut SmallStack::new())
    } else {
        closest_hit_with(bvh, isa, ray, &BoxRay::new(ray), counters, &mut *BigStack::boxed())
    }
}

/// Closest hit with the ray's box-test values `br` (`BoxRay::new(ray)`) and a stack that
/// [`Stack::holds`] `bvh.stack_need`.
///
/// Children are visited in the node's precomputed order for the ray's octant (nearest by
/// their entry corner, not by the ray's entry distance): no sort per node. The entry
/// distances still go on the stack, so a pop skips children beyond the closest hit so far.
#[inline(always)]
pub(super) fn closest_hit_with<B: BoxTest, const N: usize>(
    bvh: &Bvh,
    isa: B,
    ray: &Ray,
    br: &BoxRay,
    counters: &mut TraceCounters,
    stack: &mut Stack<N>,
) -> Option<Hit> {
    debug_assert!(Stack::<N>::holds(bvh.stack_need));
    counters.rays += 1;
    if !br.live {
        return None;
    }
    // The loop compiled once per form of the box test (no branch on it per node).
    if br.fma {
        walk(bvh, isa, ray, br, true, counters, stack)
    } else {
        walk(bvh, isa, ray, br, false, counters, stack)
    }
}

/// The loop of [`closest_hit_with`] for a live ray; `fma` is `br.fma`.
#[inline(always)]
fn walk<B: BoxTest, const N: usize>(
    bvh: &Bvh,
    isa: B,
    ray: &Ray,
    br: &BoxRay,
    fma: bool,
    counters: &mut TraceCounters,
    stack: &mut Stack<N>,
) -> Option<Hit> {
    let mut w = Walker::new(ray, br, 0);
    while !w.step(bvh, isa, fma, counters, stack) {}
    counters.nodes += w.visited;
    w.best.hit()
}

/// One ray's closest-hit traversal in progress, advanced a node or a leaf at a time (so
/// that [`closest_interleaved`] can keep three in flight).
struct Walker<'r> {
    ray: &'r Ray,
    br: &'r BoxRay,
    /// Where the hit goes (the ray's place in its group).
    slot: usize,
    best: Best,
    /// The shear, set up at the first leaf: many rays never reach one.
    sr: Option<ShearedRay>,
    sp: usize,
    cur: u32,
    visited: u64,
}

impl<'r> Walker<'r> {
    #[inline(always)]
    fn new(ray: &'r Ray, br: &'r BoxRay, slot: usize) -> Self {
        Walker { ray, br, slot, best: Best::new(ray.tmax), sr: None, sp: 0, cur: 0, visited: 0 }
    }

    /// Visits the current node, or tests the current leaf and pops the nearest pending child
    /// that can still hold something closer; true when the ray is done. `fma` is `br.fma`
    /// (a constant where the caller's loop is compiled once per form).
    #[inline(always)]
    fn step<B: BoxTest, const N: usize>(
        &mut self,
        bvh: &Bvh,
        isa: B,
        fma: bool,
        counters: &mut TraceCounters,
        stack: &mut Stack<N>,
    ) -> bool {
        if self.cur & LEAF_BIT == 0 {
            self.visited += 1;
            let node = &bvh.nodes[self.cur as usize];
            let (pushed, dists) = stack.above(self.sp);
            let br = self.br;
            let (n, one) = isa.visit(node, br, br.octant, fma, self.best.t, pushed, dists);
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
                        prefetch_child(bvh, isa, r);
                    }
                }
                return false;
            }
        } else {
            let ray = self.ray;
            let sr = shear(&mut self.sr, ray);
            counters.prim_tests += leaf_range(self.cur).1 as u64;
            leaf_closest(bvh, isa, self.cur, sr, ray, &mut self.best, &mut stack.leaf);
        }
        loop {
            if self.sp == 0 {
                return true;
            }
            self.sp -= 1;
            let at = self.sp & Stack::<N>::MASK;
            if stack.dists[at] <= self.best.t * TIE_SCALE {
                self.cur = stack.nodes[at];
                return false;
            }
        }
    }

    /// [`Walker::step`] with the form of the ray's box test chosen per step (a branch that
    /// follows the ray: the fused form nearly always).
    #[inline(always)]
    fn step_any_form<B: BoxTest, const N: usize>(
        &mut self,
        bvh: &Bvh,
        isa: B,
        counters: &mut TraceCounters,
        stack: &mut Stack<N>,
    ) -> bool {
        if self.br.fma {
            self.step(bvh, isa, true, counters, stack)
        } else {
            self.step(bvh, isa, false, counters, stack)
        }
    }
}

/// Closest hits of the rays `rays[i]` (box-test values `prep[i]`) for each `i` of `which`,
/// into `hits[i]`, three rays in flight at once: in a tree beyond the caches a ray's step
/// waits on a node load from memory that the other rays' steps overlap, where one ray alone
/// leaves the core idle on each. Each ray takes the steps it would take alone, so its hit
/// and counts are the same.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn closest_interleaved<B: BoxTest, const N: usize>(
    bvh: &Bvh,
    isa: B,
    rays: &[Ray],
    prep: &[BoxRay],
    which: &[u8],
    hits: &mut [Option<Hit>],
    counters: &mut TraceCounters,
    stacks: [&mut Stack<N>; 3],
) {
    debug_assert!(Stack::<N>::holds(bvh.stack_need));
    let [sa, sb, sc] = stacks;
    let mut pending = which.iter();
    // The next live ray (dead ones are misses without a traversal).
    let mut take = |hits: &mut [Option<Hit>], counters: &mut TraceCounters| {
        for &i in pending.by_ref() {
            let i = i as usize;
            counters.rays += 1;
            if prep[i].live {
                return Some(Walker::new(&rays[i], &prep[i], i));
            }
            hits[i] = None;
        }
        None
    };
    let mut a = take(hits, counters);
    let mut b = take(hits, counters);
    let mut c = take(hits, counters);
    // One step of a ray in flight; a ray done gives its place to the next.
    macro_rules! advance {
        ($w:ident, $stack:ident) => {
            if let Some(w) = &mut $w {
                if w.step_any_form(bvh, isa, counters, $stack) {
                    counters.nodes += w.visited;
                    hits[w.slot] = w.best.hit();
                    $w = take(hits, counters);
                }
            }
        };
    }
    while a.is_some() || b.is_some() || c.is_some() {
        advance!(a, sa);
        advance!(b, sb);
        advance!(c, sc);
    }
}

/// The ray's shear, set up at its first leaf (many rays never reach one). Not
/// `Option::get_or_insert_with`: its closure was compiled out of line, a call (and a leave
/// of the AVX2 context) at every leaf.
#[inline(always)]
fn shear<'a>(sr: &'a mut Option<ShearedRay>, ray: &Ray) -> &'a ShearedRay {
    match sr {
        Some(sr) => sr,
        None => sr.insert(ShearedRay::of(ray)),
    }
}

/// Starts loading the node or leaf block behind child reference `r`. Branch-free: both
/// addresses are formed and one is picked by mask (a branch on leaf-or-node here was
/// mispredicted about three times per diffuse ray); a prefetch never faults, so an address
/// past either array is harmless.
#[inline(always)]
pub(super) fn prefetch_child<B: BoxTest>(bvh: &Bvh, isa: B, r: u32) {
    let leaf = 0usize.wrapping_sub((r >> 31) as usize);
    let node = bvh.nodes.as_ptr().wrapping_add(r as usize) as usize;
    let (base, size) = bvh.leaf_base;
    let block = base.wrapping_add(leaf_range(r).0 * size);
    isa.prefetch_at((block & leaf | node & !leaf) as *const u8);
}

/// Lanes of leaf `r` that need the scalar test (the SIMD kernels drop certain misses), with
/// the leaf's block (`scratch` holds it when the leaves index their corners).
#[inline(always)]
fn leaf_candidates<'a, B: BoxTest>(
    bvh: &'a Bvh,
    isa: B,
    r: u32,
    sr: &ShearedRay,
    tmin: f32,
    tmax: f32,
    scratch: &'a mut Tri4,
) -> (u32, &'a Tri4) {
    let (first, count) = leaf_range(r);
    let blk = bvh.block(first, scratch);
    (block_candidates(isa, blk, count, sr, tmin, tmax), blk)
}

/// Lanes of a leaf's block of `count` primitives that need the scalar test.
#[inline(always)]
fn block_candidates<B: BoxTest>(isa: B, blk: &Tri4, count: usize, sr: &ShearedRay, tmin: f32, tmax: f32) -> u32 {
    let all = (1u32 << count) - 1;
    isa.tri_filter(blk, sr, tmin, tmax, blk.tri_lanes) | (all & !blk.tri_lanes)
}

/// The exact test of lane `lane` of a leaf. Triangle corners come from the block the filter
/// just read (already in cache); spheres from the tree's sphere list.
#[inline(always)]
pub(super) fn lane_hit(
    bvh: &Bvh,
    blk: &Tri4,
    lane: usize,
    sr: &ShearedRay,
    ray: &Ray,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    if blk.tri_lanes >> lane & 1 != 0 {
        let corner = |k: usize| Vec3::new(blk.c[k][0][lane], blk.c[k][1][lane], blk.c[k][2][lane]);
        intersect_sheared(sr, ray.tmin, tmax, corner(0), corner(1), corner(2))
    } else {
        let (centre, radius) = bvh.spheres[(blk.ids[lane] - bvh.tri_count) as usize];
        let r = Ray { tmax, ..*ray };
        sphere::intersect(&r, centre, radius).map(|t| (t, 0.0, 0.0))
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
    scratch: &mut Tri4,
) {
    let (first, count) = leaf_range(r);
    closest_in_block(bvh, isa, bvh.block(first, scratch), count, sr, ray, best);
}

/// [`leaf_closest`] in a leaf's block of `count` primitives, already at hand.
#[inline(always)]
pub(super) fn closest_in_block<B: BoxTest>(
    bvh: &Bvh,
    isa: B,
    blk: &Tri4,
    count: usize,
    sr: &ShearedRay,
    ray: &Ray,
    best: &mut Best,
) {
    let mut cand = block_candidates(isa, blk, count, sr, ray.tmin, best.t);
    while cand != 0 {
        let lane = cand.trailing_zeros() as usize;
        cand &= cand - 1;
        if let Some(h) = lane_hit(bvh, blk, lane, sr, ray, best.t) {
            best.offer(h, blk.ids[lane]);
        }
    }
}

#[inline(always)]
pub fn any_hit<B: BoxTest>(bvh: &Bvh, isa: B, ray: &Ray, counters: &mut TraceCounters) -> bool {
    if SmallStack::holds(bvh.stack_need) {
        any_hit_with(bvh, isa, ray, counters, &mut SmallStack::new())
    } else {
        any_hit_with(bvh, isa, ray, counters, &mut *BigStack::boxed())
    }
}

/// Any hit with a caller-provided stack that [`Stack::holds`] `bvh.stack_need`.
///
/// Leaf children of a node are tested as soon as the node is (before any inner child is
/// entered): a shadow ray ends at its first hit, and a leaf costs one filter while an inner
/// child costs at least another node. Only inner children go on the stack, in no order.
#[inline(always)]
pub fn any_hit_with<B: BoxTest, const N: usize>(
    bvh: &Bvh,
    isa: B,
    ray: &Ray,
    counters: &mut TraceCounters,
    stack: &mut Stack<N>,
) -> bool {
    debug_assert!(Stack::<N>::holds(bvh.stack_need));
    let br = &isa.box_ray(ray);
    counters.rays += 1;
    if !br.live {
        return false;
    }
    // The loop compiled once per form of the box test (no branch on it per node).
    if br.fma {
        walk_any(bvh, isa, ray, br, true, counters, stack)
    } else {
        walk_any(bvh, isa, ray, br, false, counters, stack)
    }
}

/// The loop of [`any_hit_with`] for a live ray; `fma` is `br.fma`.
#[inline(always)]
fn walk_any<B: BoxTest, const N: usize>(
    bvh: &Bvh,
    isa: B,
    ray: &Ray,
    br: &BoxRay,
    fma: bool,
    counters: &mut TraceCounters,
    stack: &mut Stack<N>,
) -> bool {
    let mut sr = None;
    let mut sp = 0usize;
    let mut cur = 0u32;
    let mut tnear = [0f32; WIDTH];
    let (mut visited, mut tests) = (0u64, 0u64);
    let hit = 'trace: loop {
        visited += 1;
        let node = &bvh.nodes[cur as usize];
        let mut mask = isa.test_form(node, br, br.octant, fma, ray.tmax, &mut tnear);
        if !bvh.cached && mask.count_ones() > 1 {
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
                stack.nodes[sp & Stack::<N>::MASK] = child;
                sp += 1;
                continue;
            }
            tests += leaf_range(child).1 as u64;
            let sr = shear(&mut sr, ray);
            if leaf_any(bvh, isa, child, sr, ray, &mut stack.leaf) {
                break 'trace true;
            }
        }
        if sp == 0 {
            break false;
        }
        sp -= 1;
        cur = stack.nodes[sp & Stack::<N>::MASK];
    };
    counters.nodes += visited;
    counters.prim_tests += tests;
    hit
}

/// Whether any primitive of leaf `r` is hit in `[ray.tmin, ray.tmax]`.
#[inline(always)]
fn leaf_any<B: BoxTest>(bvh: &Bvh, isa: B, r: u32, sr: &ShearedRay, ray: &Ray, scratch: &mut Tri4) -> bool {
    let (mut cand, blk) = leaf_candidates(bvh, isa, r, sr, ray.tmin, ray.tmax, scratch);
    while cand != 0 {
        let lane = cand.trailing_zeros() as usize;
        cand &= cand - 1;
        if lane_hit(bvh, blk, lane, sr, ray, ray.tmax).is_some() {
            return true;
        }
    }
    false
}
