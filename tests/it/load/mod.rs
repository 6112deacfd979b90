//! Loading through the command line: damaged files, and PLY meshes the `subdivide` command
//! writes.

mod cutouts;
mod damaged;
mod dialect;
mod ply_bulk;
