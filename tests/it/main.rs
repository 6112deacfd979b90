//! The integration tests as one crate, so the library is linked into one test binary rather
//! than one per file. A module per area, a file per subject; the big renders and ray counts
//! that take seconds each sit in submodules named `slow`, so `cargo test --profile quick --
//! --skip slow` is the edit loop and plain `cargo test --release` runs everything.

mod accel;
mod citations;
mod cli;
mod common;
mod cs184;
pub mod integrator;
mod isa;
mod layers;
mod load;
mod materials;
mod parts;
mod sampling;
mod study;
mod view;
