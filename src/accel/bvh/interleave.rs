//! Closest hits of incoherent rays, two traversals interleaved in one loop.
//!
//! A single ray's node loop is one long dependency chain (load node -> slab test -> mask ->
//! next child's load), and a diffuse ray's next node is often not in L2. Stepping two rays in
//! turn, each with its own stack and closest hit, gives the core two independent chains to
//! overlap; the next node of each ray is prefetched as soon as it is known, so its load is
//! under way while the other ray takes its step. Every ray does exactly the steps of
//! [`super::traverse::closest_hit_with`], so the hits are the same bits.
use super::Bvh;
use super::boxtest::{BoxRay, BoxTest, RootBox, TIE_SCALE};
use super::traverse::{Best, Stack, leaf_closest, prefetch_child};
use super::wide::LEAF_BIT;
use crate::accel::TraceCounters;
use crate::accel::triangle::ShearedRay;
use crate::ray::{Hit, Ray};

/// Rays set up at a time (one bit each in the root-box admission mask).
const GROUP: usize = 32;

/// One ray's traversal in flight.
struct Walk {
    /// Index of the ray in the batch.
    i: usize,
    br: BoxRay,
    cur: u32,
    sp: usize,
    best: Best,
    visited: u64,
    /// Set up at the ray's first leaf (many rays never reach one).
    sr: Option<ShearedRay>,
}

impl Walk {
    #[inline(always)]
    fn start(i: usize, br: BoxRay, ray: &Ray) -> Walk {
        Walk { i, br, cur: 0, sp: 0, best: Best::new(ray.tmax), visited: 0, sr: None }
    }
}

/// The batch's rays that may hit something, set up a group at a time ahead of their
/// traversal (root-box admission and box-test values as in `Bvh::closest_batch`); the others
/// are written as misses when their group is set up.
struct Feed<'a> {
    rays: &'a [Ray],
    hits: &'a mut [Option<Hit>],
    root: Option<&'a RootBox>,
    /// Start of the next group to set up.
    next_group: usize,
    /// The current group's admitted rays: box-test values and batch indices, `k..n` pending.
    prep: [BoxRay; GROUP],
    slot: [u32; GROUP],
    k: usize,
    n: usize,
}

impl<'a> Feed<'a> {
    /// The next live ray (batch index and box-test values), or `None` at the end of the batch.
    #[inline(always)]
    fn next<B: BoxTest>(&mut self, isa: B, c: &mut TraceCounters) -> Option<(usize, BoxRay)> {
        loop {
            while self.k < self.n {
                let (i, br) = (self.slot[self.k] as usize, self.prep[self.k]);
                self.k += 1;
                if br.live {
                    return Some((i, br));
                }
                // A dead ray: counted and a miss, as in the single-ray loop.
                c.rays += 1;
            }
            if self.next_group >= self.rays.len() {
                return None;
            }
            let base = self.next_group;
            let end = (base + GROUP).min(self.rays.len());
            self.next_group = end;
            let rs = &self.rays[base..end];
            let mut todo = match self.root {
                Some(root) => isa.admit_mask(root, rs),
                None => u32::MAX >> (GROUP - rs.len()),
            };
            let mut n = 0;
            while todo != 0 {
                let i = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                self.prep[n] = isa.box_ray(&rs[i]);
                self.slot[n] = (base + i) as u32;
                n += 1;
            }
            c.rays += (rs.len() - n) as u64;
            self.hits[base..end].fill(None);
            (self.k, self.n) = (0, n);
        }
    }
}

/// One step of `w`: a node visit (then the nearest hit child is next), or a leaf or a node
/// with no child hit (then the nearest pending child that can still hold something closer).
/// Returns whether the ray is done. The next node is prefetched at once.
#[inline(always)]
fn step<B: BoxTest>(bvh: &Bvh, isa: B, rays: &[Ray], w: &mut Walk, st: &mut Stack, c: &mut TraceCounters) -> bool {
    if w.cur & LEAF_BIT == 0 {
        w.visited += 1;
        let node = &bvh.nodes[w.cur as usize];
        // Read the ray's values from memory at each node (as the single-ray loop does): else
        // LLVM hoists both rays' broadcasts and plane addresses out of the loop and spills
        // them, and every node reloads twice as much.
        let br = std::hint::black_box(&w.br);
        let (n, one) = isa.visit(node, br, br.octant, w.best.t, &mut st.nodes, &mut st.dists, w.sp);
        if n != 0 {
            if n > 1 {
                w.sp += n as usize - 1;
                for &r in &st.nodes[w.sp + 1 - n as usize..=w.sp] {
                    prefetch_child(bvh, isa, r);
                }
            }
            w.cur = one;
            return false;
        }
    } else {
        let ray = &rays[w.i];
        leaf_closest(bvh, isa, w.cur, w.sr.get_or_insert_with(|| ShearedRay::of(ray)), ray, &mut w.best, c);
    }
    while w.sp != 0 {
        w.sp -= 1;
        if st.dists[w.sp] <= w.best.t * TIE_SCALE {
            w.cur = st.nodes[w.sp];
            return false;
        }
    }
    true
}

/// Records the result of a finished traversal.
#[inline(always)]
fn finish(w: &Walk, hits: &mut [Option<Hit>], c: &mut TraceCounters) {
    c.rays += 1;
    c.nodes += w.visited;
    hits[w.i] = w.best.hit();
}

/// Closest hits of `rays` into `hits`, two rays traversed at a time (`bvh` is not empty;
/// `stacks` hold at least `bvh.stack_need` entries each).
#[inline(always)]
pub(super) fn closest_hits<B: BoxTest>(
    bvh: &Bvh,
    isa: B,
    rays: &[Ray],
    hits: &mut [Option<Hit>],
    c: &mut TraceCounters,
    stacks: &mut [Stack; 2],
) {
    let mut feed = Feed {
        rays,
        hits,
        root: bvh.root.as_ref(),
        next_group: 0,
        prep: [BoxRay::DEAD; GROUP],
        slot: [0; GROUP],
        k: 0,
        n: 0,
    };
    let [sa, sb] = stacks;
    let Some((i, br)) = feed.next(isa, c) else { return };
    let mut a = Walk::start(i, br, &rays[i]);
    let Some((i, br)) = feed.next(isa, c) else {
        return run_alone(bvh, isa, rays, a, sa, &mut feed, c);
    };
    let mut b = Walk::start(i, br, &rays[i]);
    loop {
        let done_a = step(bvh, isa, rays, &mut a, sa, c);
        let done_b = step(bvh, isa, rays, &mut b, sb, c);
        if done_a {
            finish(&a, feed.hits, c);
            match feed.next(isa, c) {
                Some((i, br)) => a = Walk::start(i, br, &rays[i]),
                None => {
                    if done_b {
                        return finish(&b, feed.hits, c);
                    }
                    return run_alone(bvh, isa, rays, b, sb, &mut feed, c);
                }
            }
        }
        if done_b {
            finish(&b, feed.hits, c);
            match feed.next(isa, c) {
                Some((i, br)) => b = Walk::start(i, br, &rays[i]),
                None => return run_alone(bvh, isa, rays, a, sa, &mut feed, c),
            }
        }
    }
}

/// The last ray of the batch, alone.
#[inline(always)]
fn run_alone<B: BoxTest>(
    bvh: &Bvh,
    isa: B,
    rays: &[Ray],
    mut w: Walk,
    st: &mut Stack,
    feed: &mut Feed,
    c: &mut TraceCounters,
) {
    while !step(bvh, isa, rays, &mut w, st, c) {}
    finish(&w, feed.hits, c);
}
