//! Binned SAH build of a binary BVH into one flat node array.
//!
//! The top levels split in parallel (`rayon::join`) into disjoint ranges of one array: a
//! subtree over `n` primitives has at most `2n - 1` nodes, so the right child's range starts
//! where the left child's bound ends. The result is one preorder array with the root at 0 and
//! unused tails in the ranges: zeroed memory, mapped lazily, so they are address space, not
//! memory. They are left in place: closing them up wrote the nodes a second time into pages
//! not yet touched while the old ones were still resident (at 25.6M triangles, 370 MB more
//! at the build's peak, the peak of the whole run).
mod bins;
mod partition;
mod sampled;
mod small;

use super::binary::{C_TRAV, MAX_LEAF, Node2, PARALLEL_MIN, area, join_subtrees, node_bound};
use bins::{BINS, Bins};
use glam::{Vec3, Vec3A};
use partition::{Cut, Sides, partition_par};
use sampled::{Largest, SAMPLE, SAMPLED_MIN};
use small::{FEW, cheapest_of_few};

/// Below this many levels SAH splits are used; deeper, object-median splits bound the depth.
const SAH_MAX_DEPTH: usize = 48;

/// A set of up to [`MAX_LEAF`] triangles (one SIMD block) is split when the two halves' areas
/// sum to less than this fraction of the set's area. Measured (docs/decisions.md, "Leaf cost
/// for spread triangles"): 0.7 splits the Cornell boxes' wall blocks (CBbunny 6.08 -> 3.19 triangle tests
/// per ray, shadow stage -10-20%) and leaves the bunny's small triangles in full blocks; 0.5
/// changed nothing there.
const SMALL_SPLIT: f32 = 0.7;

/// A primitive as the builder sees it: its box and its id (triangles first, then spheres),
/// whose top bit marks a sphere (28 bytes, not 32 with a flag of its own: one of these per
/// triangle is the builder's largest array).
#[derive(Clone, Copy, Debug)]
pub struct PrimRef {
    pub lo: Vec3,
    pub hi: Vec3,
    key: u32,
}
const _: () = assert!(std::mem::size_of::<PrimRef>() == 28);

impl PrimRef {
    const SPHERE: u32 = 1 << 31;

    /// `id` is below 2^31 (a tree holds far fewer primitives).
    pub fn new(lo: Vec3, hi: Vec3, id: u32, sphere: bool) -> PrimRef {
        debug_assert!(id < Self::SPHERE);
        PrimRef { lo, hi, key: id | if sphere { Self::SPHERE } else { 0 } }
    }

    #[inline]
    pub fn id(&self) -> u32 {
        self.key & !Self::SPHERE
    }

    /// Spheres are tested one by one, outside the leaf's SIMD triangle block.
    #[inline]
    pub fn sphere(&self) -> bool {
        self.key & Self::SPHERE != 0
    }

    #[inline]
    fn centroid(&self) -> Vec3 {
        self.centroid_a().into()
    }

    #[inline]
    fn centroid_a(&self) -> Vec3A {
        0.5 * (Vec3A::from(self.lo) + Vec3A::from(self.hi))
    }
}

/// A node's box and the box of its primitives' centroids.
type Bounds = (Vec3, Vec3, Vec3, Vec3);

fn bounds(refs: &[PrimRef]) -> Bounds {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let (mut clo, mut chi) = (lo, hi);
    for r in refs {
        lo = lo.min(r.lo);
        hi = hi.max(r.hi);
        let c = r.centroid();
        clo = clo.min(c);
        chi = chi.max(c);
    }
    (lo, hi, clo, chi)
}

/// [`bounds`] over chunks in parallel (min and max are exact in any order: the same bounds).
fn bounds_par(refs: &[PrimRef]) -> Bounds {
    use rayon::prelude::*;
    let join = |a: Bounds, b: Bounds| (a.0.min(b.0), a.1.max(b.1), a.2.min(b.2), a.3.max(b.3));
    let inf = Vec3::splat(f32::INFINITY);
    refs.par_chunks(SPLIT_PAR_MIN).map(bounds).reduce(|| (inf, -inf, inf, -inf), join)
}

