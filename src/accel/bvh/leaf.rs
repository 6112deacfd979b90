//! Leaf storage for the SIMD triangle filter: every leaf starts at a multiple of four in the
//! leaf-ordered arrays, so leaf `first / 4` is one block of four triangles stored lane by lane.
//!
//! The SIMD kernels only *reject* triangles, with exactly the operations (same operands, same
//! order, no fused multiply-add) of the scalar watertight test; any lane they cannot reject
//! (a hit candidate, an edge function that is exactly zero, a sphere) goes through the scalar
//! test. So every path reports bit-identical hits, and the scalar test stays the reference.
use super::wide::{EMPTY, LEAF_BIT, MAX_PRIMS, Node8, leaf_range, leaf_ref};
use glam::Vec3;

/// Triangles per block (one SSE register per coordinate).
pub const LANES: usize = 4;

/// Four triangles: `c[corner][axis][lane]`, and the lanes that hold triangles (the others
/// are spheres or padding), in what would otherwise be alignment padding (192 bytes, three
/// cache lines).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub struct Tri4 {
    pub c: [[[f32; LANES]; 3]; 3],
    pub tri_lanes: u32,
}

/// Leaf-ordered primitives, each leaf padded to a whole block.
pub struct Leaves {
    pub prims: Vec<[Vec3; 3]>,
    pub ids: Vec<u32>,
    pub blocks: Vec<Tri4>,
}

/// Moves every leaf of `nodes` to a block boundary (rewriting the leaf references) and
/// builds the SoA blocks. `prims`/`ids` are in the builder's leaf order. A leaf holds at
/// most [`LANES`] primitives, so leaf `i` (in node order) takes block `i` and slots
/// `4i .. 4i + 4`: every block is filled independently, in parallel.
pub fn pad_leaves(nodes: &mut [Node8], prims: &[[Vec3; 3]], ids: &[u32], tri_count: u32) -> Leaves {
    use rayon::prelude::*;
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
    let mut out = Leaves {
        prims: vec![[Vec3::ZERO; 3]; leaves.len() * LANES],
        ids: vec![u32::MAX; leaves.len() * LANES],
        blocks: vec![Tri4::default(); leaves.len()],
    };
    out.blocks
        .par_iter_mut()
        .zip(out.prims.par_chunks_mut(LANES))
        .zip(out.ids.par_chunks_mut(LANES))
        .zip(leaves.par_iter())
        .for_each(|(((block, slot_prims), slot_ids), &(_, _, first, count))| {
            let mut lanes = 0u32;
            for lane in 0..count as usize {
                let (p, id) = (prims[first as usize + lane], ids[first as usize + lane]);
                if id < tri_count {
                    lanes |= 1 << lane;
                    for (corner, v) in p.iter().enumerate() {
                        for axis in 0..3 {
                            block.c[corner][axis][lane] = v[axis];
                        }
                    }
                }
                slot_prims[lane] = p;
                slot_ids[lane] = id;
            }
            block.tri_lanes = lanes;
        });
    for (i, &(n, slot, _, count)) in leaves.iter().enumerate() {
        nodes[n as usize].child[slot as usize] = leaf_ref((i * LANES) as u32, count as u32);
    }
    out
}
