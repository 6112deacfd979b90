//! Loading through the command line: damaged files, and PLY meshes the `subdivide` command
//! writes.

mod damaged;
mod dialect;
mod gltf_layers;
mod ply_bulk;