/// Builds the tree over `refs`, reordering them into leaf order. Only the nodes reachable
/// from the root (at 0) are the tree; the others are zero.
pub fn build(refs: &mut [PrimRef]) -> Vec<Node2> {
    let b = bounds_par(refs);
    let big = if refs.len() >= SAMPLED_MIN { Largest::of_par(refs) } else { Largest::default() };
    let mut nodes: Vec<Node2> = bytemuck::zeroed_vec(node_bound(refs.len()));
    build_into(refs, b, big, 0, 0, &mut nodes, 0);
    nodes
}

/// Builds the subtree over `refs` into `nodes` (its root in `nodes[0]`, at index `at` of the
/// whole array; child indices are absolute). `b`: the bounds of `refs` (known from the
/// parent's split, so no pass computes them). Below [`PARALLEL_MIN`] primitives the subtree
/// is written densely from the front of its range.
///
/// `big`: the largest references of `refs` when it is sampled ([`Largest`]).
fn build_into(
    refs: &mut [PrimRef],
    b: Bounds,
    big: Largest,
    base: usize,
    depth: usize,
    nodes: &mut [Node2],
    at: usize,
) {
    let mut bins = Box::new([Bins::empty(), Bins::empty()]);
    let split = if refs.len() < PARALLEL_MIN { None } else { split_sides(refs, b, depth, &mut bins, &big) };
    drop(big);
    let Some((mid, lb, rb, [lbig, rbig])) = split else {
        Seq { nodes, at, next: 0, bins: &mut bins }.build(refs, b, base, depth);
        return;
    };
    drop(bins);
    let (lo, hi, _, _) = b;
    let (l, r) = refs.split_at_mut(mid);
    join_subtrees(
        nodes,
        at,
        mid,
        |n, i| build_into(l, lb, lbig, base, depth + 1, n, i),
        |n, i| build_into(r, rb, rbig, base + mid, depth + 1, n, i),
        |_, _| (lo, hi),
    );
}

/// The sequential build of a subtree into its range of the node array: nodes are written
/// densely from the front of `nodes` (whose first is index `at` of the whole array), and
/// `bins` is the scratch every [`split`] reuses.
struct Seq<'a> {
    nodes: &'a mut [Node2],
    at: usize,
    /// The next free node of the range.
    next: usize,
    bins: &'a mut [Bins; 2],
}

impl Seq<'_> {
    /// Writes the subtree over `refs` (leaf-order places `base ..`, bounds `bnd`) at the next
    /// free node onwards; returns its root's absolute index.
    fn build(&mut self, refs: &mut [PrimRef], bnd: Bounds, base: usize, depth: usize) -> u32 {
        let (lo, hi, _, _) = bnd;
        let me = self.next;
        self.next += 1;
        self.nodes[me] = Node2 { lo, hi, a: base as u32, b: 0, count: refs.len() as u32 };
        if let Some((mid, lb, rb)) = split(refs, bnd, depth, self.bins) {
            let (l, r) = refs.split_at_mut(mid);
            let a = self.build(l, lb, base, depth + 1);
            let b = self.build(r, rb, base + mid, depth + 1);
            self.nodes[me] = Node2 { lo, hi, a, b, count: 0 };
        }
        (self.at + me) as u32
    }
}

/// Chooses a split and partitions `refs` around it: the split point and the two sides'
/// bounds; None makes a leaf.
/// `bins`: scratch, reused from split to split (see [`Bins::gather`]).
fn split(refs: &mut [PrimRef], b: Bounds, depth: usize, bins: &mut [Bins; 2]) -> Option<(usize, Bounds, Bounds)> {
    split_sides(refs, b, depth, bins, &Largest::default()).map(|(mid, l, r, _)| (mid, l, r))
}

