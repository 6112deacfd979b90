//! Random numbers and the warps that turn them into directions and points.
//!
//! Every path draws its numbers from a generator keyed by (seed, pixel, sample, bounce), so
//! an image does not depend on the thread count, the chunk size or the order of work. The
//! numbers of one pixel's samples are independent or follow a pattern (`pattern`).

pub mod distribution;
pub mod numbers;
mod pattern;
mod rng;
pub mod rng8;
mod splitmix;
pub mod warp;

pub use numbers::Numbers;
pub use pattern::SamplerKind;
pub use rng::{Pattern, Sampler};
pub use splitmix::splitmix64;
pub use warp::Frame;
