//! Ray files (the format of ../shared/peers): dumping the renderer's rays and tracing them.

mod dump;
pub mod file;
mod trace;

pub use dump::{cosine_direction, diffuse_rays, offset_origin, primary_rays};
pub use trace::{CHUNK, trace_all};

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct DumpArgs {
    /// Scene file.
    pub scene: PathBuf,
    /// primary: camera rays; diffuse: first diffuse bounces of the primary hits.
    #[arg(long, value_parser = ["primary", "diffuse"])]
    pub kind: String,
    /// Output ray file.
    #[arg(long)]
    pub out: PathBuf,
    /// Resolution of the camera rays.
    #[arg(short = 'r', num_args = 2, value_names = ["W", "H"])]
    pub resolution: Option<Vec<u32>>,
    /// Seed of the diffuse directions.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

#[derive(Args, Debug, Clone)]
#[command(allow_negative_numbers = true)]
pub struct TraceArgs {
    /// Mesh or scene file.
    pub mesh: PathBuf,
    /// Ray file.
    pub rays: PathBuf,
    /// Threads (positional form of -t).
    pub threads_pos: Option<usize>,
    /// Timed passes (positional form of -r).
    pub reps_pos: Option<usize>,
    #[arg(short = 't')]
    pub threads: Option<usize>,
    #[arg(short = 'r')]
    pub reps: Option<usize>,
    /// Untimed warm-up passes.
    #[arg(short = 'w', default_value_t = 1)]
    pub warmup: usize,
    /// Write the hits file here.
    #[arg(short = 'o')]
    pub hits: Option<PathBuf>,
    /// Variant label printed in the JSON line.
    #[arg(long, default_value = "bvh")]
    pub variant: String,
    /// Widest SIMD instruction set of the box tests: scalar, sse, avx2, avx512.
    #[arg(long, value_name = "ISA", value_parser = crate::cli::parse_isa, default_value = "avx2")]
    pub isa: crate::cpu::Isa,
}

pub fn dump(args: &DumpArgs) -> Result<()> {
    dump::dump(args)
}

pub fn trace(args: &TraceArgs) -> Result<()> {
    trace::trace(args)
}
