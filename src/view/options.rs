//! How a viewer is started: where it listens, where it may write, what its command line
//! reproduces, the denoiser it has and what it shows first.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use wavepath::{Aov, Denoiser};

/// How the viewer is reached and what it may write.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    pub listen: SocketAddr,
    /// Folder for saved images (`None`: saving is refused).
    pub save_dir: Option<PathBuf>,
    /// The scene file and environment map, for the reproducing command line.
    pub scene_path: Option<String>,
    pub envmap_path: Option<String>,
    /// Sampler name as the command line spells it.
    pub sampler: String,
    /// Open Image Denoise, when a runtime was found (`None`: the page's denoise box is off
    /// and requests to denoise are refused).
    pub denoiser: Option<Arc<Denoiser>>,
    /// What the image shows at start: the picture (`None`) or an output variable.
    pub show: Option<Aov>,
    /// Denoise the picture from the start (needs `denoiser`).
    pub denoise: bool,
}
