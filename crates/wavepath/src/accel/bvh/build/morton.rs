//! The fast build (`--bvh-build fast`): primitives sorted along a Morton curve of their
//! centroids and split where the code's highest differing bit changes (the LBVH of
//! Lauterbach et al. 2009), instead of by the SAH. One sort and one pass over the sorted
//! codes replace the binned build's binning and partition of every level; the tree is worse
//! (rays take 6-12% longer on the meshes measured, docs/decisions.md, "Fast build"). The
//! result is the binary tree [`super::sah::build`] makes (the same node array layout,
//! leaves of at most [`MAX_LEAF`]), so the collapse, the leaf store and every traversal are
//! shared, and the closest hits are those of any other tree.
//!
//! No primitive references are made: a primitive's box is computed where it is needed, from
//! the scene, so the build holds the sort keys (8 bytes a primitive) where the SAH build
//! holds its references (28).
use super::binary::{MAX_LEAF, Node2, PARALLEL_MIN, join_subtrees, node_bound};
use glam::Vec3;
use rayon::prelude::*;

/// Sets of at most this many primitives are cut into leaves of [`MAX_LEAF`] in curve order
/// (consecutive primitives are neighbours), not at the code's bits: full leaves, where bit
/// splits leave many part-filled ones (a leaf block costs the same whatever it holds).
const CHUNKED: usize = 16;

/// Most Morton bits per axis (three axes and the primitive's index share a 64-bit key).
const MAX_BITS: u32 = 21;

/// How a sort key is laid out: a centroid's Morton code above the primitive's index (so keys
/// are unique, and primitives with equal codes keep the mesh's order), `shift` bits for the
/// index and `bits` per axis for the code.
#[derive(Clone, Copy, Debug)]
pub(super) struct Keys {
    shift: u32,
    bits: u32,
}

impl Keys {
    /// As many code bits per axis as `n` indices leave room for, up to [`MAX_BITS`].
    pub(super) fn for_count(n: usize) -> Keys {
        let shift = (usize::BITS - n.saturating_sub(1).leading_zeros()).max(1);
        Keys { shift, bits: ((64 - shift) / 3).min(MAX_BITS) }
    }

    fn code(self, k: u64) -> u64 {
        k >> self.shift
    }

    fn index(self, k: u64) -> usize {
        (k & ((1u64 << self.shift) - 1)) as usize
    }
}

/// The binary tree over primitives `0..n`, whose boxes `prim` gives, in Morton order; and the
/// primitive indices in its leaf order.
pub fn build<F>(n: usize, prim: F) -> (Vec<Node2>, Vec<u32>)
where
    F: Fn(usize) -> (Vec3, Vec3) + Sync,
{
    assert!(n > 0 && n <= u32::MAX as usize);
    let kf = Keys::for_count(n);
    let keys = sorted_keys(n, &prim, kf);
    let mut nodes: Vec<Node2> = bytemuck::zeroed_vec(node_bound(n));
    Tree { prim, kf }.emit_par(&keys, 0, &mut nodes, 0);
    let order = keys.par_iter().map(|&k| kf.index(k) as u32).collect();
    (nodes, order)
}

/// The sorted keys (see [`Keys`]) of primitives `0..n`: each centroid's Morton code in a
/// cube around all of them (cubic cells split space evenly whatever the scene's proportions).
fn sorted_keys<F>(n: usize, prim: &F, kf: Keys) -> Vec<u64>
where
    F: Fn(usize) -> (Vec3, Vec3) + Sync,
{
    let centroid = |i: usize| {
        let (lo, hi) = prim(i);
        0.5 * (lo + hi)
    };
    let inf = Vec3::INFINITY;
    let (lo, hi) = (0..n)
        .into_par_iter()
        .fold(
            || (inf, -inf),
            |(lo, hi), i| {
                let c = centroid(i);
                (lo.min(c), hi.max(c))
            },
        )
        .reduce(|| (inf, -inf), |a, b| (a.0.min(b.0), a.1.max(b.1)));
    let extent = (hi - lo).max_element();
    // One point (or an extent that overflows) gives every primitive the same code, and the
    // splits halve: still a valid tree.
    let scale = if extent > 0.0 && extent.is_finite() { (1u64 << kf.bits) as f32 / extent } else { 0.0 };
    let mut keys: Vec<u64> =
        (0..n).into_par_iter().map(|i| morton(centroid(i), lo, scale, kf.bits) << kf.shift | i as u64).collect();
    keys.par_sort_unstable();
    keys
}

/// The Morton code of `c` in a grid of `2^bits` cells of `1 / scale` per axis from `lo`,
/// each axis clamped to the grid (a NaN coordinate to cell 0).
pub(super) fn morton(c: Vec3, lo: Vec3, scale: f32, bits: u32) -> u64 {
    let max = ((1u64 << bits) - 1) as f32;
    let cell = |x: f32, l: f32| ((x - l) * scale).clamp(0.0, max) as u64;
    spread(cell(c.x, lo.x)) << 2 | spread(cell(c.y, lo.y)) << 1 | spread(cell(c.z, lo.z))
}

