//! `wavepath.Scene`: a loaded (or array-built) scene, its BVH built once on first use and
//! shared by every ray query and render that asks for the default tree.

use crate::arrays::{self, Floats};
use crate::errors::value_error;
use crate::rays::{self, RayArrays};
use crate::render::{self, RenderOptions};
use crate::values;
use glam::{Vec2, Vec3};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::sync::{Arc, Mutex, OnceLock, RwLock, RwLockReadGuard, RwLockWriteGuard, TryLockError};
use std::thread::ThreadId;
use std::time::Duration;
use wavepath::{Bvh, BvhOptions, Intersector, Isa, MaterialIds, Mesh, Scene, SceneSource, Settings};

/// A scene: triangles and spheres, materials, lights and a camera.
///
/// Make one with `wavepath.load(path)`, `wavepath.default_scene()` or
/// `Scene.from_arrays(vertices, faces, ...)`; then `render(...)` it to a numpy image, or cast
/// rays at it with `intersect(...)` and `occluded(...)`.
#[pyclass(name = "Scene", module = "wavepath", frozen)]
pub struct PyScene {
    /// Written only while a render swaps in its camera (restored after), read by queries.
    scene: RwLock<Scene>,
    /// The default BVH (default build, best instruction set), built on first use.
    bvh: OnceLock<Bvh>,
    /// The thread whose render holds the scene, so that a query from its own progress
    /// callback is refused instead of waiting for itself.
    rendering: Mutex<Option<ThreadId>>,
    /// Worker pools by thread count, made on first use: building one costs about 0.1 ms,
    /// more than a small batch of rays takes to trace.
    pools: Mutex<Vec<(usize, Arc<rayon::ThreadPool>)>>,
}

/// How long a thread that finds the scene locked waits, without the GIL, before trying again.
const LOCK_RETRY: Duration = Duration::from_micros(200);

impl PyScene {
    pub fn new(scene: Scene) -> Self {
        PyScene {
            scene: RwLock::new(scene),
            bvh: OnceLock::new(),
            rendering: Mutex::new(None),
            pools: Mutex::new(Vec::new()),
        }
    }

    /// Refuses a query from inside this scene's own render (its progress callback).
    fn not_from_own_render(&self) -> PyResult<()> {
        let r = *self.rendering.lock().unwrap_or_else(|e| e.into_inner());
        if r == Some(std::thread::current().id()) {
            return Err(PyRuntimeError::new_err(
                "the scene is being rendered by this thread: use it after render() returns",
            ));
        }
        Ok(())
    }

