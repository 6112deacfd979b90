//! The tree's inner nodes: eight children each, their boxes stored lane by lane (SoA), so one
//! 8-lane compare (or eight scalar ones) tests every child of a node; and the child
//! references that point at inner nodes or leaves.

pub const WIDTH: usize = 8;

/// Child reference: an inner node index, or (top bit set) a leaf of `count` primitives at
/// `first`: the builder's position of its first primitive until the leaves are stored, then
/// the leaf's place in the leaf store.
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
    pub fn empty() -> Self {
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
            // Keys once per slot, not per comparison: the signed near rows added lane-wise.
            let row = |axis: usize| {
                let neg = q >> axis & 1 == 1;
                let near = self.b[2 * axis + neg as usize];
                if neg { near.map(|v| -v) } else { near }
            };
            let (x, y, z) = (row(0), row(1), row(2));
            // Each slot's place is how many slots come before it (farther, or as far and
            // later): 64 branch-free comparisons instead of a sort per octant, which was a
            // twentieth of the build. The keys as integers ordered as `f32::total_cmp`.
            let key: [i32; WIDTH] = std::array::from_fn(|slot| {
                let bits = (x[slot] + y[slot] + z[slot]).to_bits() as i32;
                bits ^ (((bits >> 31) as u32) >> 1) as i32
            });
            for a in 0..WIDTH {
                let ka = key[a];
                let place: usize =
                    key.iter().enumerate().map(|(b, &kb)| ((kb > ka) | ((kb == ka) & (b > a))) as usize).sum();
                self.perm[place] |= (a as u32) << (3 * q);
            }
        }
    }
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
