//! Leaf storage for the SIMD triangle filter: a leaf of at most four primitives is either one
//! block of their corners lane by lane, or a packed record of its distinct vertices that
//! traversal gathers into such a block; a leaf reference's `first` is its place in the store.
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

/// One cache line of packed leaf records (32-bit words: ids and indices, or coordinate bits).
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(64))]
pub struct Line(pub [u32; 16]);

/// Words of a packed record before its vertices: four ids, twelve byte-sized corner
/// indices, and the triangle lanes.
const PACKED_HEAD: usize = 8;

/// Writes the block the SIMD filter reads from the packed record at the start of `rec`:
/// ids (words 0-3), corner `k` of lane `l` as local vertex `byte 3 l + k` of words 4-6,
/// triangle lanes (word 7), then each local vertex's x, y, z. Padding and sphere lanes use
/// vertex 0 and are masked out. `rec` is four lines (the store ends with spare ones) and
/// every index is taken modulo its length, so no access needs a bounds check.
#[inline(always)]
fn gather_packed(rec: &[u32; 64], out: &mut Tri4) {
    let idx: [u8; 12] = bytemuck::cast([rec[4], rec[5], rec[6]]);
    let coord = |lane: usize, corner: usize, axis: usize| {
        f32::from_bits(rec[(PACKED_HEAD + 3 * idx[3 * lane + corner] as usize + axis) & 63])
    };
    for corner in 0..3 {
        out.c[corner] = std::array::from_fn(|axis| std::array::from_fn(|lane| coord(lane, corner, axis)));
    }
    out.tri_lanes = rec[7];
    out.ids = [rec[0], rec[1], rec[2], rec[3]];
}

/// Lines after the last record, so that every record can be read as four lines.
const SPARE_LINES: usize = 3;

/// The leaves in one of the two layouts.
pub enum LeafStore {
    /// Corners copied into the blocks: no lookup, 192 bytes a leaf.
    Corners(Vec<Tri4>),
    /// Each leaf one self-contained record of whole cache lines: its distinct vertices once
    /// each (a leaf of four neighbouring triangles has about six) and byte indices into them:
    /// two lines where a [`Tri4`] takes three, no dependent load.
    Packed { lines: Vec<Line>, leaves: usize },
}

impl LeafStore {
    /// How many leaves it holds.
    pub fn leaves(&self) -> usize {
        match self {
            LeafStore::Corners(b) => b.len(),
            LeafStore::Packed { leaves, .. } => *leaves,
        }
    }

    pub fn bytes(&self) -> usize {
        match self {
            LeafStore::Corners(b) => std::mem::size_of_val(&b[..]),
            LeafStore::Packed { lines, .. } => std::mem::size_of_val(&lines[..]),
        }
    }

    /// Where the leaf at `first` begins, per unit of `first` (for prefetching).
    pub fn base(&self) -> (usize, usize) {
        match self {
            LeafStore::Corners(b) => (b.as_ptr() as usize, std::mem::size_of::<Tri4>()),
            LeafStore::Packed { lines, .. } => (lines.as_ptr() as usize, std::mem::size_of::<Line>()),
        }
    }

    /// Leaf `first` as the SIMD filter reads it: in place, or gathered into `scratch`.
    #[inline(always)]
    pub fn block<'a>(&'a self, first: usize, scratch: &'a mut Tri4) -> &'a Tri4 {
        match self {
            LeafStore::Corners(blocks) => &blocks[first],
            LeafStore::Packed { lines, .. } => {
                let rec: &[Line; 4] = lines[first..first + 4].try_into().expect("a record is read as four lines");
                gather_packed(bytemuck::cast_ref(rec), scratch);
                scratch
            }
        }
    }
}

