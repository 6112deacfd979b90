//! Collapse of the binary tree into 8-wide nodes whose child boxes are stored lane by lane,
//! so one 8-lane compare (or eight scalar ones) tests every child of a node.
use super::binary::{C_TRAV, MAX_LEAF, Node2, area};
use crate::accel::bvh::tree::{Node8, WIDTH, leaf_ref};
use rayon::prelude::*;

pub struct Wide {
    pub nodes: Vec<Node8>,
    pub depth: usize,
    pub sah_cost: f64,
}

/// Collapses `bin` (root at 0) into 8-wide nodes: each wide node takes the descendants of a
/// binary node that fill its eight slots at least SAH cost ([`Plan`]).
pub fn collapse(bin: &[Node2]) -> Wide {
    let root_area = area(bin[0].lo, bin[0].hi).max(f32::MIN_POSITIVE) as f64;
    if bin[0].count > 0 {
        // The whole scene is one leaf: a root with a single leaf child.
        let mut n = Node8::empty();
        set_child(&mut n, 0, &bin[0], leaf_ref(bin[0].a, bin[0].count));
        n.set_order();
        return Wide { nodes: vec![n], depth: 1, sah_cost: C_TRAV as f64 + bin[0].count as f64 };
    }
    let plan = Plan::new(bin, root_area);
    // Every node's place is known from the plan's counts, so subtrees are emitted in
    // parallel into their own ranges of one array, itself filled in parallel (emitting
    // on one thread, page faults included, took 0.3-0.5 s at 25.6M triangles).
    let mut nodes: Vec<Node8> = (0..plan.wide[0]).into_par_iter().map(|_| Node8::empty()).collect();
    let (depth, sah_cost) = emit(bin, &plan, 0, &mut nodes, 0, root_area);
    Wide { nodes, depth, sah_cost }
}

fn set_child(n: &mut Node8, slot: usize, c: &Node2, r: u32) {
    for axis in 0..3 {
        n.b[2 * axis][slot] = widen(c.lo[axis], -1.0);
        n.b[2 * axis + 1][slot] = widen(c.hi[axis], 1.0);
    }
    n.child[slot] = r;
}

/// Moves a box bound outward (`side` -1 for lower, +1 for upper) by an ulp and a tiny
/// absolute amount, so every vertex lies strictly inside its leaf's box. A ray parallel to
/// an axis and lying in the plane of a box face (an axis-parallel ray through a shared vertex
/// or along an edge) otherwise gets a zero slab distance, `(plane - origin) * inv = 0`, for
/// that face: the unfused slab test then rejects the box while the watertight triangle test
/// hits its corner, and the fused form (which shifts its terms outward) accepts it, so the
/// instruction sets found different triangles at such ties. With the margin the distance is
/// at least 1e-30 times the reciprocal (`f32::MAX` for a zero component): beyond any hit.
fn widen(x: f32, side: f32) -> f32 {
    if x.is_finite() { x + side * (x.abs() * f32::EPSILON + 1e-30) } else { x }
}

/// For each binary node, how its subtree fills `k` slots of a wide node at least cost
/// (Ylitie et al. 2017, "Efficient incoherent ray traversal on GPUs through compressed wide
/// BVHs", section 3.1, without leaf merging: our leaves are already one SIMD block each).
/// A subtree in one slot costs a leaf test, or a wide node visit plus its own children's best
/// spread over eight slots, weighted by its area; in `k` slots it either stays in one or
/// splits its slots between its two children. The greedy collapse opens the largest child
/// until the node is full; this picks which to open by what the whole subtree costs.
struct Plan {
    /// What the plan expects the whole tree to cost (the root as a wide node): the tests
    /// check it against the SAH of the tree it emits.
    #[cfg_attr(not(test), allow(dead_code))]
    root_cost: f64,
    /// `left[n][k - 1]`: slots given to the left child in that best spread (0: one slot).
    left: Vec<[u8; WIDTH]>,
    /// Slots given to the left child when inner node `n` becomes a wide node (its children
    /// spread over all eight slots; at least one, so the 0 of a node never planned reads as 1).
    /// The tables start as zeroed memory, mapped lazily: the binary array's unused ranges
    /// (see the builder) cost them nothing either.
    open: Vec<u8>,
    /// Wide nodes in the subtree of inner node `n` when it becomes a wide node (itself
    /// included): where each subtree goes in the wide array, before any is emitted.
    wide: Vec<u32>,
}