    /// The scene for reading. The lock is never waited for while holding the GIL: a thread
    /// that holds the lock may need the GIL (a render calls back into Python), so waiting
    /// with it could deadlock; the wait releases the GIL between tries.
    fn read(&self, py: Python<'_>) -> PyResult<RwLockReadGuard<'_, Scene>> {
        self.not_from_own_render()?;
        loop {
            match self.scene.try_read() {
                Ok(g) => return Ok(g),
                Err(TryLockError::Poisoned(e)) => return Ok(e.into_inner()),
                Err(TryLockError::WouldBlock) => py.detach(|| std::thread::sleep(LOCK_RETRY)),
            }
        }
    }

    /// The scene for a render to swap its camera in, waited for as [`PyScene::read`].
    fn write(&self, py: Python<'_>) -> PyResult<RwLockWriteGuard<'_, Scene>> {
        self.not_from_own_render()?;
        loop {
            match self.scene.try_write() {
                Ok(g) => return Ok(g),
                Err(TryLockError::Poisoned(e)) => return Ok(e.into_inner()),
                Err(TryLockError::WouldBlock) => py.detach(|| std::thread::sleep(LOCK_RETRY)),
            }
        }
    }

    fn bvh_of(&self, scene: &Scene) -> &Bvh {
        self.bvh.get_or_init(|| Bvh::build_with(scene, BvhOptions::default()).with_isa(Isa::default()))
    }

    /// Runs `f` on `threads` workers (0: rayon's global pool, every core).
    fn on_threads<T: Send>(&self, threads: usize, f: impl FnOnce() -> T + Send) -> PyResult<T> {
        if threads == 0 {
            return Ok(f());
        }
        let pool = {
            let mut pools = self.pools.lock().unwrap_or_else(|e| e.into_inner());
            match pools.iter().find(|(n, _)| *n == threads) {
                Some((_, p)) => p.clone(),
                None => {
                    let p = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .map_err(|e| value_error(format!("cannot start {threads} threads: {e}")))?;
                    let p = Arc::new(p);
                    pools.push((threads, p.clone()));
                    p
                }
            }
        };
        Ok(pool.install(f))
    }

    /// The origins, directions and bounds of a ray query, read from Python values.
    fn ray_inputs<'py>(
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        tmin: Option<&Bound<'py, PyAny>>,
        tmax: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Floats<'py>, Floats<'py>, arrays::PerRay<'py>, arrays::PerRay<'py>)> {
        let o = arrays::floats(origins, "origins", 3)?;
        let d = arrays::floats(directions, "directions", 3)?;
        let n = o.rows().len();
        if d.rows().len() != n {
            return Err(value_error(format!("origins has {n} rows but directions has {}", d.rows().len())));
        }
        // Left out, the bounds are the whole ray: [0, inf).
        let lo = tmin.map_or(Ok(arrays::PerRay::All(0.0)), |t| arrays::per_ray(t, "tmin", n))?;
        let hi = tmax.map_or(Ok(arrays::PerRay::All(f32::INFINITY)), |t| arrays::per_ray(t, "tmax", n))?;
        Ok((o, d, lo, hi))
    }
}

fn bad_ray(i: usize) -> PyErr {
    value_error(format!(
        "ray {i} is not a ray: its origin or direction is not finite, its direction is zero, or a bound is NaN"
    ))
}

#[pymethods]
impl PyScene {
    /// A scene from numpy arrays (or a mesh object with `vertices` and `faces`, such as a
    /// trimesh mesh: pass it as the only argument).
    ///
    /// vertices: (n, 3) float32 or float64. faces: (m, 3) integers. normals: (n, 3) per
    /// vertex; uvs: (n, 2); material_ids: (m,) indices into `materials` (default all 0).
    /// materials: list of dicts, e.g. {"type": "diffuse", "color": (0.8, 0.2, 0.2)}, or
    /// "emitter", "mirror", "glass", "metallic_roughness", "phong" (default: one grey
    /// diffuse). lights: list of dicts ("point", "directional", "spot", "area", "sky").
    /// spheres: list of {"center", "radius", "material"}. camera: {"eye", "target", "up",
    /// "fov"} or a camera file; without one the camera frames the bounds. A scene with no
    /// light and no emitter is lit by the default sky, as a bare OBJ is.
    #[staticmethod]
    #[pyo3(signature = (vertices, faces=None, *, normals=None, uvs=None, material_ids=None, materials=None, lights=None, spheres=None, camera=None, name=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_arrays(
        vertices: &Bound<'_, PyAny>,
        faces: Option<&Bound<'_, PyAny>>,
        normals: Option<&Bound<'_, PyAny>>,
        uvs: Option<&Bound<'_, PyAny>>,
        material_ids: Option<&Bound<'_, PyAny>>,
        materials: Option<&Bound<'_, PyList>>,
        lights: Option<&Bound<'_, PyList>>,
        spheres: Option<&Bound<'_, PyList>>,
        camera: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
    ) -> PyResult<PyScene> {
        // Duck typing: anything with `vertices` and `faces` is a mesh (trimesh, Open3D's
        // legacy meshes through `np.asarray` of theirs, plain namespaces).
        let (vertices, faces) = match faces {
            Some(f) => (vertices.clone(), f.clone()),
            None if vertices.hasattr("vertices")? && vertices.hasattr("faces")? => {
                (vertices.getattr("vertices")?, vertices.getattr("faces")?)
            }
            None => return Err(value_error("from_arrays needs faces (or a mesh object with vertices and faces)")),
        };
        let v = arrays::floats(&vertices, "vertices", 3)?;
        let rows = v.rows();
        let positions: Vec<Vec3> = (0..rows.len()).map(|i| rows.vec3(i)).collect();
        let flat = arrays::indices(&faces, "faces", Some(3))?;
        let triangles: Vec<[u32; 3]> = flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        let mut mesh = Mesh { positions, triangles, ..Mesh::default() };
        if let Some(n) = normals {
            let n = arrays::floats(n, "normals", 3)?;
            let r = n.rows();
            mesh.normals = Some((0..r.len()).map(|i| r.vec3(i)).collect());
        }
        if let Some(u) = uvs {
            let u = arrays::floats(u, "uvs", 2)?;
            let r = u.rows();
            mesh.uvs = Some((0..r.len()).map(|i| Vec2::new(r.at(i, 0), r.at(i, 1))).collect());
        }
        let m = mesh.triangles.len();
        mesh.material_ids = match material_ids {
            Some(ids) => {
                let ids = arrays::indices(ids, "material_ids", None)?;
                if ids.len() != m {
                    return Err(value_error(format!("material_ids has {} entries for {m} faces", ids.len())));
                }
                let mut out = MaterialIds::default();
                ids.into_iter().for_each(|i| out.push(i));
                out
            }
            None => MaterialIds::uniform(0, m),
        };
        let mut scene = Scene {
            name: name.unwrap_or_else(|| "arrays".into()),
            source: SceneSource { dialect: wavepath::Dialect::Standard, reader: "arrays", default_sky: false },
            mesh,
            ..Scene::default()
        };
        scene.materials = match materials {
            Some(list) => list.iter().enumerate().map(|(i, m)| values::material(&m, i)).collect::<PyResult<_>>()?,
            None => vec![wavepath::Material::default()],
        };
        if let Some(list) = lights {
            scene.lights = list.iter().enumerate().map(|(i, l)| values::light(&l, i)).collect::<PyResult<_>>()?;
        }
        if let Some(list) = spheres {
            scene.spheres = list.iter().enumerate().map(|(i, s)| values::sphere(&s, i)).collect::<PyResult<_>>()?;
        }
        if scene.mesh.triangles.is_empty() && scene.spheres.is_empty() {
            return Err(value_error("from_arrays: the scene has no triangles and no spheres"));
        }
        scene.validate().map_err(|e| value_error(format!("from_arrays: {e}")))?;
        scene.camera = match camera {
            Some(c) => values::camera(c)?,
            None => {
                let (lo, hi) = scene.bounds().ok_or_else(|| value_error("from_arrays: the scene has no geometry"))?;
                wavepath::Camera::framing(lo, hi)
            }
        };
        scene.light_by_default_sky();
        Ok(PyScene::new(scene))
    }

