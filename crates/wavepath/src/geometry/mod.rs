//! The bottom layer: rays and hits, floating-point error bounds, the offsets that keep a
//! ray from finding its own surface again, and colour weights. Everything above uses it;
//! it uses nothing of the crate.

pub mod colour;
pub mod error_bound;
pub mod offset;
mod ray;
pub mod trig;

pub use colour::illuminance;
pub use ray::{Hit, Ray};