/// SAH cost of visiting a wide node, relative to a leaf block test. The leaves are fixed
/// by the binary build, so plans differ only in the total area of the nodes they keep: this
/// weight scales the cost but does not change the plan (0.5, 1 and 2 give the same tree).
const C_NODE: f64 = 1.0;

impl Plan {
    fn new(bin: &[Node2], root_area: f64) -> Plan {
        let mut left = vec![[0u8; WIDTH]; bin.len()];
        let mut open = vec![0u8; bin.len()];
        let mut wide = vec![0u32; bin.len()];
        let (cost, _) = plan_subtree(bin, 0, Tables { left: &mut left, open: &mut open, wide: &mut wide }, root_area);
        Plan { root_cost: cost[0], left, open, wide }
    }

    /// The binary nodes that fill the slots of the wide node made from inner node `n` (the
    /// first `.1` of the array).
    fn children(&self, bin: &[Node2], n: usize) -> ([u32; WIDTH], usize) {
        let (l, r, j) = (bin[n].a as usize, bin[n].b as usize, self.open[n].max(1) as usize);
        let mut out = ([0; WIDTH], 0);
        self.fill(bin, l, j, &mut out);
        self.fill(bin, r, WIDTH - j, &mut out);
        out
    }

    fn fill(&self, bin: &[Node2], n: usize, k: usize, out: &mut ([u32; WIDTH], usize)) {
        let j = if bin[n].count > 0 || k < 2 { 0 } else { self.left[n][k - 1] as usize };
        if j == 0 {
            out.0[out.1] = n as u32;
            out.1 += 1;
        } else {
            self.fill(bin, bin[n].a as usize, j, out);
            self.fill(bin, bin[n].b as usize, k - j, out);
        }
    }
}

/// Binary nodes from which [`plan_subtree`] plans the two children in parallel.
const PARALLEL_PLAN: usize = 1 << 14;

/// A subtree's own entries of the plan's tables (`[0]` is its root's).
struct Tables<'a> {
    left: &'a mut [[u8; WIDTH]],
    open: &'a mut [u8],
    wide: &'a mut [u32],
}

