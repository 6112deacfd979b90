//! wavepath: a physically based, data-oriented wavefront path tracer for the CPU.
//!
//! Data flows file -> [`load`] -> [`scene::Scene`] -> [`accel`] -> [`render`] ->
//! [`film`] + [`stats`]. The modules below are listed by layer, lowest first: each uses only
//! layers before it (ARCHITECTURE.md; `tests/it/layers.rs` checks it).

// 0: run-time CPU features; rays, error bounds, offsets.
pub mod cpu;
pub mod geometry;
// 1: random streams and warps.
pub mod sampling;
// 2: plain data.
pub mod scene;
pub mod settings;
// 3: what the integrators are built from.
pub mod accel;
pub mod bsdf;
pub mod effects;
pub mod film;
pub mod lights;
pub mod load;
// 4: what a render measured.
pub mod stats;
// 5: light transport: the shared vertex logic, the wavefront stages, the recursive reference.
pub mod integrator;
// 6: a whole render.
pub mod render;
// 7: built on whole renders: split renders, accuracy-versus-time studies, ray files, the
// interactive viewer.
pub mod parts;
pub mod rayfile;
pub mod study;
pub mod view;
