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
/// builds the SoA blocks. `prims`/`ids` are in the builder's leaf order.
pub fn pad_leaves(nodes: &mut [Node8], prims: &[[Vec3; 3]], ids: &[u32], tri_count: u32) -> Leaves {
    let mut out = Leaves {
        prims: Vec::with_capacity(prims.len() * 2),
        ids: Vec::with_capacity(prims.len() * 2),
        blocks: Vec::with_capacity(prims.len() / 2),
    };
    for node in nodes.iter_mut() {
        for child in node.child.iter_mut() {
            if *child == EMPTY || *child & LEAF_BIT == 0 {
                continue;
            }
            let (first, count) = leaf_range(*child);
            let start = out.prims.len();
            assert!(start + LANES < MAX_PRIMS, "a BVH holds at most {MAX_PRIMS} padded primitive slots");
            let mut block = Tri4::default();
            let mut lanes = 0u32;
            for lane in 0..count {
                let (p, id) = (prims[first + lane], ids[first + lane]);
                if id < tri_count {
                    lanes |= 1 << lane;
                    for (corner, v) in p.iter().enumerate() {
                        for axis in 0..3 {
                            block.c[corner][axis][lane] = v[axis];
                        }
                    }
                }
                out.prims.push(p);
                out.ids.push(id);
            }
            for _ in count..LANES {
                out.prims.push([Vec3::ZERO; 3]);
                out.ids.push(u32::MAX);
            }
            block.tri_lanes = lanes;
            out.blocks.push(block);
            *child = leaf_ref(start as u32, count as u32);
        }
    }
    out
}
