//! The binary tree every builder makes (the SAH build and the Morton build alike), and the
//! one way both lay it out in memory, so the collapse, the leaf store and every traversal
//! are shared whatever built the tree.
use glam::Vec3;

/// Most primitives in one leaf (the wide leaves keep this bound).
pub const MAX_LEAF: usize = 4;
/// Subtrees with fewer primitives are built on the current thread.
pub const PARALLEL_MIN: usize = 4096;
/// Cost of a node visit relative to one primitive test.
pub const C_TRAV: f32 = 1.0;

/// A binary node: leaf when `count > 0` (prims `a .. a + count` of the reordered refs),
/// else inner with children `a` and `b`.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Node2 {
    pub lo: Vec3,
    pub hi: Vec3,
    pub a: u32,
    pub b: u32,
    pub count: u32,
}

pub fn area(lo: Vec3, hi: Vec3) -> f32 {
    let d = (hi - lo).max(Vec3::ZERO);
    2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
}

/// Most binary nodes over `n` primitives (every leaf holds one or more).
pub fn node_bound(n: usize) -> usize {
    2 * n.max(1) - 1
}

/// Builds a node's two subtrees in parallel into their ranges of `nodes` (the node at
/// `nodes[0]`, index `at` of the whole array; the left subtree, over `mid` primitives, from
/// `at + 1`, the right one after the left's [`node_bound`]): `left` and `right` get their
/// range and its absolute index. Then writes the node with the box `boxed` makes of the two
/// results, and returns that box.
pub fn join_subtrees<A: Send, B: Send>(
    nodes: &mut [Node2],
    at: usize,
    mid: usize,
    left: impl FnOnce(&mut [Node2], usize) -> A + Send,
    right: impl FnOnce(&mut [Node2], usize) -> B + Send,
    boxed: impl FnOnce(&A, &B) -> (Vec3, Vec3),
) -> (Vec3, Vec3) {
    let right_at = at + 1 + node_bound(mid);
    let (me, rest) = nodes.split_first_mut().expect("a subtree has a node");
    let (left_nodes, right_nodes) = rest.split_at_mut(node_bound(mid));
    let (a, b) = rayon::join(|| left(left_nodes, at + 1), || right(right_nodes, right_at));
    let (lo, hi) = boxed(&a, &b);
    *me = Node2 { lo, hi, a: at as u32 + 1, b: right_at as u32, count: 0 };
    (lo, hi)
}