    /// Renders the scene; returns `(image, stats)`: a float32 (height, width, 3) linear image,
    /// top row first, and the statistics `wavepath --stats` writes (rays, Mrays/s, stage times).
    ///
    /// The same settings give the same image, bit for bit, as the command line
    /// (`wavepath SCENE -s SPP -l LIGHT_SAMPLES -m MAX_DEPTH -r W H ...`). Ctrl-C stops the
    /// render (KeyboardInterrupt); `progress(done, total)` is called a few times a second
    /// with the camera samples finished. Other Python threads run meanwhile.
    #[pyo3(signature = (*, spp=None, light_samples=None, max_depth=None, accumulate=None, resolution=None, camera=None, threads=None, sampler=None, seed=None, adaptive=None, shading=None, integrator=None, hemisphere=None, mis=None, roulette=None, rr=None, rr_depth=None, isa=None, fov=None, lens_radius=None, focal_distance=None, light_paths=None, aovs=None, denoise=false, oidn=None, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        spp: Option<i64>,
        light_samples: Option<i64>,
        max_depth: Option<i64>,
        accumulate: Option<bool>,
        resolution: Option<(i64, i64)>,
        camera: Option<&Bound<'py, PyAny>>,
        threads: Option<i64>,
        sampler: Option<String>,
        seed: Option<u64>,
        adaptive: Option<(f64, f64)>,
        shading: Option<String>,
        integrator: Option<String>,
        hemisphere: Option<bool>,
        mis: Option<bool>,
        roulette: Option<String>,
        rr: Option<f64>,
        rr_depth: Option<i64>,
        isa: Option<String>,
        fov: Option<String>,
        lens_radius: Option<f64>,
        focal_distance: Option<f64>,
        light_paths: Option<f64>,
        aovs: Option<Vec<String>>,
        denoise: bool,
        oidn: Option<std::path::PathBuf>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let o = RenderOptions {
            spp,
            light_samples,
            max_depth,
            accumulate,
            resolution,
            threads,
            sampler,
            seed,
            adaptive,
            shading,
            integrator,
            hemisphere,
            mis,
            roulette,
            rr,
            rr_depth,
            isa,
            fov,
            lens_radius,
            focal_distance,
            light_paths,
            aovs,
            denoise,
        };
        let asked = render::asked_aovs(&o)?;
        let wants_aovs = o.aovs.is_some();
        // The denoiser is found before the render, so a missing one costs no render.
        let denoiser = if denoise { Some(crate::denoise::load(py, oidn.as_deref())?) } else { None };
        let given_camera = camera.map(values::camera).transpose()?;
        if let Some(p) = &progress
            && !p.bind(py).is_callable()
        {
            return Err(value_error("progress must be callable as progress(done, total)"));
        }
        // The render's camera (the one given, with the lens values) is swapped in for its
        // duration (queries from other threads wait); the scene's own is put back whatever
        // happens. Its fit to the image is the render plan's, from the settings.
        let mut guard = self.write(py)?;
        *self.rendering.lock().unwrap_or_else(|e| e.into_inner()) = Some(std::thread::current().id());
        let request = render::request(&o)?;
        let s: Settings = render::settings(&guard, &request)?;
        let cam = request.camera(given_camera.unwrap_or(guard.camera));
        let saved = std::mem::replace(&mut guard.camera, cam);
        let scene: &Scene = &guard;
        let result = (|| {
            let default_tree =
                s.accel.use_bvh && s.accel.bvh == BvhOptions::default() && s.execution.isa == Isa::default();
            if default_tree {
                let bvh = py.detach(|| self.on_threads(s.execution.threads, || self.bvh_of(scene)))?;
                render::run(py, scene, bvh, bvh.info(), &s, progress.as_ref())
            } else {
                let (accel, build) =
                    py.detach(|| self.on_threads(s.execution.threads, || wavepath::build_accel(scene, &s)))?;
                render::run(py, scene, accel.as_ref(), build, &s, progress.as_ref())
            }
        })();
        guard.camera = saved;
        *self.rendering.lock().unwrap_or_else(|e| e.into_inner()) = None;
        drop(guard);
        let r = result?;
        let mut log = r.log;
        let film = match &denoiser {
            Some(d) => {
                let (film, line) = crate::denoise::run(py, d, &r.out.film, &r.out.aovs)?;
                log.push(line);
                film
            }
            None => r.out.film,
        };
        let image = film_rows(
            py,
            film.width,
            film.height,
            3,
            &film.pixels.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>(),
        )?;
        let stats = py.import("json")?.call_method1("loads", (r.stats_json,))?;
        if let Ok(d) = stats.cast::<PyDict>() {
            d.set_item("log", log)?;
        }
        if !wants_aovs {
            return PyTuple::new(py, [image.into_any(), stats]);
        }
        let out = PyDict::new(py);
        for a in r.out.aovs.iter().filter(|a| asked.contains(a.aov)) {
            out.set_item(a.aov.name(), film_rows(py, a.width, a.height, a.channels(), &a.data)?)?;
        }
        PyTuple::new(py, [image.into_any(), stats, out.into_any()])
    }

    /// Closest hits of rays given as numpy arrays.
    ///
    /// origins, directions: (n, 3) float32 or float64 (any order; directions need not be
    /// unit length: t is in units of the direction). tmin, tmax: numbers or (n,) arrays.
    /// Returns a dict: "t" float32 (n,) (inf on a miss), "prim" uint32 (n,) (the triangle's
    /// index in the file, spheres after triangles; MISS on a miss), "uv" float32 (n, 2)
    /// barycentrics, and with normals=True "normal" float32 (n, 3), the unit geometric normal.
    /// Watertight: a ray through a shared edge or vertex hits one of its triangles. The GIL is
    /// released; threads=0 uses every core.
    #[pyo3(signature = (origins, directions, tmin=None, tmax=None, *, normals=false, threads=0))]
    #[allow(clippy::too_many_arguments)]
    fn intersect<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        tmin: Option<&Bound<'py, PyAny>>,
        tmax: Option<&Bound<'py, PyAny>>,
        normals: bool,
        threads: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (o, d, lo, hi) = Self::ray_inputs(origins, directions, tmin, tmax)?;
        let rays = RayArrays { origins: o.rows(), directions: d.rows(), tmin: lo.view(), tmax: hi.view() };
        let n = rays.len();
        let scene = self.read(py)?;
        let hits = py.detach(|| {
            self.on_threads(threads, || {
                let bvh = self.bvh_of(&scene);
                rays::intersect(&scene, bvh as &dyn Intersector, rays, normals)
            })
        })?;
        drop(scene);
        if hits.bad != usize::MAX {
            return Err(bad_ray(hits.bad));
        }
        let out = PyDict::new(py);
        out.set_item("t", PyArray1::from_vec(py, hits.t))?;
        out.set_item("prim", PyArray1::from_vec(py, hits.prim))?;
        out.set_item("uv", to_2d(py, hits.uv, n, 2)?)?;
        if let Some(g) = hits.normal {
            out.set_item("normal", to_2d(py, g, n, 3)?)?;
        }
        Ok(out)
    }

    /// Whether anything lies on each ray between tmin and tmax: a bool (n,) array. Same
    /// inputs as `intersect`; stops at the first hit of each ray.
    #[pyo3(signature = (origins, directions, tmin=None, tmax=None, *, threads=0))]
    fn occluded<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        tmin: Option<&Bound<'py, PyAny>>,
        tmax: Option<&Bound<'py, PyAny>>,
        threads: usize,
    ) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let (o, d, lo, hi) = Self::ray_inputs(origins, directions, tmin, tmax)?;
        let rays = RayArrays { origins: o.rows(), directions: d.rows(), tmin: lo.view(), tmax: hi.view() };
        let scene = self.read(py)?;
        let (occ, bad) = py.detach(|| {
            self.on_threads(threads, || {
                let bvh = self.bvh_of(&scene);
                rays::occluded(bvh as &dyn Intersector, rays)
            })
        })?;
        drop(scene);
        if bad != usize::MAX {
            return Err(bad_ray(bad));
        }
        Ok(PyArray1::from_vec(py, occ))
    }

    /// Builds the BVH now (it is otherwise built by the first query or render) and returns
    /// what the build measured: seconds, nodes, leaves, depth, SAH cost, bytes.
    #[pyo3(signature = (*, threads=0))]
    fn build<'py>(&self, py: Python<'py>, threads: usize) -> PyResult<Bound<'py, PyAny>> {
        let scene = self.read(py)?;
        let info = py.detach(|| self.on_threads(threads, || self.bvh_of(&scene).info()))?;
        drop(scene);
        let json = serde_json::to_string(&info).map_err(|e| value_error(e.to_string()))?;
        py.import("json")?.call_method1("loads", (json,))
    }

    /// The camera rays of a width x height image (one per pixel centre, rows bottom-up), the
    /// peers' "primary" set, as a dict of "origins", "directions" (n, 3) float32 and "tmin",
    /// "tmax" (n,) float32.
    fn primary_rays<'py>(&self, py: Python<'py>, width: usize, height: usize) -> PyResult<Bound<'py, PyDict>> {
        if width == 0 || height == 0 {
            return Err(value_error("primary_rays needs a width and a height above 0"));
        }
        let scene = self.read(py)?;
        let rays = py.detach(|| wavepath::primary_rays(&scene, width, height));
        ray_dict(py, &rays)
    }

    /// One cosine-distributed bounce from each primary hit: the peers' "diffuse" set (what
    /// `wavepath rays dump --kind diffuse` writes for the same seed).
    #[pyo3(signature = (width, height, seed=0))]
    fn diffuse_rays<'py>(
        &self,
        py: Python<'py>,
        width: usize,
        height: usize,
        seed: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        if width == 0 || height == 0 {
            return Err(value_error("diffuse_rays needs a width and a height above 0"));
        }
        let scene = self.read(py)?;
        let rays = py.detach(|| {
            let primary = wavepath::primary_rays(&scene, width, height);
            let bvh = self.bvh_of(&scene);
            wavepath::diffuse_rays(&scene, bvh, &primary, seed)
        });
        ray_dict(py, &rays)
    }

    /// Vertex positions, (n, 3) float32 (a copy).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let s = self.read(py)?;
        let v: Vec<f32> = s.mesh.positions.iter().flat_map(|p| p.to_array()).collect();
        to_2d(py, v, s.mesh.positions.len(), 3)
    }

    /// Triangles as vertex indices, (m, 3) uint32 (a copy), in the file's order.
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<u32>>> {
        let s = self.read(py)?;
        let v: Vec<u32> = s.mesh.triangles.iter().flatten().copied().collect();
        to_2d(py, v, s.mesh.triangles.len(), 3)
    }

    #[getter]
    fn name(&self, py: Python<'_>) -> PyResult<String> {
        Ok(self.read(py)?.name.clone())
    }

    #[getter]
    fn triangle_count(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.read(py)?.mesh.triangle_count())
    }

    #[getter]
    fn sphere_count(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.read(py)?.spheres.len())
    }

    /// Material names, in index order.
    #[getter]
    fn materials(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        Ok(self.read(py)?.materials.iter().map(|m| m.name.clone()).collect())
    }

    /// Light kinds, in order ("area", "point", "hemisphere", ...).
    #[getter]
    fn lights(&self, py: Python<'_>) -> PyResult<Vec<&'static str>> {
        Ok(self.read(py)?.lights.iter().map(|l| l.kind()).collect())
    }

    /// The axis-aligned bounds as ((x, y, z), (x, y, z)).
    #[getter]
    fn bounds<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let (lo, hi) = self.read(py)?.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
        PyTuple::new(py, [lo.to_array(), hi.to_array()])
    }

    /// Which file dialect's defaults the scene's renders start from ("cs184" or "standard").
    #[getter]
    fn dialect(&self, py: Python<'_>) -> PyResult<&'static str> {
        Ok(self.read(py)?.source.dialect.name())
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let s = self.read(py)?;
        Ok(format!(
            "wavepath.Scene({:?}: {} triangles, {} spheres, {} materials, {} lights, {} dialect)",
            s.name,
            s.mesh.triangle_count(),
            s.spheres.len(),
            s.materials.len(),
            s.lights.len(),
            s.source.dialect.name()
        ))
    }
}

