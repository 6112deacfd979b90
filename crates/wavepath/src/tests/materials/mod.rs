//! Materials: the BSDF models against their densities and physics, non-diffuse materials
//! in renders, and albedo textures.

mod bsdf;
mod emissive_textures;
mod layers;
mod renders;
mod textures;
