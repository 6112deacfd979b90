//! Where the Open Image Denoise runtime is: the path the user gave, or the `pyoidn` package
//! installed for the `python3` on the PATH (the active virtual environment's comes first).
//! The engine loads it (`wavepath::Denoiser::load`, which takes a library file or a folder
//! such as pyoidn's).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::bail;

/// The library (or the folder holding it) to hand to `Denoiser::load`: `explicit` when given
/// (it must exist), else the folder of the `pyoidn` package `python3` imports; else an error
/// whose message is `wavepath::OIDN_HELP`.
pub fn find_oidn(explicit: Option<&Path>) -> anyhow::Result<PathBuf> {
    if let Some(path) = explicit {
        if !path.exists() {
            bail!("{}: no such file or folder; {}", path.display(), wavepath::OIDN_HELP);
        }
        return Ok(path.to_path_buf());
    }
    match pyoidn_folder() {
        Some(folder) => Ok(folder),
        None => bail!("{}", wavepath::OIDN_HELP),
    }
}

/// Python printing the folder of the `pyoidn` package without importing it (importing it
/// imports numpy, and torch when installed, which takes seconds); fails when there is none.
const PYOIDN_FOLDER: &str = "import importlib.util as u; print(u.find_spec('pyoidn').submodule_search_locations[0])";

/// The folder of the `pyoidn` package that `python3` imports, if there is one: asked quietly
/// (its errors discarded; no python3 at all is simply none).
fn pyoidn_folder() -> Option<PathBuf> {
    let out =
        Command::new("python3").args(["-c", PYOIDN_FOLDER]).stdin(Stdio::null()).stderr(Stdio::null()).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let folder = PathBuf::from(String::from_utf8(out.stdout).ok()?.trim());
    (!folder.as_os_str().is_empty() && folder.is_dir()).then_some(folder)
}