/// Stores every leaf of `nodes`, packed or as corners, rewriting each leaf reference's
/// `first` to the leaf's place in the store. `ids` are the primitive ids in the builder's
/// leaf order. A leaf holds at most [`LANES`] primitives; leaves are filled independently,
/// in parallel.
pub fn store_leaves(nodes: &mut [Node8], ids: &[u32], scene: &Scene, packed: bool) -> LeafStore {
    use rayon::prelude::*;
    let tri_count = scene.mesh.triangle_count() as u32;
    let lane_ids = |first: u32, count: u32| {
        let mut out = [u32::MAX; LANES];
        out[..count as usize].copy_from_slice(&ids[first as usize..(first + count) as usize]);
        out
    };
    let corners = |ids: &[u32; LANES]| -> [[u32; 3]; LANES] {
        std::array::from_fn(
            |lane| if ids[lane] < tri_count { scene.mesh.triangles[ids[lane] as usize] } else { [0; 3] },
        )
    };
    // Nodes in groups whose leaves (in node, then slot order) are one run of the store: no
    // list of every leaf and no table of places (at 25.6M triangles, 110 MB at the peak).
    let groups: Vec<(usize, usize)> = nodes
        .par_chunks(GROUP)
        .map(|g| {
            let leaves = g.iter().flat_map(|n| n.child).filter(|&c| is_leaf(c)).count();
            let lines = if packed {
                leaf_ranges(g)
                    .map(|(first, count)| {
                        let ids = lane_ids(first, count);
                        Packed::of(&ids, &corners(&ids), tri_count).lines()
                    })
                    .sum()
            } else {
                leaves
            };
            (leaves, lines)
        })
        .collect();
    let total_leaves: usize = groups.iter().map(|g| g.0).sum();
    let total_units: usize = groups.iter().map(|g| g.1).sum();
    assert!(
        total_leaves < MAX_PRIMS && total_units < MAX_PRIMS,
        "a BVH holds at most {MAX_PRIMS} leaves and leaf lines"
    );
    // Splits `store` into each group's run, paired with the group's nodes and the place of
    // the run's start.
    fn runs<'a, T>(
        nodes: &'a mut [Node8],
        groups: &[(usize, usize)],
        mut store: &'a mut [T],
    ) -> Vec<(&'a mut [Node8], &'a mut [T], usize)> {
        let mut out = Vec::with_capacity(groups.len());
        let mut at = 0;
        for (g, &(_, units)) in nodes.chunks_mut(GROUP).zip(groups) {
            let (run, rest) = store.split_at_mut(units);
            out.push((g, run, at));
            at += units;
            store = rest;
        }
        out
    }
    if packed {
        // Each record is made twice, to count its lines and to write it: keeping them between
        // the passes would hold as much memory again as the store itself.
        let mut lines = vec![Line::default(); total_units + SPARE_LINES];
        runs(nodes, &groups, &mut lines[..total_units]).into_par_iter().for_each(|(g, run, start)| {
            let mut at = 0;
            for_each_leaf(g, |first, count| {
                let ids = lane_ids(first, count);
                let rec = Packed::of(&ids, &corners(&ids), tri_count);
                let n = rec.lines();
                rec.write(bytemuck::cast_slice_mut(&mut run[at..at + n]), &scene.mesh.positions);
                at += n;
                (start + at - n) as u32
            });
        });
        LeafStore::Packed { lines, leaves: total_leaves }
    } else {
        let mut blocks = vec![Tri4::default(); total_units];
        runs(nodes, &groups, &mut blocks).into_par_iter().for_each(|(g, run, start)| {
            let mut at = 0;
            for_each_leaf(g, |first, count| {
                let block = &mut run[at];
                block.ids = lane_ids(first, count);
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
                at += 1;
                (start + at - 1) as u32
            });
        });
        LeafStore::Corners(blocks)
    }
}

/// Nodes per group of [`store_leaves`].
const GROUP: usize = 1024;

fn is_leaf(child: u32) -> bool {
    child != EMPTY && child & LEAF_BIT != 0
}

/// The builder's (first, count) of a leaf child.
fn range_of(child: u32) -> (u32, u32) {
    let (first, count) = leaf_range(child);
    assert!(count <= LANES, "a leaf of {count} primitives does not fit one block");
    (first as u32, count as u32)
}

/// The builder's (first, count) of each leaf child of `nodes`, in node then slot order.
fn leaf_ranges(nodes: &[Node8]) -> impl Iterator<Item = (u32, u32)> + '_ {
    nodes.iter().flat_map(|n| n.child).filter(|&c| is_leaf(c)).map(range_of)
}

/// Calls `store` with each leaf child's (first, count) in node then slot order, and points
/// the child at the place in the store it returns.
fn for_each_leaf(nodes: &mut [Node8], mut store: impl FnMut(u32, u32) -> u32) {
    for node in nodes {
        for child in node.child.iter_mut().filter(|c| is_leaf(**c)) {
            let (first, count) = range_of(*child);
            *child = leaf_ref(store(first, count), count);
        }
    }
}

/// A leaf's packed record before it is written: its distinct vertices (mesh indices) and
/// each corner's place among them.
struct Packed {
    ids: [u32; LANES],
    tri_lanes: u32,
    verts: [u32; 3 * LANES],
    nverts: usize,
    local: [u8; 3 * LANES],
}

impl Packed {
    fn of(ids: &[u32; LANES], corners: &[[u32; 3]; LANES], tri_count: u32) -> Packed {
        let mut p = Packed { ids: *ids, tri_lanes: 0, verts: [0; 3 * LANES], nverts: 0, local: [0; 3 * LANES] };
        for lane in 0..LANES {
            if ids[lane] >= tri_count {
                continue;
            }
            p.tri_lanes |= 1 << lane;
            for (k, &v) in corners[lane].iter().enumerate() {
                let at = p.verts[..p.nverts].iter().position(|&u| u == v).unwrap_or_else(|| {
                    p.verts[p.nverts] = v;
                    p.nverts += 1;
                    p.nverts - 1
                });
                p.local[3 * lane + k] = at as u8;
            }
        }
        // A leaf of spheres only still reads vertex 0 (masked out): keep one.
        p.nverts = p.nverts.max(1);
        p
    }

    fn lines(&self) -> usize {
        (PACKED_HEAD + 3 * self.nverts).div_ceil(16)
    }

    fn write(&self, out: &mut [u32], positions: &[Vec3]) {
        out[..LANES].copy_from_slice(&self.ids);
        let idx: [u32; 3] = bytemuck::cast(self.local);
        out[4..7].copy_from_slice(&idx);
        out[7] = self.tri_lanes;
        for (i, &v) in self.verts[..self.nverts].iter().enumerate() {
            let p = if self.tri_lanes == 0 { Vec3::ZERO } else { positions[v as usize] };
            out[PACKED_HEAD + 3 * i..PACKED_HEAD + 3 * i + 3].copy_from_slice(&p.to_array().map(f32::to_bits));
        }
    }
}
