//! Random numbers and the warps that turn them into directions and points.
//!
//! Every path draws its numbers from a generator seeded by (seed, pixel, sample), so an
//! image does not depend on the thread count, the chunk size or the order of work.

mod rng;

pub use rng::{Sampler, splitmix64};
