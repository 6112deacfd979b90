//! How a viewer is started: where it listens, where it may write, what its command line
//! reproduces.

use std::net::SocketAddr;
use std::path::PathBuf;

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
}
