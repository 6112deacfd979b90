//! Helpers of the engine's test modules: the ones the applications' tests share
//! (`shared.rs`) and the submodules below.

pub mod agree;
pub mod chi2;
pub mod cutout;
pub mod gltf_brdf;
pub mod meshgen;
pub mod render;
mod shared;
pub mod special;

pub use shared::*;