fn to_2d<T: numpy::Element>(py: Python<'_>, v: Vec<T>, rows: usize, cols: usize) -> PyResult<Bound<'_, PyArray2<T>>> {
    Ok(Array2::from_shape_vec((rows, cols), v).map_err(|e| value_error(e.to_string()))?.into_pyarray(py))
}

fn ray_dict<'py>(py: Python<'py>, rays: &[wavepath::Ray]) -> PyResult<Bound<'py, PyDict>> {
    let n = rays.len();
    let o: Vec<f32> = rays.iter().flat_map(|r| r.origin.to_array()).collect();
    let d: Vec<f32> = rays.iter().flat_map(|r| r.dir.to_array()).collect();
    let out = PyDict::new(py);
    out.set_item("origins", to_2d(py, o, n, 3)?)?;
    out.set_item("directions", to_2d(py, d, n, 3)?)?;
    out.set_item("tmin", PyArray1::from_vec(py, rays.iter().map(|r| r.tmin).collect()))?;
    out.set_item("tmax", PyArray1::from_vec(py, rays.iter().map(|r| r.tmax).collect()))?;
    Ok(out)
}

/// An image's interleaved channels (film rows, bottom first) as a numpy array, top row
/// first: (height, width, channels), or (height, width) for one channel.
fn film_rows<'py>(py: Python<'py>, w: usize, h: usize, c: usize, data: &[f32]) -> PyResult<Bound<'py, PyAny>> {
    let mut rows = Vec::with_capacity(w * h * c);
    for y in (0..h).rev() {
        rows.extend_from_slice(&data[y * w * c..(y + 1) * w * c]);
    }
    if c == 1 {
        let a = numpy::ndarray::Array2::from_shape_vec((h, w), rows).map_err(|e| value_error(e.to_string()))?;
        return Ok(a.into_pyarray(py).into_any());
    }
    let a = numpy::ndarray::Array3::from_shape_vec((h, w, c), rows).map_err(|e| value_error(e.to_string()))?;
    Ok(a.into_pyarray(py).into_any())
}
