//! The root package's tests as one crate: the `wavepath` command through its binary and the
//! applications (split renders, studies, the viewer, ray files) through their library, all
//! on the engine's face. The engine's own tests are inside it (`crates/wavepath/src/tests`).
//! Cases that take seconds each sit in submodules named `slow`: `cargo test --profile quick
//! -- --skip slow` is the edit loop, `cargo test --release` runs everything.

mod accel;
mod citations;
mod cli;
mod common;
mod cs184;
mod flags;
mod integrator;
mod load;
mod parts;
mod study;
mod view;
