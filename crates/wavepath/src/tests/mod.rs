//! The engine's tests. They sit inside the crate so that they can check the private modules
//! behind the face (traversal kernels against brute force, BSDFs against closed forms,
//! samplers, loaders' internals) and the library is linked into one test binary. A module per
//! area, a file per subject; the big renders and ray counts that take seconds each sit in
//! submodules named `slow`, so `cargo test --profile quick -- --skip slow` is the edit loop and
//! `cargo test --release` runs everything. Tests through the binary and the applications are
//! the root package's `tests/it`.

mod accel;
pub mod common;
mod cs184;
mod denoise;
pub mod integrator;
mod isa;
mod layers;
mod load;
mod materials;
mod sampling;
