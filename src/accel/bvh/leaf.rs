//! Leaf storage for the SIMD triangle filter: every leaf is one block of at most four
//! primitives stored lane by lane, so leaf `first / 4` is block `first / 4`.
//!
//! The SIMD kernels only *reject* triangles, with exactly the operations (same operands, same
//! order, no fused multiply-add) of the scalar watertight test; any lane they cannot reject
//! (a hit candidate, an edge function that is exactly zero, a sphere) goes through the scalar
//! test. So every path reports bit-identical hits, and the scalar test stays the reference.
use super::wide::{EMPTY, LEAF_BIT, MAX_PRIMS, Node8, leaf_range, leaf_ref};
use crate::scene::Scene;
use glam::Vec3;

/// Primitives per block (one SSE register per coordinate).
pub const LANES: usize = 4;

/// Four primitives: triangle corners `c[corner][axis][lane]`, the lanes that hold triangles
/// (the others are spheres or padding) and each lane's scene primitive id, in what would
/// otherwise be alignment padding: a block is the whole leaf (192 bytes, three cache lines),
/// so the mesh's corners are not kept a second time anywhere in the tree.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub struct Tri4 {
    pub c: [[[f32; LANES]; 3]; 3],
    pub tri_lanes: u32,
    /// Scene primitive id of each lane (triangles first, then spheres; padding `u32::MAX`).
    pub ids: [u32; LANES],
}
const _: () = assert!(std::mem::size_of::<Tri4>() == 192);

/// Leaf `i` of the indexed layout: each lane's corners as indices into the tree's own vertex
/// array, and each lane's scene primitive id (padding `u32::MAX`; a sphere's id is at least
/// the triangle count): one cache line, a third of a [`Tri4`].
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub struct Idx4 {
    pub v: [[u32; 3]; LANES],
    pub ids: [u32; LANES],
}
const _: () = assert!(std::mem::size_of::<Idx4>() == 64);

impl Idx4 {
    /// Writes the block the SIMD filter reads: the lanes' corners fetched from `verts`.
    /// Branch-free (padding and sphere lanes index vertex 0 and are masked out), and each
    /// row written whole, so the filter's vector loads are forwarded from these stores
    /// rather than stalled behind twelve narrow ones.
    #[inline(always)]
    pub fn gather(&self, verts: &[Vec3], tri_count: u32, out: &mut Tri4) {
        for corner in 0..3 {
            let p: [Vec3; LANES] = std::array::from_fn(|lane| verts[self.v[lane][corner] as usize]);
            out.c[corner] = [[p[0].x, p[1].x, p[2].x, p[3].x], [p[0].y, p[1].y, p[2].y, p[3].y], [p[0].z, p[1].z, p[2].z, p[3].z]];
        }
        out.tri_lanes = (0..LANES).fold(0, |m, lane| m | ((self.ids[lane] < tri_count) as u32) << lane);
        out.ids = self.ids;
    }
}

/// The leaves in one of the two layouts.
pub enum LeafStore {
    /// Corners copied into the blocks: fastest, 192 bytes a leaf.
    Corners(Vec<Tri4>),
    /// Corners as indices into `verts`, the mesh's vertices in the order the leaves first use
    /// them (a leaf's corners lie together): 64 bytes a leaf plus 12 a vertex.
    Indexed { blocks: Vec<Idx4>, verts: Vec<Vec3> },
}

impl LeafStore {
    pub fn len(&self) -> usize {
        match self {
            LeafStore::Corners(b) => b.len(),
            LeafStore::Indexed { blocks, .. } => blocks.len(),
        }
    }

    pub fn bytes(&self) -> usize {
        match self {
            LeafStore::Corners(b) => std::mem::size_of_val(&b[..]),
            LeafStore::Indexed { blocks, verts } => std::mem::size_of_val(&blocks[..]) + std::mem::size_of_val(&verts[..]),
        }
    }
}

/// Gives every leaf of `nodes` its own block (rewriting the leaf references so leaf `i`, in
/// node order, starts at slot `4 i`) and fills the blocks from the scene in the chosen
/// layout. `ids` are the primitive ids in the builder's leaf order. A leaf holds at most
/// [`LANES`] primitives, so every block is filled independently, in parallel.
pub fn pad_leaves(nodes: &mut [Node8], ids: &[u32], scene: &Scene, indexed: bool) -> LeafStore {
    use rayon::prelude::*;
    let tri_count = scene.mesh.triangle_count() as u32;
    // (node, slot, first, count) of every leaf child, in node order.
    let mut leaves: Vec<(u32, u8, u32, u8)> = Vec::new();
    for (n, node) in nodes.iter().enumerate() {
        for (slot, &child) in node.child.iter().enumerate() {
            if child != EMPTY && child & LEAF_BIT != 0 {
                let (first, count) = leaf_range(child);
                assert!(count <= LANES, "a leaf of {count} primitives does not fit one block");
                leaves.push((n as u32, slot as u8, first as u32, count as u8));
            }
        }
    }
    assert!(leaves.len() * LANES < MAX_PRIMS, "a BVH holds at most {MAX_PRIMS} padded primitive slots");
    let lane_ids = |first: u32, count: u8| {
        let mut out = [u32::MAX; LANES];
        out[..count as usize].copy_from_slice(&ids[first as usize..first as usize + count as usize]);
        out
    };
    let store = if indexed {
        let mut blocks: Vec<Idx4> = leaves
            .par_iter()
            .map(|&(_, _, first, count)| {
                let ids = lane_ids(first, count);
                let v = std::array::from_fn(|lane| {
                    if ids[lane] < tri_count { scene.mesh.triangles[ids[lane] as usize] } else { [0; 3] }
                });
                Idx4 { v, ids }
            })
            .collect();
        let verts = first_use_order(&mut blocks, &scene.mesh.positions, tri_count);
        LeafStore::Indexed { blocks, verts }
    } else {
        LeafStore::Corners(
            leaves
                .par_iter()
                .map(|&(_, _, first, count)| {
                    let mut block = Tri4 { ids: lane_ids(first, count), ..Tri4::default() };
                    for lane in 0..count as usize {
                        let id = block.ids[lane];
                        if id < tri_count {
                            block.tri_lanes |= 1 << lane;
                            for (corner, v) in scene.mesh.corners(id as usize).iter().enumerate() {
                                for axis in 0..3 {
                                    block.c[corner][axis][lane] = v[axis];
                                }
                            }
                        }
                    }
                    block
                })
                .collect(),
        )
    };
    for (i, &(n, slot, _, count)) in leaves.iter().enumerate() {
        nodes[n as usize].child[slot as usize] = leaf_ref((i * LANES) as u32, count as u32);
    }
    store
}

/// Renumbers the blocks' vertex indices in the order the blocks first use them and returns
/// the positions in that order (vertices no triangle uses are left out).
fn first_use_order(blocks: &mut [Idx4], positions: &[Vec3], tri_count: u32) -> Vec<Vec3> {
    let mut new_index = vec![u32::MAX; positions.len()];
    let mut verts = Vec::with_capacity(positions.len());
    for b in blocks.iter_mut() {
        for lane in 0..LANES {
            if b.ids[lane] >= tri_count {
                continue;
            }
            for v in &mut b.v[lane] {
                let slot = &mut new_index[*v as usize];
                if *slot == u32::MAX {
                    *slot = verts.len() as u32;
                    verts.push(positions[*v as usize]);
                }
                *v = *slot;
            }
        }
    }
    verts
}