/// The low 21 bits of `v` with two zero bits inserted after each.
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | x << 32) & 0x1f_0000_0000_ffff;
    x = (x | x << 16) & 0x1f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    (x | x << 2) & 0x1249_2492_4924_9249
}

/// Where the sorted `keys` (at least two) split: before the first whose code has the
/// highest bit in which the first and last codes differ, or halfway when all codes are
/// equal. Both sides are non-empty.
pub(super) fn split_point(keys: &[u64], kf: Keys) -> usize {
    let (first, last) = (kf.code(keys[0]), kf.code(keys[keys.len() - 1]));
    if first == last {
        return keys.len() / 2;
    }
    // The keys are sorted, so every key between shares the codes' bits above `bit`.
    let bit = 63 - (first ^ last).leading_zeros();
    keys.partition_point(|&k| kf.code(k) >> bit & 1 == 0)
}

/// What every subtree reads: the primitives' boxes and the keys' layout.
struct Tree<F> {
    prim: F,
    kf: Keys,
}

impl<F: Fn(usize) -> (Vec3, Vec3) + Sync> Tree<F> {
    /// Writes the subtree over `keys` (leaf-order places `base ..`) into `nodes`, its root
    /// at `nodes[0]`, index `at` of the whole array, in the ranges the SAH build gives its
    /// parallel levels; returns the subtree's box (nodes are boxed bottom-up).
    fn emit_par(&self, keys: &[u64], base: usize, nodes: &mut [Node2], at: usize) -> (Vec3, Vec3) {
        if keys.len() < PARALLEL_MIN {
            return self.emit_seq(keys, base, nodes, at, &mut 0).1;
        }
        let mid = split_point(keys, self.kf);
        let (l, r) = keys.split_at(mid);
        join_subtrees(
            nodes,
            at,
            mid,
            |n, i| self.emit_par(l, base, n, i),
            |n, i| self.emit_par(r, base + mid, n, i),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        )
    }

