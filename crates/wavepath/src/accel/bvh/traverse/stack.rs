//! The one traversal stack of every loop: node references, their entry distances and, for
//! packets, the rays that entered each, in separate arrays (the SIMD paths store a node's hit
//! children as one vector each).
use crate::accel::bvh::tree::{Tri4, WIDTH};

/// Stack entries for trees up to this depth live in a small array; deeper trees use a
/// [`BIG_STACK`] one on the heap.
pub const FIXED_STACK: usize = 128;

/// Entries of the largest stack: enough for any tree the build makes (SAH splits stop at 48
/// levels and median splits below halve the count, so fewer than 80 levels of [`WIDTH`]
/// entries each; the build asserts it).
pub const BIG_STACK: usize = 1024;

/// Stack entries needed per tree level (a node pushes at most all its children).
pub const WIDTH_STACK: usize = WIDTH;

/// A traversal stack of `N - WIDTH` entries: node references, entry distances (closest hit
/// only) and a value `X` per entry (a packet's rays; nothing for single rays).
pub struct Stack<const N: usize, X: Copy + Default = ()> {
    pub nodes: [u32; N],
    pub dists: [f32; N],
    pub rays: [X; N],
    /// The block of the leaf being tested, when the tree's leaves index their corners.
    pub leaf: Tri4,
}

impl<const N: usize, X: Copy + Default> Stack<N, X> {
    /// Positions are taken modulo `N - WIDTH` (a power of two), which never wraps (a
    /// traversal only uses a stack that [`Stack::holds`] its tree's `stack_need`) but lets the
    /// compiler drop every bounds check in the loop: the eight entries above any position
    /// are inside the arrays.
    pub const MASK: usize = {
        assert!(N > WIDTH && (N - WIDTH).is_power_of_two());
        N - WIDTH - 1
    };

    pub fn new() -> Self {
        Stack { nodes: [0; N], dists: [0.0; N], rays: [X::default(); N], leaf: Tri4::default() }
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
    pub fn above(&mut self, sp: usize) -> (&mut [u32; WIDTH], &mut [f32; WIDTH]) {
        let at = sp & Self::MASK;
        let n = (&mut self.nodes[at..at + WIDTH]).try_into().expect("eight entries");
        let d = (&mut self.dists[at..at + WIDTH]).try_into().expect("eight entries");
        (n, d)
    }
}

impl<const N: usize, X: Copy + Default> Default for Stack<N, X> {
    fn default() -> Self {
        Self::new()
    }
}

/// The stack of single rays in shallow trees.
pub type SmallStack = Stack<{ FIXED_STACK + WIDTH }>;
/// The stack of batches, of single rays in deep trees and (with their rays per entry, bit
/// `k` for ray `k`) of packets.
pub type BigStack<X = ()> = Stack<{ BIG_STACK + WIDTH }, X>;