/// [`split`] with the set's largest references `big` (binned beside a sample), and the two
/// sides' largest (kept only when the set is sampled).
fn split_sides(
    refs: &mut [PrimRef],
    b: Bounds,
    depth: usize,
    bins: &mut [Bins; 2],
    big: &Largest,
) -> Option<(usize, Bounds, Bounds, [Largest; 2])> {
    let (lo, hi, clo, chi) = b;
    let n = refs.len();
    // A leaf of up to MAX_LEAF triangles is one SIMD block: testing it costs about what a
    // single triangle does, and splitting it only adds nodes (and cache lines) to visit.
    // Spheres are not in the block: each costs a full test, so a set holding one is split by
    // the SAH below (a sphere shares a leaf only when that is cheaper).
    if n <= 1 {
        return None;
    }
    let one_block = n <= MAX_LEAF && !refs.iter().any(PrimRef::sphere);
    let ext = chi - clo;
    let axis = ext.max_position();
    let median = |refs: &mut [PrimRef]| {
        let mid = n / 2;
        refs.select_nth_unstable_by(mid, |a, b| a.centroid()[axis].total_cmp(&b.centroid()[axis]));
        let (l, r) = refs.split_at(mid);
        Some((mid, bounds(l), bounds(r), Default::default()))
    };
    if ext[axis] <= 0.0 || depth >= SAH_MAX_DEPTH {
        // All centroids coincide (or the tree is already deep): a leaf if allowed, else an
        // object-median split, which halves the count and so bounds the depth.
        if n <= MAX_LEAF {
            return None;
        }
        return median(refs);
    }
    let scale = Vec3::select(ext.cmpgt(Vec3::ZERO), Vec3::splat(BINS as f32) / ext, Vec3::ZERO);
    let sampled = n >= SAMPLED_MIN;
    let bins = (n >= FEW).then(|| {
        let [even, odd] = bins;
        if sampled {
            even.gather_sample(refs, big, clo, scale, odd);
        } else {
            even.gather(refs, clo, scale, odd);
        }
        &*even
    });
    let best = match bins {
        Some(bins) => bins.cheapest(if sampled { SAMPLE + big.refs.len() } else { n }),
        None => cheapest_of_few(refs, clo, scale),
    };
    let parent = area(lo, hi).max(f32::MIN_POSITIVE);
    let split_cost = C_TRAV + best.0 / parent;
    let leaf_cost = n as f32;
    if one_block {
        // A block is split only when its triangles are large and spread (the walls of a
        // box): the halves' boxes together must have well under the whole one's area, so
        // rays reach far fewer block tests than the one extra node slot costs.
        if best.0 / parent >= SMALL_SPLIT {
            return None;
        }
    } else if n <= MAX_LEAF && leaf_cost <= split_cost {
        return None;
    }
    if !best.0.is_finite() {
        // Every bin split left one side empty (tiny extent): fall back to the median.
        return median(refs);
    }
    let (ax, bin) = (best.1, best.2);
    let cut = Cut { ax, bin, clo, scale };
    let side = |(b, c): Sides| (b.lo.into(), b.hi.into(), c.lo.into(), c.hi.into());
    if sampled {
        // The bins saw a sample: the sides' boxes are taken by the partition.
        let (mid, l, r, big) = partition_par::<true>(refs, cut);
        return Some((mid, side(l), side(r), big));
    }
    let (mid, (_, lc), (_, rc), _) = partition_par::<false>(refs, cut);
    let Some(bins) = bins else {
        let (l, r) = refs.split_at(mid);
        return Some((mid, bounds(l), bounds(r), Default::default()));
    };
    Some((mid, side((bins.union(ax, 0..bin), lc)), side((bins.union(ax, bin..BINS), rc)), Default::default()))
}

