//! The traversal loops of the 8-wide tree, written once over the kernel traits so that the
//! scalar and SIMD paths share every other line (and therefore every decision). Each loop is
//! a method of one [`Walker`] (the tree and its kernels, a [`Stack`], the counters) in a file
//! of its own: [`closest`] and [`any_hit`] for single rays, [`interleaved`] for three rays in
//! flight, [`packet`] for shadow rays of one point, [`coherent`] for camera rays of one
//! pixel block; [`batch_policy`] decides which loop each ray of a batch takes. Every entry point
//! is a value implementing [`crate::accel::bvh::simd::WithKernels`], run with the kernels of
//! one instruction set.
mod any_hit;
mod batch_policy;
mod closest;
mod coherent;
mod interleaved;
mod leaf;
mod packet;
mod stack;

pub use any_hit::{AnyHit, AnyHits};
pub use batch_policy::ClosestBatch;
pub use closest::ClosestHit;
pub use packet::ShadowPackets;
pub use stack::{BIG_STACK, BigStack, SmallStack, Stack, WIDTH_STACK};

use super::Bvh;
use crate::accel::TraceCounters;
use crate::accel::bvh::simd::BoxTest;
use crate::accel::bvh::tree::leaf_range;

/// Tree size (nodes and leaves, bytes) above which single rays are traced as in a tree that
/// does not fit the caches: three in flight at once, each prefetching the children it pushes,
/// which hides memory latency (25.6M, 1.6 GB: diffuse rays 1.19 -> 1.53 Mrays/s). Below it
/// they go one at a time without prefetching: the prefetches are only extra instructions
/// (Lucy 100k, 6 MB: 1-3% faster without), and rays in flight gain 2-5% on a lone mesh's
/// diffuse rays but cost renders 4-6% of their traverse stage (rays that end after a node or
/// two, a Cornell box's walls, pay the bookkeeping and overlap nothing). At 1.6M (100 MB) the
/// prefetches break even and rays in flight gain 15%. Packets prefetch at every size (camera
/// rays at 100k: 6-8% slower without).
pub const CACHED_UP_TO: usize = 32 << 20;

/// The tree and the kernels that test it: what every loop and leaf test reads (a copy is
/// two words, so it travels by value beside the borrowed stack).
#[derive(Clone, Copy)]
pub struct Tracer<'a, K> {
    pub bvh: &'a Bvh,
    pub isa: K,
}

/// One traversal's state: the tree and its kernels, the stack `S` (one [`Stack`], or one
/// per ray in flight) and the counters the traversal adds to. The loops are its methods.
pub struct Walker<'a, K, S> {
    pub t: Tracer<'a, K>,
    pub stack: S,
    pub counters: &'a mut TraceCounters,
}

impl<'a, K: BoxTest, S> Walker<'a, K, S> {
    #[inline(always)]
    pub fn new(bvh: &'a Bvh, isa: K, stack: S, counters: &'a mut TraceCounters) -> Self {
        Walker { t: Tracer { bvh, isa }, stack, counters }
    }
}

impl<K: BoxTest> Tracer<'_, K> {
    /// Starts loading the node or leaf block behind child reference `r`. Branch-free: both
    /// addresses are formed and one is picked by mask (a branch on leaf-or-node here was
    /// mispredicted about three times per diffuse ray); a prefetch never faults, so an
    /// address past either array is harmless.
    #[inline(always)]
    pub fn prefetch_child(self, r: u32) {
        let bvh = self.bvh;
        let leaf = 0usize.wrapping_sub((r >> 31) as usize);
        let node = bvh.nodes.as_ptr().wrapping_add(r as usize) as usize;
        let (base, size) = bvh.leaf_base;
        let block = base.wrapping_add(leaf_range(r).0 * size);
        self.isa.prefetch_at((block & leaf | node & !leaf) as *const u8);
    }
}
