//! The integration tests, one crate so the library is compiled and linked into one test
//! binary. A module per area; the statistical and big-render cases that take seconds each
//! sit in submodules named `slow`, so `cargo test --release -- --skip slow` is the quick
//! loop and plain `cargo test --release` runs everything.

mod accel;
mod cli;
mod common;
mod integrator;
mod load;
mod materials;
mod parts;
mod sampling;
mod study;