impl<'a> Tables<'a> {
    /// The root's entries, and the tables of the two child subtrees (the left one's
    /// `len` entries first).
    #[allow(clippy::type_complexity)]
    fn split(self, len: usize) -> ((&'a mut [u8; WIDTH], &'a mut u8, &'a mut u32), Tables<'a>, Tables<'a>) {
        let (own_left, left) = self.left.split_first_mut().expect("a subtree has a root");
        let (own_open, open) = self.open.split_first_mut().expect("a subtree has a root");
        let (own_wide, wide) = self.wide.split_first_mut().expect("a subtree has a root");
        let (ll, lr) = left.split_at_mut(len);
        let (ol, or) = open.split_at_mut(len);
        let (wl, wr) = wide.split_at_mut(len);
        (
            (own_left, own_open, own_wide),
            Tables { left: ll, open: ol, wide: wl },
            Tables { left: lr, open: or, wide: wr },
        )
    }
}

/// `cost[k - 1]`: the least SAH cost of subtree `n` in at most `k` slots, and `count[k - 1]`
/// the wide nodes it then makes; fills the plan of every node of the subtree. Both build
/// paths store a subtree contiguously in preorder (`n`, then the left child's subtree, then
/// the right child's), so the tables' entries are the subtree's own (`[0]` is `n`'s) and
/// split into the children's without overlap: the children are planned in parallel, and
/// only one cost row per level of the recursion is ever held (the table of every node's
/// costs took 64 bytes a node).
fn plan_subtree(bin: &[Node2], n: usize, t: Tables, root_area: f64) -> ([f64; WIDTH], [u32; WIDTH]) {
    let node = &bin[n];
    let a = area(node.lo, node.hi) as f64 / root_area;
    if node.count > 0 {
        return ([a; WIDTH], [0; WIDTH]);
    }
    let (l, r) = (node.a as usize, node.b as usize);
    debug_assert!(l == n + 1 && r > l && r - n < t.left.len());
    let size = t.left.len();
    let ((own_left, own_open, own_wide), tl, tr) = t.split(r - l);
    let ((cl, nl), (cr, nr)) = if size >= PARALLEL_PLAN {
        rayon::join(|| plan_subtree(bin, l, tl, root_area), || plan_subtree(bin, r, tr, root_area))
    } else {
        (plan_subtree(bin, l, tl, root_area), plan_subtree(bin, r, tr, root_area))
    };
    // Best spread of the two children over `k` slots (k >= 2).
    let spread = |k: usize| -> (f64, u8) {
        (1..k)
            .map(|j| (cl[j - 1] + cr[k - j - 1], j as u8))
            .fold((f64::INFINITY, 0), |b, c| if c.0 < b.0 { c } else { b })
    };
    let (full, j8) = spread(WIDTH);
    let one = C_NODE * a + full;
    let j8 = j8.max(1) as usize;
    *own_open = j8 as u8;
    *own_wide = 1 + nl[j8 - 1] + nr[WIDTH - j8 - 1];
    let (mut c, mut d, mut w) = ([one; WIDTH], [0u8; WIDTH], [*own_wide; WIDTH]);
    for k in 2..=WIDTH {
        let (s, j) = spread(k);
        if s < one {
            let j = j as usize;
            (c[k - 1], d[k - 1], w[k - 1]) = (s, j as u8, nl[j - 1] + nr[k - j - 1]);
        }
    }
    *own_left = d;
    (c, w)
}

/// Wide nodes from which [`emit`] emits a node's subtrees in parallel.
const PARALLEL_EMIT: u32 = 1 << 12;

/// Emits the wide node for binary inner node `i` and its subtree into `nodes` (exactly its
/// `plan.wide[i]` nodes, in preorder; `at` is the index of `nodes[0]` in the whole array);
/// returns the subtree's depth and SAH cost (its children's, added in slot order).
fn emit(bin: &[Node2], plan: &Plan, i: usize, nodes: &mut [Node8], at: usize, root_area: f64) -> (usize, f64) {
    debug_assert_eq!(nodes.len(), plan.wide[i] as usize);
    let (kids, count) = plan.children(bin, i);
    let (me, mut rest) = nodes.split_first_mut().expect("a wide node");
    let mut cost = C_TRAV as f64 * area(bin[i].lo, bin[i].hi) as f64 / root_area;
    // The inner children's subtrees, each with its range of the array (in an array, not a
    // vector: no allocation per wide node).
    let mut subtrees: [Option<(usize, &mut [Node8], usize)>; WIDTH] = Default::default();
    let mut next = at + 1;
    for (slot, &k) in kids[..count].iter().enumerate() {
        let c = &bin[k as usize];
        let r = if c.count > 0 {
            debug_assert!(c.count as usize <= MAX_LEAF);
            cost += c.count as f64 * area(c.lo, c.hi) as f64 / root_area;
            leaf_ref(c.a, c.count)
        } else {
            let len = plan.wide[k as usize] as usize;
            let (sub, more) = std::mem::take(&mut rest).split_at_mut(len);
            rest = more;
            subtrees[slot] = Some((k as usize, sub, next));
            next += len;
            (next - len) as u32
        };
        set_child(me, slot, c, r);
    }
    me.set_order();
    let run = |(k, sub, at): (usize, &mut [Node8], usize)| emit(bin, plan, k, sub, at, root_area);
    // The children's costs are added in slot order on both paths (the same sum).
    let add = |(depth, cost): (usize, f64), (d, c): (usize, f64)| (depth.max(1 + d), cost + c);
    if plan.wide[i] >= PARALLEL_EMIT {
        let done: Vec<(usize, f64)> = subtrees.into_par_iter().flatten().map(run).collect();
        done.into_iter().fold((1, cost), add)
    } else {
        subtrees.into_iter().flatten().map(run).fold((1, cost), add)
    }
}

#[cfg(test)]
mod tests {
    use super::super::sah::{PrimRef, build};
    use super::*;
    use crate::accel::bvh::tree::{LEAF_BIT, leaf_range};
    use glam::Vec3;