/// Sets of at least this many primitives are partitioned (and searched for their largest
/// references) by several threads.
const SPLIT_PAR_MIN: usize = 1 << 18;

#[cfg(test)]
mod tests {
    use super::bins::{bins_of, blocks};
    use super::partition::partition;
    use super::sampled::LARGEST;
    use super::*;

    fn unit_box(at: Vec3, id: u32, sphere: bool) -> PrimRef {
        PrimRef::new(at - Vec3::splat(0.5), at + Vec3::splat(0.5), id, sphere)
    }

    /// Leaves of the binary tree, as sets of ids.
    fn leaves(nodes: &[Node2], refs: &[PrimRef]) -> Vec<Vec<u32>> {
        let mut ids: Vec<Vec<u32>> = nodes
            .iter()
            .filter(|n| n.count > 0)
            .map(|n| {
                let mut v: Vec<u32> = refs[n.a as usize..(n.a + n.count) as usize].iter().map(PrimRef::id).collect();
                v.sort();
                v
            })
            .collect();
        ids.sort();
        ids
    }

    /// Boxes scattered in clusters (so the splits are uneven and the parallel ranges'
    /// bounds leave gaps of every size).
    fn scattered(n: usize) -> Vec<PrimRef> {
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|i| {
                let cluster = Vec3::splat((i % 7) as f32 * 30.0);
                let at = cluster + Vec3::new(next(), next(), next()) * 10.0 * (1.0 + (i % 3) as f32);
                let size = Vec3::new(next(), next(), next()) * 0.5;
                PrimRef::new(at - size, at + size, i as u32, false)
            })
            .collect()
    }

    #[test]
    fn a_sampled_split_sees_every_column_of_a_grid_stored_row_by_row() {
        // Rows of `run` boxes far apart along x, as many rows as a sample takes, close together
        // along y: halving x halves the set's area, halving y does not. A sample of every
        // `run`-th reference would see one column, all in one bin on x, and split on y.
        let run = 8;
        let mut refs: Vec<PrimRef> = (0..run * SAMPLE)
            .map(|i| unit_box(Vec3::new((i % run) as f32 * 1000.0, (i / run) as f32 * 0.001, 0.0), i as u32, false))
            .collect();
        assert!(refs.len() >= SAMPLED_MIN && refs.len() / SAMPLE == run, "the sampled path, one row per run");
        let b = bounds(&refs);
        let (mid, l, r) = split(&mut refs, b, 0, &mut [Bins::empty(), Bins::empty()]).expect("a split");
        // Split between two columns: the sides apart on x, whole columns each.
        assert!(l.1.x < r.0.x, "left {:?}..{:?}, right {:?}..{:?}", l.0, l.1, r.0, r.1);
        assert_eq!(mid % SAMPLE, 0, "{mid} references on the left");
    }

    #[test]
    fn a_sampled_split_sees_the_few_largest_primitives() {
        // Tiny boxes filling a unit cube inside a room: two walls far out on x, large and
        // thin, their centroids on the cube's floor (y = 0). Binning everything puts the walls
        // with the cube's lowest slice on y (a y split just above them: the walls' huge box
        // over few primitives); a sample alone almost never holds a wall, sees a cube, and
        // splits it in the middle, leaving half the cube inside the walls' box.
        let mut u = uniform(5);
        let n = SAMPLED_MIN + 1000;
        let mut refs: Vec<PrimRef> = (0..n)
            .map(|i| {
                let at = Vec3::new(u(), u(), u());
                PrimRef::new(at, at + 0.001, i as u32, false)
            })
            .collect();
        for (k, x) in [-100.0f32, 100.0].into_iter().enumerate() {
            refs[1000 + 77_777 * k] =
                PrimRef::new(Vec3::new(x, -100.0, -100.0), Vec3::new(x + 1.0, 100.0, 100.0), 7, false);
        }
        let b = bounds(&refs);
        let big = Largest::of_par(&refs);
        assert_eq!(big.refs.iter().filter(|(a, _)| *a > 1e4).count(), 2, "both walls among the largest");
        let mut bins = [Bins::empty(), Bins::empty()];
        let (mid, l, r, [lbig, rbig]) = split_sides(&mut refs, b, 0, &mut bins, &big).expect("a split");
        let walls_left = refs[..mid].iter().filter(|r| r.hi.y - r.lo.y > 100.0).count();
        assert_eq!(walls_left, 2, "the walls go left with the lowest slice: {l:?} {r:?}");
        assert!(mid < n / 8, "{mid} of {n} references with the walls");
        // Each side keeps its own largest: the walls on the left.
        assert_eq!(lbig.refs.iter().filter(|(a, _)| *a > 1e4).count(), 2);
        assert!(rbig.refs.len() == LARGEST && rbig.refs.iter().all(|(a, _)| *a < 1.0));
    }

    #[test]
    fn the_parallel_build_lays_out_the_tree_the_sequential_one_does() {
        // Large enough for the top splits to bin and partition in parallel too.
        let n = 2 * SPLIT_PAR_MIN + 20 * PARALLEL_MIN + 123;
        let (mut par, mut seq) = (scattered(n), scattered(n));
        let nodes = build(&mut par);
        // The reference: the whole tree built on one thread, densely from the front.
        let mut reference: Vec<Node2> = bytemuck::zeroed_vec(node_bound(n));
        let b = bounds(&seq);
        let mut bins = [Bins::empty(), Bins::empty()];
        let used = {
            let mut one = Seq { nodes: &mut reference, at: 0, next: 0, bins: &mut bins };
            one.build(&mut seq, b, 0, 0);
            one.next
        };
        // Both walked from the root: the same nodes (boxes, leaf ranges, the same primitives
        // in each leaf: a parallel partition orders each side its own way); leaves covering
        // the references once, in order; a left child right after its parent; every node's
        // box exactly the union of its children's or its primitives' (the top splits, which
        // bin a sample, take the sides' boxes in the partition).
        let ids = |refs: &[PrimRef], node: &Node2| {
            let mut v: Vec<u32> =
                refs[node.a as usize..(node.a + node.count) as usize].iter().map(PrimRef::id).collect();
            v.sort();
            v
        };
        let (mut stack, mut covered, mut reached) = (vec![(0usize, 0usize)], 0, 0);
        while let Some((i, j)) = stack.pop() {
            let (node, other) = (nodes[i], reference[j]);
            reached += 1;
            assert_eq!((node.lo, node.hi, node.count), (other.lo, other.hi, other.count), "node {i}");
            let union = |boxes: &mut dyn Iterator<Item = (Vec3, Vec3)>| {
                boxes.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
            };
            if node.count > 0 {
                assert_eq!((node.a, ids(&par, &node)), (covered, ids(&seq, &other)));
                covered += node.count;
                let prims = &par[node.a as usize..(node.a + node.count) as usize];
                assert_eq!(union(&mut prims.iter().map(|r| (r.lo, r.hi))), (node.lo, node.hi), "leaf {i}");
            } else {
                assert_eq!(node.a as usize, i + 1);
                assert!(node.b as usize > i + 1 && (node.b as usize) < nodes.len());
                let children = [node.a, node.b].map(|c| nodes[c as usize]);
                assert_eq!(union(&mut children.iter().map(|c| (c.lo, c.hi))), (node.lo, node.hi), "node {i}");
                stack.push((node.b as usize, other.b as usize));
                stack.push((node.a as usize, other.a as usize));
            }
        }
        assert_eq!((covered as usize, reached), (n, used));
        assert!(used > n / MAX_LEAF, "{used} nodes");
    }

    /// Uniform numbers in [0, 1) from a seed (a linear congruential generator).
    fn uniform(seed: u64) -> impl FnMut() -> f32 {
        let mut x = seed;
        move || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// The builder's binning frame of `refs` and their bins: centroid lower corner and scale.
    fn binned(refs: &[PrimRef]) -> (Vec3, Vec3, Bins) {
        let (_, _, clo, chi) = bounds(refs);
        let ext = chi - clo;
        let scale = Vec3::select(ext.cmpgt(Vec3::ZERO), Vec3::splat(BINS as f32) / ext, Vec3::ZERO);
        let (mut bins, mut odd) = (Bins::empty(), Bins::empty());
        bins.gather(refs, clo, scale, &mut odd);
        (clo, scale, bins)
    }

    #[test]
    fn the_partition_puts_each_reference_on_the_side_of_its_bin() {
        // Random boxes, and points whose centroids differ along x by the smallest float:
        // a scale so large it is infinite, and `0 * inf` (the lowest centroid) is NaN, which
        // the bins count in bin 0.
        let mut next = uniform(11);
        let random: Vec<PrimRef> =
            (0..500).map(|i| unit_box(Vec3::new(next(), next(), next()) * 10.0, i, false)).collect();
        let tiny: Vec<PrimRef> = (0..40)
            .map(|i| {
                let at = Vec3::new(f32::from_bits(i % 2), 1.0, 2.0);
                PrimRef::new(at, at, i, false)
            })
            .collect();
        let ids = |refs: &[PrimRef]| {
            let mut v: Vec<u32> = refs.iter().map(PrimRef::id).collect();
            v.sort();
            v
        };
        assert_eq!(binned(&tiny).1.x, f32::INFINITY, "the points' scale along x is infinite");
        for set in [random, tiny] {
            let (clo, scale, bins) = binned(&set);
            for ax in 0..3 {
                for bin in 1..BINS {
                    let (clo_a, scale_a) = (Vec3A::from(clo), Vec3A::from(scale));
                    let left: Vec<PrimRef> =
                        set.iter().filter(|r| bins_of(r.centroid_a(), clo_a, scale_a)[ax] < bin).copied().collect();
                    let mut refs = set.clone();
                    let (mid, (lb, lc), _, _) = partition::<true>(&mut refs, Cut { ax, bin, clo, scale });
                    assert_eq!(ids(&refs[..mid]), ids(&left), "axis {ax}, bin {bin}");
                    if mid > 0 {
                        // The side's box is its bins' box, as the bins of all the references give it.
                        let b = bins.union(ax, 0..bin);
                        assert_eq!((lb.lo, lb.hi), (b.lo, b.hi), "axis {ax}, bin {bin}");
                        assert!(
                            left.iter().all(|r| lc.lo.cmple(r.centroid_a()).all() && lc.hi.cmpge(r.centroid_a()).all())
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn few_primitives_choose_the_split_the_bins_choose() {
        let mut next = uniform(7);
        let mut splits = 0;
        for case in 0..20_000 {
            let n = 2 + case % (FEW - 2);
            // Coordinates on a coarse grid half the time: equal centroids, flat axes, ties.
            let grid = case % 2 == 0;
            let refs: Vec<PrimRef> = (0..n)
                .map(|i| {
                    let at = Vec3::new(next(), next(), next()) * 10.0;
                    let at = if grid { (at * 0.4).floor() } else { at };
                    let size = Vec3::new(next(), next(), next()) * if case % 3 == 0 { 0.0 } else { 2.0 };
                    PrimRef::new(at - size, at + size, i as u32, false)
                })
                .collect();
            let (clo, scale, bins) = binned(&refs);
            let binned = bins.cheapest(n);
            let few = cheapest_of_few(&refs, clo, scale);
            assert_eq!(few.0.to_bits(), binned.0.to_bits(), "case {case}: {few:?} vs {binned:?}");
            if binned.0.is_finite() {
                assert_eq!((few.1, few.2), (binned.1, binned.2), "case {case}");
                splits += 1;
            }
        }
        assert!(splits > 10_000, "{splits}");
    }

    /// The sweep over every bin position (each empty bin's too), as the reference for the
    /// sweep that visits occupied bins only.
    fn cheapest_every_bin(bins: &Bins, n: usize) -> (f32, usize, usize) {
        let mut best = (f32::INFINITY, 0usize, 0usize);
        for ax in 0..3 {
            for at in 1..BINS {
                let (l, r) = (bins.union(ax, 0..at), bins.union(ax, at..BINS));
                let c: u32 = bins.cnt[ax][..at].iter().sum();
                if c == 0 || c as usize == n {
                    continue;
                }
                let cost = l.area() * blocks(c) + r.area() * blocks(n as u32 - c);
                if cost < best.0 {
                    best = (cost, ax, at);
                }
            }
        }
        best
    }

    #[test]
    fn the_sweep_over_occupied_bins_chooses_what_every_bin_position_would() {
        let mut next = uniform(11);
        let mut splits = 0;
        for case in 0..4_000 {
            let n = FEW + case % 60;
            // Clustered centroids leave most bins empty; a coarse grid gives equal costs.
            let clusters: Vec<Vec3> = (0..1 + case % 4).map(|_| Vec3::new(next(), next(), next()) * 10.0).collect();
            let refs: Vec<PrimRef> = (0..n)
                .map(|i| {
                    let at = clusters[i % clusters.len()] + Vec3::new(next(), next(), next()) * 0.3;
                    let at = if case % 2 == 0 { (at * 2.0).floor() } else { at };
                    let size = Vec3::new(next(), next(), next()) * if case % 3 == 0 { 0.0 } else { 2.0 };
                    PrimRef::new(at - size, at + size, i as u32, false)
                })
                .collect();
            let (_, _, bins) = binned(&refs);
            let (got, want) = (bins.cheapest(n), cheapest_every_bin(&bins, n));
            assert_eq!(got.0.to_bits(), want.0.to_bits(), "case {case}: {got:?} vs {want:?}");
            if want.0.is_finite() {
                assert_eq!((got.1, got.2), (want.1, want.2), "case {case}");
                splits += 1;
            }
        }
        assert!(splits > 3_000, "{splits}");
    }

    #[test]
    fn close_triangles_make_one_leaf_but_distant_ones_and_spheres_are_split_off() {
        // Four touching boxes: the best split's halves cover 22/24 of the whole one's area.
        let near = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let mut tris: Vec<PrimRef> = near.iter().enumerate().map(|(i, &p)| unit_box(p, i as u32, false)).collect();
        let nodes = build(&mut tris);
        assert_eq!(leaves(&nodes, &tris), vec![vec![0, 1, 2, 3]]);
        // Four far apart (large spread triangles, as the walls of a box): split.
        let at = [Vec3::ZERO, Vec3::X * 10.0, Vec3::Y * 10.0, Vec3::Z * 10.0];
        let mut tris: Vec<PrimRef> = at.iter().enumerate().map(|(i, &p)| unit_box(p, i as u32, false)).collect();
        let nodes = build(&mut tris);
        let l = leaves(&nodes, &tris);
        assert!(l.len() > 1 && l.iter().map(Vec::len).sum::<usize>() == 4, "{l:?}");
        // Two of the four are spheres: each full sphere test is paid only by rays that reach
        // its own box.
        let mut mixed: Vec<PrimRef> = at.iter().enumerate().map(|(i, &p)| unit_box(p, i as u32, i >= 2)).collect();
        let nodes = build(&mut mixed);
        let l = leaves(&nodes, &mixed);
        assert!(l.iter().all(|leaf| !(leaf.contains(&2) && leaf.contains(&3))), "{l:?}");
        assert_eq!(l.iter().map(Vec::len).sum::<usize>(), 4);
    }
}
