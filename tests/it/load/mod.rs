//! Loading through the command line: damaged files, what materials become, and PLY meshes
//! the `subdivide` command writes.

mod cutouts;
mod damaged;
mod dialect;
mod materials;
mod gltf_layers;
mod ply_bulk;
