//! Ray traversal: the BVH against brute force, every instruction set against the scalar
//! path (single rays, batches, packets), both leaf layouts, watertightness.

mod batch_closest;
mod bvh;
mod coherent;
mod cutouts;
mod layouts;
mod packets;
mod raysets;
mod watertight;
