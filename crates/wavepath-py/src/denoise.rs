//! `render(..., denoise=True)`: Open Image Denoise loaded at run time by the engine's
//! loader, from the path given or from the installed `pyoidn` package (whose wheel carries
//! the library, its CPU device and TBB).

use crate::errors::value_error;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;
use wavepath::{Aov, AovImage, Aux, Denoiser, Film};

/// The denoiser from `oidn` (a library file, a folder holding it, a pyoidn package) or, when
/// none is given, from `import pyoidn`.
pub fn load(py: Python<'_>, oidn: Option<&Path>) -> PyResult<Denoiser> {
    let path = match oidn {
        Some(p) => p.to_path_buf(),
        None => pyoidn_folder(py)
            .ok_or_else(|| PyRuntimeError::new_err(format!("denoise=True: {}", wavepath::OIDN_HELP)))?,
    };
    Denoiser::load(&path).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// The folder of the `pyoidn` package this interpreter imports, if any.
fn pyoidn_folder(py: Python<'_>) -> Option<PathBuf> {
    let file: String = py.import("pyoidn").ok()?.getattr("__file__").ok()?.extract().ok()?;
    Path::new(&file).parent().map(Path::to_path_buf)
}

/// `film` denoised with the render's albedo and normal (prefiltered: they carry the render's
/// noise), without the GIL; with the log line saying what it took.
pub fn run(py: Python<'_>, d: &Denoiser, film: &Film, aovs: &[AovImage]) -> PyResult<(Film, String)> {
    let find = |k: Aov| aovs.iter().find(|v| v.aov == k).map(|v| v.to_film());
    let (albedo, normal) = (find(Aov::Albedo), find(Aov::Normal));
    py.detach(|| {
        let t = Instant::now();
        let aux = Aux { albedo: albedo.as_ref(), normal: normal.as_ref(), prefilter: true };
        let out = d.denoise(film, aux).map_err(|e| value_error(e.to_string()))?;
        let line =
            format!("Denoised in {:.3} s (Open Image Denoise, {})", t.elapsed().as_secs_f64(), d.library().display());
        Ok((out, line))
    })
}
