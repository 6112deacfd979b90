//! What a built tree is, as traversal reads it: the 8-wide inner nodes with their child boxes
//! lane by lane ([`node`]) and the leaf store in one of its two layouts ([`leaf`]).
mod leaf;
mod node;

pub use leaf::{LANES, LeafStore, Line, PACKED_HEAD, SPARE_LINES, Tri4};
pub use node::{EMPTY, LEAF_BIT, MAX_PRIMS, Node8, WIDTH, leaf_range, leaf_ref, octant};
