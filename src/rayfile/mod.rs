//! Ray files (the format of ../shared/peers): the renderer's rays to dump, and tracing a file.

pub mod file;
mod trace;

pub use trace::{CHUNK, trace_all};
