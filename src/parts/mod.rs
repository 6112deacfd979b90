//! Past one machine: a render cut into parts that separate processes (array jobs under
//! Slurm or a Kubernetes Indexed Job) render on their own, each writing its exact per-pixel
//! sums to a part file, and a merge that adds them back into the single-process image.
//!
//! - [`spec`]: which pixels or samples part I of N takes (`--part I/N|auto`, `--split`).
//! - [`render`]: renders one part.
//! - [`file`]: the part file (OpenEXR with the sums as extra channels and a JSON header).
//! - [`merge`]: checks that the parts belong together and adds them.
//! - [`identity`]: the scene hash and settings key the parts must share.

pub mod file;
pub mod identity;
pub mod merge;
pub mod render;
pub mod spec;
pub mod stats;

pub use file::{Part, PartMeta};
pub use merge::{Merged, merge_files};
pub use render::render_part;
pub use spec::{PartSpec, Split};
pub use stats::PartStats;
