//! Collapse of the binary tree into 8-wide nodes whose child boxes are stored lane by lane,
//! so one 8-lane compare (or eight scalar ones) tests every child of a node.
use super::build::{C_TRAV, MAX_LEAF, Node2, area};

pub const WIDTH: usize = 8;

/// Child reference: an inner node index, or (top bit set) a leaf of `count` primitives
/// starting at `first` in the leaf-ordered primitive arrays.
pub const LEAF_BIT: u32 = 1 << 31;
const COUNT_SHIFT: u32 = 27;
/// Leaf-order primitive positions must fit below the count field.
pub const MAX_PRIMS: usize = 1 << COUNT_SHIFT;
pub const EMPTY: u32 = u32::MAX;

#[inline]
pub fn leaf_ref(first: u32, count: u32) -> u32 {
    LEAF_BIT | ((count - 1) << COUNT_SHIFT) | first
}

/// (first, count) of a leaf reference.
#[inline]
pub fn leaf_range(r: u32) -> (usize, usize) {
    ((r & (MAX_PRIMS as u32 - 1)) as usize, (((r >> COUNT_SHIFT) & 0xf) + 1) as usize)
}

/// One 8-wide node. `b[2 * axis]` holds the children's lower bounds on that axis and
/// `b[2 * axis + 1]` the upper ones. Unused slots have lo = +inf, hi = -inf: whatever the
/// ray direction, their entry distance is +inf and exit -inf, so they are never hit.
///
/// `perm` is the visiting order per direction octant, precomputed (Fuetterling et al. 2017,
/// as in tinybvh's BVH8_CPU): bits `3 q .. 3 q + 3` of `perm[k]` are the slot of the child at
/// position `k` for octant `q` (see [`octant`]), farthest first. Traversal pushes the hit
/// children in this order, so the nearest ends on top with no sort; it fills what was
/// alignment padding (the node stays four cache lines).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node8 {
    pub b: [[f32; WIDTH]; 6],
    pub child: [u32; WIDTH],
    pub perm: [u32; WIDTH],
}

/// Octant of a direction: bit `axis` set when that component is negative (sign bit, so -0
/// counts as negative, as in the box test's choice of planes).
#[inline(always)]
pub fn octant(d: [f32; 3]) -> u32 {
    d[0].is_sign_negative() as u32 | (d[1].is_sign_negative() as u32) << 1 | (d[2].is_sign_negative() as u32) << 2
}

impl Node8 {
    fn empty() -> Self {
        let mut b = [[f32::INFINITY; WIDTH]; 6];
        for axis in 0..3 {
            b[2 * axis + 1] = [f32::NEG_INFINITY; WIDTH];
        }
        Node8 { b, child: [EMPTY; WIDTH], perm: [0; WIDTH] }
    }

    /// Fills `perm`: for each octant, the slots sorted by how far along such a direction the
    /// child's entry corner lies (the near corner's coordinates, signed by the direction);
    /// empty slots (distance +inf) come first, i.e. are treated as farthest.
    pub fn set_order(&mut self) {
        self.perm = [0; WIDTH];
        for q in 0..8u32 {
            let key = |slot: usize| -> f32 {
                (0..3)
                    .map(|axis| {
                        let neg = q >> axis & 1 == 1;
                        let near = self.b[2 * axis + neg as usize][slot];
                        if neg { -near } else { near }
                    })
                    .sum()
            };
            let mut slots: [usize; WIDTH] = std::array::from_fn(|i| i);
            slots.sort_by(|&a, &b| key(b).total_cmp(&key(a)).then(b.cmp(&a)));
            for (k, &slot) in slots.iter().enumerate() {
                self.perm[k] |= (slot as u32) << (3 * q);
            }
        }
    }
}

pub struct Wide {
    pub nodes: Vec<Node8>,
    pub depth: usize,
    pub sah_cost: f64,
}

/// Collapses `bin` (root at 0) into 8-wide nodes: each wide node takes the children of a
/// binary node and keeps opening its largest inner child until it has eight.
pub fn collapse(bin: &[Node2]) -> Wide {
    let mut nodes = Vec::with_capacity(bin.len() / 4 + 1);
    let root_area = area(bin[0].lo, bin[0].hi).max(f32::MIN_POSITIVE) as f64;
    let mut cost = 0.0;
    let depth = if bin[0].count > 0 {
        // The whole scene is one leaf: a root with a single leaf child.
        let mut n = Node8::empty();
        set_child(&mut n, 0, &bin[0], leaf_ref(bin[0].a, bin[0].count));
        cost += C_TRAV as f64 + bin[0].count as f64;
        nodes.push(n);
        1
    } else {
        emit(bin, 0, &mut nodes, root_area, &mut cost)
    };
    nodes.iter_mut().for_each(Node8::set_order);
    Wide { nodes, depth, sah_cost: cost }
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

/// Emits the wide node for binary inner node `i`; returns the depth of its subtree.
fn emit(bin: &[Node2], i: usize, nodes: &mut Vec<Node8>, root_area: f64, cost: &mut f64) -> usize {
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
    *cost += C_TRAV as f64 * area(bin[i].lo, bin[i].hi) as f64 / root_area;
    let me = nodes.len();
    nodes.push(Node8::empty());
    let mut depth = 1;
    for (slot, &k) in kids.iter().enumerate() {
        let c = &bin[k as usize];
        let r = if c.count > 0 {
            debug_assert!(c.count as usize <= MAX_LEAF);
            *cost += c.count as f64 * area(c.lo, c.hi) as f64 / root_area;
            leaf_ref(c.a, c.count)
        } else {
            let idx = nodes.len() as u32;
            depth = depth.max(1 + emit(bin, k as usize, nodes, root_area, cost));
            idx
        };
        let mut n = nodes[me];
        set_child(&mut n, slot, c, r);
        nodes[me] = n;
    }
    depth
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For every octant the order is a permutation of the slots, from the farthest entry
    /// corner to the nearest along that octant's diagonal, empty slots first.
    #[test]
    fn order_is_far_to_near_per_octant() {
        let mut n = Node8::empty();
        let boxes = [
            ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
            ([5.0, 0.0, 0.0], [6.0, 1.0, 1.0]),
            ([0.0, 3.0, -4.0], [1.0, 4.0, -3.0]),
        ];
        for (slot, (lo, hi)) in boxes.iter().enumerate() {
            for axis in 0..3 {
                n.b[2 * axis][slot] = lo[axis];
                n.b[2 * axis + 1][slot] = hi[axis];
            }
        }
        n.set_order();
        let order = |q: u32| -> Vec<usize> { n.perm.iter().map(|p| (p >> (3 * q) & 7) as usize).collect() };
        for q in 0..8 {
            let mut seen = order(q);
            seen.sort();
            assert_eq!(seen, (0..WIDTH).collect::<Vec<_>>(), "octant {q}");
            // The five empty slots come first (farthest).
            assert!(order(q)[..5].iter().all(|&s| s >= 3), "octant {q}: {:?}", order(q));
        }
        // +x +y +z (octant 0): keys 0, 5, -1 -> far to near 1, 0, 2.
        assert_eq!(&order(0)[5..], &[1, 0, 2]);
        // -x +y +z (octant 1): keys -1, -6, -2 -> 0, 2, 1.
        assert_eq!(&order(1)[5..], &[0, 2, 1]);
        // +x +y -z (octant 4): keys -1, 4, 6 -> 2, 1, 0.
        assert_eq!(&order(4)[5..], &[2, 1, 0]);
    }
}
