//! Leaf storage for the SIMD triangle filter: a leaf of at most four primitives is either one
//! block of their corners lane by lane, or a packed record of its distinct vertices that
//! traversal gathers into such a block; a leaf reference's `first` is its place in the store.
//!
//! The SIMD kernels only *reject* triangles, with exactly the operations (same operands, same
//! order, no fused multiply-add) of the scalar watertight test; any lane they cannot reject
//! (a hit candidate, an edge function that is exactly zero, a sphere) goes through the scalar
//! test. So every path reports bit-identical hits, and the scalar test stays the reference.

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
    /// The lanes that hold a sphere: the filter does not see them, the exact test decides
    /// each (kept here, from padding, instead of derived from the leaf's count at every leaf).
    pub other_lanes: u32,
    /// Scene primitive id of each lane (triangles first, then spheres; padding `u32::MAX`).
    pub ids: [u32; LANES],
}
const _: () = assert!(std::mem::size_of::<Tri4>() == 192);

/// One cache line of packed leaf records (32-bit words: ids and indices, or coordinate bits).
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(64))]
pub struct Line(pub [u32; 16]);

/// Words of a packed record before its vertices: four ids, twelve byte-sized corner
/// indices, and the triangle lanes (bits 0-3) with the sphere lanes (bits 4-7).
pub const PACKED_HEAD: usize = 8;

/// Writes the block the SIMD filter reads from the packed record at the start of `rec`:
/// ids (words 0-3), corner `k` of lane `l` as local vertex `byte 3 l + k` of words 4-6,
/// triangle and sphere lanes (word 7, bits 0-3 and 4-7), then each local vertex's x, y, z.
/// Padding and sphere lanes use vertex 0 and are masked out. `rec` is four lines (the store ends with spare ones) and
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
    out.tri_lanes = rec[7] & 0xf;
    out.other_lanes = rec[7] >> 4 & 0xf;
    out.ids = [rec[0], rec[1], rec[2], rec[3]];
}

/// Lines after the last record, so that every record can be read as four lines.
pub const SPARE_LINES: usize = 3;

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