    /// [`Tree::emit_par`] on one thread, its nodes written densely from `nodes[*next]` on;
    /// returns the root's absolute index and the box.
    fn emit_seq(
        &self,
        keys: &[u64],
        base: usize,
        nodes: &mut [Node2],
        at: usize,
        next: &mut usize,
    ) -> (u32, (Vec3, Vec3)) {
        let me = *next;
        *next += 1;
        let n = keys.len();
        let (lo, hi) = if n <= MAX_LEAF {
            let (lo, hi) = keys.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &k| {
                let (a, b) = (self.prim)(self.kf.index(k));
                (lo.min(a), hi.max(b))
            });
            nodes[me] = Node2 { lo, hi, a: base as u32, b: 0, count: n as u32 };
            (lo, hi)
        } else {
            let mid =
                if n <= CHUNKED { n.div_ceil(MAX_LEAF).div_ceil(2) * MAX_LEAF } else { split_point(keys, self.kf) };
            let (l, r) = keys.split_at(mid);
            let (a, lb) = self.emit_seq(l, base, nodes, at, next);
            let (b, rb) = self.emit_seq(r, base + mid, nodes, at, next);
            let (lo, hi) = (lb.0.min(rb.0), lb.1.max(rb.1));
            nodes[me] = Node2 { lo, hi, a, b, count: 0 };
            (lo, hi)
        };
        ((at + me) as u32, (lo, hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Uniform numbers in [0, 1) from a seed (a linear congruential generator).
    fn uniform(seed: u64) -> impl FnMut() -> f32 {
        let mut x = seed;
        move || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// Bit `i` of each cell index at bit `3 i + 2` (x), `3 i + 1` (y), `3 i` (z), one bit at a
    /// time: the definition the shifts and masks must meet.
    fn interleaved(x: u64, y: u64, z: u64, bits: u32) -> u64 {
        (0..bits)
            .fold(0, |m, i| m | (x >> i & 1) << (3 * i + 2) | (y >> i & 1) << (3 * i + 1) | (z >> i & 1) << (3 * i))
    }

    #[test]
    fn codes_interleave_the_cells_bits() {
        let mut u = uniform(3);
        for bits in [1, 10, 15, 21] {
            let cells = 1u64 << bits;
            for _ in 0..2000 {
                let c = [0; 3].map(|_| ((u() * cells as f32) as u64).min(cells - 1));
                // The centre of cell c in a grid of unit cells from the origin.
                let p = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) + 0.5;
                assert_eq!(morton(p, Vec3::ZERO, 1.0, bits), interleaved(c[0], c[1], c[2], bits), "{bits} bits {c:?}");
            }
            // Outside the grid (and NaN) clamps to its edge cells.
            let top = interleaved(cells - 1, 0, cells - 1, bits);
            assert_eq!(morton(Vec3::new(1e30, -5.0, f32::INFINITY), Vec3::ZERO, 1.0, bits), top);
            assert_eq!(morton(Vec3::splat(f32::NAN), Vec3::ZERO, 1.0, bits), 0);
        }
    }

    #[test]
    fn keys_hold_every_index_and_a_code_beside_it() {
        for n in [1usize, 2, 3, 4, 5, 1000, 1 << 20, (1 << 20) + 1, 25_600_000, u32::MAX as usize] {
            let kf = Keys::for_count(n);
            assert!(1u128 << kf.shift >= n as u128, "{n}: {kf:?}");
            assert!(kf.shift + 3 * kf.bits <= 64 && kf.bits >= 10, "{n}: {kf:?}");
            let (code, index) = ((1u64 << (3 * kf.bits)) - 1, n - 1);
            let k = code << kf.shift | index as u64;
            assert_eq!((kf.code(k), kf.index(k)), (code, index), "{n}");
        }
    }

    #[test]
    fn a_split_separates_the_highest_differing_bit_of_the_codes() {
        let kf = Keys { shift: 8, bits: 4 };
        let keys = |codes: &[u64]| -> Vec<u64> { codes.iter().enumerate().map(|(i, &c)| c << 8 | i as u64).collect() };
        assert_eq!(split_point(&keys(&[0b0100, 0b0101, 0b0110, 0b1000, 0b1111]), kf), 3);
        assert_eq!(split_point(&keys(&[0b0100, 0b0101, 0b0110, 0b0111]), kf), 2);
        assert_eq!(split_point(&keys(&[5, 5, 5, 5, 5]), kf), 2, "equal codes: halved");
        assert_eq!(split_point(&keys(&[5, 6]), kf), 1);
        // The index below the code never decides: equal codes of different indices.
        assert_eq!(split_point(&keys(&[9, 9]), kf), 1);
    }

    /// Checks the tree over `n` primitives with boxes `prim`: the leaf order is a permutation,
    /// leaves cover it once in order with at most `MAX_LEAF` each, and every box is exactly
    /// the union of its children's or its primitives'. Returns the leaf sizes.
    fn check(n: usize, prim: &(impl Fn(usize) -> (Vec3, Vec3) + Sync)) -> Vec<u32> {
        let (nodes, order) = build(n, prim);
        let mut seen = vec![false; n];
        for &i in &order {
            assert!(!std::mem::replace(&mut seen[i as usize], true), "primitive {i} twice");
        }
        let union = |it: &mut dyn Iterator<Item = (Vec3, Vec3)>| {
            it.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
        };
        let (mut stack, mut covered, mut sizes) = (vec![0usize], 0u32, vec![]);
        while let Some(i) = stack.pop() {
            let node = nodes[i];
            if node.count > 0 {
                assert!(node.count as usize <= MAX_LEAF && node.a == covered, "leaf {i}: {node:?}");
                let prims = &order[node.a as usize..(node.a + node.count) as usize];
                assert_eq!(union(&mut prims.iter().map(|&p| prim(p as usize))), (node.lo, node.hi), "leaf {i}");
                covered += node.count;
                sizes.push(node.count);
            } else {
                let children = [node.a, node.b].map(|c| nodes[c as usize]);
                assert_eq!(union(&mut children.iter().map(|c| (c.lo, c.hi))), (node.lo, node.hi), "node {i}");
                stack.push(node.b as usize);
                stack.push(node.a as usize);
            }
        }
        assert_eq!(covered as usize, n);
        sizes
    }

    #[test]
    fn every_primitive_is_in_one_leaf_of_exact_boxes() {
        let mut u = uniform(11);
        // Clusters of every size (the parallel levels included), and sets with one point.
        let n = 3 * PARALLEL_MIN + 77;
        let centres: Vec<Vec3> = (0..n)
            .map(|i| Vec3::splat((i % 5) as f32 * 40.0) + Vec3::new(u(), u(), u()) * (1.0 + (i % 3) as f32))
            .collect();
        let sizes: Vec<Vec3> = (0..n).map(|_| Vec3::new(u(), u(), u()) * 0.3).collect();
        let sizes = check(n, &|i| (centres[i] - sizes[i], centres[i] + sizes[i]));
        // Cut in curve order at the bottom: leaves hold 3.5 primitives on average (splits at
        // the codes' bits all the way down: 2.8).
        let mean = n as f64 / sizes.len() as f64;
        assert!(mean > 3.3, "{mean:.2} primitives a leaf");
        for n in 1..=40 {
            check(n, &|i| (Vec3::splat(i as f32), Vec3::splat(i as f32 + 0.5)));
        }
        // All centroids equal (every code the same: halved down to leaves), and all in one
        // point (no extent to scale).
        for n in [5, 100, PARALLEL_MIN + 1] {
            check(n, &|i| (Vec3::splat(-(i as f32)), Vec3::splat(i as f32)));
            check(n, &|_| (Vec3::ONE, Vec3::ONE));
        }
        // Extents that overflow, and huge and tiny scales.
        check(50, &|i| {
            if i % 2 == 0 { (Vec3::splat(-3e38), Vec3::splat(-2e38)) } else { (Vec3::splat(2e38), Vec3::splat(3e38)) }
        });
        check(50, &|i| (Vec3::splat(i as f32 * 1e-38), Vec3::splat(i as f32 * 1e-38 + 1e-40)));
    }
}
