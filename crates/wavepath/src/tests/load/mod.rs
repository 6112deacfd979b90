//! Scene loaders: COLLADA, OBJ, PLY and glTF, on the shared scenes and on hand-written
//! files, and one scene written in three formats loading alike.

mod collada;
mod collada_common;
mod cutouts;
mod exporters;
mod formats_agree;
mod gltf_extensions;
mod gltf_materials;
mod mesh_loaders;
mod mtl_models;
mod obj_bulk;
mod other_tools;
mod ply_bulk;
mod relief;
