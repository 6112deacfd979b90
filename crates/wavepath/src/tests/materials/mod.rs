//! Materials: the BSDF models against their densities and physics, non-diffuse materials
//! in renders (closed forms among them), and albedo textures.

mod bsdf;
mod closed_form;
mod emissive_textures;
mod layers;
mod renders;
mod textures;
