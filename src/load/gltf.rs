//! Loader for gltf files (in progress).
use crate::scene::Scene;
use anyhow::{Result, bail};
use std::path::Path;

pub fn load(path: &Path) -> Result<Scene> {
    bail!("{}: gltf files are not supported yet", path.display())
}
