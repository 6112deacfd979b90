//! Shading in lanes: eight or sixteen paths at a time, in fixed loops over the lanes that
//! the compiler vectorises, bit for bit what the one-path code ([`super::one_path`]) gives
//! each path.
//!
//! - [`width`] (`integrator/lane_width.rs`, shared with the light subpaths' starts): the one
//!   place a lane kernel's width and instructions are chosen (a portable
//!   arm on every CPU, AVX2 and AVX-512 on x86-64).
//! - [`soa`]: the lane groups' data, one array per component.
//! - [`numbers`]: a group's random numbers, drawn in lanes as the model asks for them.
//! - [`model`]: every material model as the leaving kernel shades it, Lambert included.
//! - [`leave`]: leaving a vertex, written once over model and lane count.
//! - The kernels, one per kind of path [`super::shade`] sorts out: [`hits`] (the hits on
//!   each model, from one list of the models), [`escaped`] (rays that left the scene).

pub mod escaped;
pub mod hits;
pub mod leave;
pub mod model;
pub mod numbers;
pub mod soa;
pub use crate::integrator::lane_width as width;