    /// The children of binary node `i`, opening the largest inner one until there are eight.
    fn greedy_children(bin: &[Node2], i: usize) -> Vec<u32> {
        let mut kids: Vec<u32> = vec![bin[i].a, bin[i].b];
        while kids.len() < WIDTH {
            let open = kids
                .iter()
                .enumerate()
                .filter(|(_, k)| bin[**k as usize].count == 0)
                .max_by(|a, b| {
                    let (na, nb) = (&bin[*a.1 as usize], &bin[*b.1 as usize]);
                    area(na.lo, na.hi).total_cmp(&area(nb.lo, nb.hi))
                })
                .map(|(j, _)| j);
            let Some(j) = open else { break };
            let k = kids.swap_remove(j) as usize;
            kids.push(bin[k].a);
            kids.push(bin[k].b);
        }
        kids
    }

    /// The greedy collapse (largest inner child opened first) as a reference: wide nodes as
    /// lists of binary nodes, depth first.
    fn greedy(bin: &[Node2], i: usize, out: &mut Vec<Vec<u32>>) {
        let kids = greedy_children(bin, i);
        out.push(kids.clone());
        for k in kids {
            if bin[k as usize].count == 0 {
                greedy(bin, k as usize, out);
            }
        }
    }

    /// SAH cost of a wide tree given as lists of binary nodes: a node visit per wide node
    /// (its box: the binary node it was made from, i.e. the union of its slots), a block test
    /// per leaf, weighted by area.
    fn sah(bin: &[Node2], wide: &[Vec<u32>]) -> f64 {
        let a = |n: &Node2| area(n.lo, n.hi) as f64 / area(bin[0].lo, bin[0].hi) as f64;
        let union = |kids: &[u32]| {
            let (lo, hi) = kids.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &k| {
                (lo.min(bin[k as usize].lo), hi.max(bin[k as usize].hi))
            });
            Node2 { lo, hi, a: 0, b: 0, count: 0 }
        };
        wide.iter()
            .map(|kids| {
                C_NODE * a(&union(kids))
                    + kids.iter().filter(|&&k| bin[k as usize].count > 0).map(|&k| a(&bin[k as usize])).sum::<f64>()
            })
            .sum()
    }

    /// The planned wide nodes, depth first.
    fn planned(bin: &[Node2], plan: &Plan, i: usize, out: &mut Vec<Vec<u32>>) {
        let (kids, count) = plan.children(bin, i);
        let kids = kids[..count].to_vec();
        out.push(kids.clone());
        for k in kids {
            if bin[k as usize].count == 0 {
                planned(bin, plan, k as usize, out);
            }
        }
    }

