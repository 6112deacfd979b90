//! Loading through the command line: damaged files, what materials become, and PLY meshes
//! the `subdivide` command writes.

mod cutouts;
mod damaged;
mod dialect;
mod gltf_layers;
mod materials;
mod ply_bulk;
