//! Ray traversal: the BVH against brute force, every instruction set against the scalar
//! path (single rays, batches, packets), watertightness, and ray files.

mod batch_closest;
mod bvh;
mod packets;
mod rays;
mod watertight;