    /// On random scenes (clustered and uniform boxes of mixed sizes), the planned collapse
    /// keeps every leaf exactly once, fills at most eight slots per node, reports its own SAH
    /// cost exactly, and never costs more than the greedy one.
    #[test]
    fn planned_collapse_beats_greedy() {
        let mut h = 0x9e37_79b9u32;
        let mut rnd = move || {
            h = h.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            (h >> 8) as f32 / (1 << 24) as f32
        };
        let mut better = 0;
        // The last scene is large enough for subtrees to be emitted in parallel.
        for scene in 0..13 {
            let n = if scene == 12 { 150_000 } else { [50, 300, 2000][scene % 3] };
            let mut refs: Vec<PrimRef> = (0..n)
                .map(|id| {
                    let cluster = if scene % 2 == 0 { (rnd() * 5.0).floor() * 10.0 } else { 0.0 };
                    let c = Vec3::new(rnd() * 20.0 + cluster, rnd() * 3.0, rnd() * 20.0);
                    let half = Vec3::new(rnd(), rnd(), rnd()) * if rnd() < 0.1 { 3.0 } else { 0.2 };
                    PrimRef::new(c - half, c + half, id as u32, false)
                })
                .collect();
            let bin = build(&mut refs);
            let root_area = area(bin[0].lo, bin[0].hi) as f64;
            let plan = Plan::new(&bin, root_area);
            let (mut p, mut g) = (Vec::new(), Vec::new());
            planned(&bin, &plan, 0, &mut p);
            greedy(&bin, 0, &mut g);
            let leaves = |w: &[Vec<u32>]| {
                let mut l: Vec<u32> = w.iter().flatten().copied().filter(|&k| bin[k as usize].count > 0).collect();
                l.sort();
                l
            };
            let all: Vec<u32> = (0..bin.len() as u32).filter(|&k| bin[k as usize].count > 0).collect();
            assert_eq!(leaves(&p), all, "scene {scene}: planned leaves");
            assert_eq!(leaves(&g), all, "scene {scene}: greedy leaves");
            assert!(p.iter().all(|k| (2..=WIDTH).contains(&k.len())), "scene {scene}");
            let (sp, sg) = (sah(&bin, &p), sah(&bin, &g));
            // The root in one slot: its own node plus its subtree's best spread.
            let own = plan.root_cost;
            assert!((own - sp).abs() <= 1e-9 * sp, "scene {scene}: plan says {own}, its tree costs {sp}");
            assert!(sp <= sg * (1.0 + 1e-9), "scene {scene}: planned {sp} > greedy {sg}");
            better += (sp < sg * (1.0 - 1e-6)) as usize;
            // The emitted array is the planned nodes in that order: each inner child points
            // at the node made from its binary node, with nothing left over.
            let w = collapse(&bin);
            assert!(scene < 12 || w.nodes.len() > 2 * PARALLEL_EMIT as usize, "{}", w.nodes.len());
            assert_eq!((w.nodes.len(), plan.wide[0] as usize), (p.len(), p.len()), "scene {scene}");
            let ra = |n: &Node2| area(n.lo, n.hi) as f64 / root_area;
            let mut want_cost = 0.0;
            let mut seen = vec![false; p.len()];
            let mut stack = vec![(0usize, 0u32)];
            while let Some((j, b)) = stack.pop() {
                assert!(!seen[j], "scene {scene}: node {j} reached twice");
                seen[j] = true;
                let (kids, count) = plan.children(&bin, b as usize);
                assert_eq!(&kids[..count], &p[j][..], "scene {scene}: node {j}");
                want_cost += C_TRAV as f64 * ra(&bin[b as usize]);
                for (slot, &k) in kids[..count].iter().enumerate() {
                    let r = w.nodes[j].child[slot];
                    if bin[k as usize].count == 0 {
                        assert!(r & LEAF_BIT == 0 && (r as usize) > j, "scene {scene}: node {j} slot {slot}");
                        stack.push((r as usize, k));
                    } else {
                        assert_eq!(leaf_range(r), (bin[k as usize].a as usize, bin[k as usize].count as usize));
                        want_cost += bin[k as usize].count as f64 * ra(&bin[k as usize]);
                    }
                }
            }
            assert!(seen.iter().all(|&s| s), "scene {scene}: an emitted node no parent points at");
            assert!((w.sah_cost - want_cost).abs() <= 1e-9 * want_cost, "scene {scene}: {} vs {want_cost}", w.sah_cost);
        }
        assert!(better > 0, "the plan never found a cheaper tree than the greedy collapse");
    }
}
