//! wavepath: a physically based, data-oriented wavefront path tracer for the CPU.
//!
//! Data flows file -> [`load`] -> [`scene::Scene`] -> [`accel`] -> [`render`] ->
//! [`film`] + [`stats`]; see DESIGN.md in the shared folder for the full picture.

pub mod accel;
pub mod bsdf;

pub mod cpu;
pub mod effects;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod lights;
pub mod load;
pub mod parts;
pub mod rays;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod settings;
pub mod stats;
pub mod study;
