//! Loader for collada files (in progress).
use crate::scene::Scene;
use anyhow::{Result, bail};
use std::path::Path;

pub fn load(path: &Path, _opts: &super::LoadOptions) -> Result<Scene> {
    bail!("{}: collada files are not supported yet", path.display())
}
