//! wavepath from Python: the engine's face as a Python module (`import wavepath`).
//!
//! Scenes load from files or come from numpy arrays; renders return numpy images and the
//! command line's statistics, bit for bit the command line's image for the same settings;
//! ray queries take and return numpy arrays. Long calls release the GIL; renders stop on
//! Ctrl-C. The stub `wavepath.pyi` beside this crate's pyproject.toml documents the types.

mod arrays;
mod denoise;
mod errors;
mod rays;
mod render;
mod scene;
mod values;

use pyo3::prelude::*;
use scene::PyScene;

/// Loads a scene file (.dae, .obj, .ply, .gltf, .glb) with the command line's defaults.
///
/// camera: "cs184" (the CS184 reference placement for .dae, as the command line) or "file"
/// (the file's camera as written). smooth_normals: COLLADA files get area-weighted vertex
/// normals (as the reference renderer). two_sided_emission: every emitter emits from both
/// faces. subdivide: rounds of midpoint subdivision (4^n times the triangles).
/// Raises FileNotFoundError for a missing file, ValueError for a malformed one.
#[pyfunction]
#[pyo3(signature = (path, *, camera=None, smooth_normals=None, two_sided_emission=None, subdivide=None))]
fn load(
    py: Python<'_>,
    path: std::path::PathBuf,
    camera: Option<&str>,
    smooth_normals: Option<bool>,
    two_sided_emission: Option<bool>,
    subdivide: Option<u32>,
) -> PyResult<PyScene> {
    // Options left out keep the library's defaults (`LoadOptions::default()`, the command line's).
    let mut opts = wavepath::LoadOptions::default();
    if let Some(name) = camera {
        opts.camera =
            name.parse().map_err(|e: wavepath::UnknownName| errors::value_error(e.for_option("camera").to_string()))?;
    }
    opts.smooth_normals = smooth_normals.unwrap_or(opts.smooth_normals);
    opts.two_sided_emission = two_sided_emission.unwrap_or(opts.two_sided_emission);
    opts.subdivide = subdivide.unwrap_or(opts.subdivide);
    let mut scene = py.detach(|| wavepath::load(&path, &opts)).map_err(errors::to_py)?;
    scene.drop_unused_uvs();
    Ok(PyScene::new(scene))
}

/// The embedded default scene: the Cornell box with two spheres that `wavepath` renders
/// when given no file.
#[pyfunction]
fn default_scene() -> PyScene {
    PyScene::new(wavepath::default_scene())
}

/// wavepath: a physically based wavefront path tracer for the CPU.
///
///     scene = wavepath.load("dragon.ply")          # or Scene.from_arrays(vertices, faces)
///     image, stats = scene.render(spp=16, max_depth=5, resolution=(320, 240))
///     hits = scene.intersect(origins, directions)  # dict of numpy arrays
#[pymodule(name = "wavepath")]
fn wavepath_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(default_scene, m)?)?;
    m.add_class::<PyScene>()?;
    m.add("MISS", rays::wavepath_miss())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
