//! Ray files (the format of ../shared/peers): the renderer's rays to dump, and tracing a file.

mod dump;
pub mod file;
mod trace;

pub use dump::{cosine_direction, diffuse_rays, primary_rays};
pub use trace::{CHUNK, trace_all};
