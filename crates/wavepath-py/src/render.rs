//! `Scene.render`: the command line's settings from keyword arguments, the render on its own
//! thread without the GIL, and a waiting loop that reports progress and honours Ctrl-C.

use crate::errors::{to_py, value_error};
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;
use wavepath::{
    BuildInfo, Camera, Extent, IntegratorKind, Intersector, Isa, RenderOutput, RenderPlan, RenderStats, RouletteKind,
    SamplerKind, Scene, Settings, Shading,
};

/// How often the waiting loop looks at Ctrl-C and calls the progress callback.
const POLL: Duration = Duration::from_millis(50);

/// The keyword arguments of `Scene.render`, each `None` where the caller left it out (the
/// scene's defaults, as the command line's, then stand).
#[derive(Default)]
pub struct RenderOptions {
    pub spp: Option<i64>,
    pub light_samples: Option<i64>,
    pub max_depth: Option<i64>,
    pub accumulate: Option<bool>,
    pub resolution: Option<(i64, i64)>,
    pub threads: Option<i64>,
    pub sampler: Option<String>,
    pub seed: Option<u64>,
    pub adaptive: Option<(f64, f64)>,
    pub shading: Option<String>,
    pub integrator: Option<String>,
    pub hemisphere: Option<bool>,
    pub mis: Option<bool>,
    pub roulette: Option<String>,
    pub rr: Option<f64>,
    pub rr_depth: Option<i64>,
    pub isa: Option<String>,
    pub fov: Option<String>,
    pub lens_radius: Option<f64>,
    pub focal_distance: Option<f64>,
}

/// Largest image side and pixel count, as the command line's `-r`.
const MAX_SIDE: i64 = 1 << 15;
const MAX_PIXELS: i64 = 1 << 28;

fn in_range(name: &str, v: i64, lo: i64, hi: i64) -> PyResult<i64> {
    if v < lo || v > hi {
        return Err(value_error(format!("{name} must be between {lo} and {hi}, got {v}")));
    }
    Ok(v)
}

/// The settings of a render: [`Settings::for_scene`], then each option given, with the
/// command line's ranges and rules (the shading follows the depth: [`Shading::for_depth`]).
pub fn settings(scene: &Scene, o: &RenderOptions) -> PyResult<Settings> {
    let mut s = Settings::for_scene(scene);
    if let Some((w, h)) = o.resolution {
        let w = in_range("resolution width", w, 1, MAX_SIDE)?;
        let h = in_range("resolution height", h, 1, MAX_SIDE)?;
        if w * h > MAX_PIXELS {
            return Err(value_error(format!(
                "resolution ({w}, {h}) is {} pixels, more than the limit of {MAX_PIXELS}",
                w * h
            )));
        }
        s.image.width = w as usize;
        s.image.height = h as usize;
    }
    // Left out, an option keeps the library's default for the scene (as a flag left out does).
    if let Some(v) = o.spp {
        s.sampling.spp = in_range("spp (samples per pixel)", v, 1, 1 << 20)? as u32;
    }
    if let Some(v) = o.light_samples {
        s.sampling.light_samples = in_range("light_samples (samples per area light)", v, 1, 1 << 16)? as u32;
    }
    if let Some(v) = o.max_depth {
        s.paths.max_depth = in_range("max_depth (maximum ray depth)", v, 0, 1 << 12)? as u32;
    }
    if let Some(v) = o.accumulate {
        s.paths.accumulate = v;
    }
    if let Some((b, t)) = o.adaptive {
        if !(b.is_finite() && b >= 1.0 && b <= (1u32 << 20) as f64 && b.fract() == 0.0) {
            return Err(value_error(format!(
                "adaptive batch size must be a whole number between 1 and {}, got {b}",
                1u32 << 20
            )));
        }
        if !(t.is_finite() && t > 0.0) {
            return Err(value_error(format!("adaptive tolerance must be a positive number, got {t}")));
        }
        s.sampling.adaptive = Some((b as u32, t as f32));
    }
    if let Some(t) = o.threads {
        s.execution.threads = in_range("threads", t, 0, 4096)? as usize;
    }
    let rr = o.rr.unwrap_or(s.paths.roulette.continue_prob as f64);
    if !(rr.is_finite() && rr > 0.0 && rr <= 1.0) {
        return Err(value_error(format!("rr must be in (0, 1], got {rr}")));
    }
    s.paths.roulette.continue_prob = rr as f32;
    if let Some(k) = &o.roulette {
        s.paths.roulette.kind = match k.as_str() {
            "fixed" => RouletteKind::Fixed,
            "throughput" => RouletteKind::Throughput,
            other => return Err(value_error(format!("roulette must be \"fixed\" or \"throughput\", got \"{other}\""))),
        };
        s.paths.roulette.start_depth = s.paths.roulette.kind.default_start_depth();
    }
    if let Some(d) = o.rr_depth {
        s.paths.roulette.start_depth = in_range("rr_depth", d, 1, 1 << 16)? as u32;
    }
    if let Some(v) = o.hemisphere {
        s.paths.hemisphere = v;
    }
    if let Some(v) = o.mis {
        s.paths.mis = v;
    }
    if let Some(isa) = &o.isa {
        s.execution.isa = Isa::parse(isa)
            .ok_or_else(|| value_error(format!("unknown instruction set \"{isa}\" (scalar, sse, avx2, avx512)")))?;
    }
    if let Some(v) = o.seed {
        s.sampling.seed = v;
    }
    if let Some(i) = &o.integrator {
        s.execution.integrator = match i.as_str() {
            "wavefront" => IntegratorKind::Wavefront,
            "recursive" => IntegratorKind::Recursive,
            other => {
                return Err(value_error(format!("integrator must be \"wavefront\" or \"recursive\", got \"{other}\"")));
            }
        };
    }
    if let Some(k) = &o.sampler {
        s.sampling.sampler = match k.as_str() {
            "independent" => SamplerKind::Independent,
            "stratified" => SamplerKind::Stratified,
            "sobol" => SamplerKind::Sobol,
            other => {
                return Err(value_error(format!(
                    "sampler must be \"independent\", \"stratified\" or \"sobol\", got \"{other}\""
                )));
            }
        };
    }
    s.paths.shading = match o.shading.as_deref() {
        None => Shading::for_depth(s.paths.max_depth),
        Some("normals") => Shading::Normals,
        Some("direct") => Shading::Direct,
        Some("global") => Shading::Global,
        Some(other) => {
            return Err(value_error(format!("shading must be \"normals\", \"direct\" or \"global\", got \"{other}\"")));
        }
    };
    if let Some(b) = o.lens_radius
        && !(b.is_finite() && b >= 0.0)
    {
        return Err(value_error(format!("lens_radius must be a non-negative number, got {b}")));
    }
    if let Some(d) = o.focal_distance
        && !(d.is_finite() && d > 0.0)
    {
        return Err(value_error(format!("focal_distance must be a positive number, got {d}")));
    }
    Ok(s)
}

/// The camera of this render: the given one or the scene's, fitted to the image by the
/// `fov` rule (`"cs184"`, the command line's default, or `"frame"`), with lens overrides.
pub fn camera(base: Camera, s: &Settings, o: &RenderOptions) -> PyResult<Camera> {
    let mut cam = base;
    match o.fov.as_deref() {
        None | Some("cs184") => {}
        Some("frame") => cam.whole_frame(),
        Some(other) => return Err(value_error(format!("fov must be \"cs184\" or \"frame\", got \"{other}\""))),
    }
    cam.fit_to(s.image.width as f32, s.image.height as f32);
    if let Some(b) = o.lens_radius {
        cam.lens_radius = b as f32;
    }
    if let Some(d) = o.focal_distance {
        cam.focal_distance = d as f32;
    }
    Ok(cam)
}

/// A finished render and what the command line would print of it.
pub struct Rendered {
    pub out: RenderOutput,
    pub stats_json: String,
    pub log: Vec<String>,
}

/// Renders on a thread of its own while this (Python's) thread waits without the GIL, every
/// [`POLL`] taking it back for a moment to call `progress(done, total)` and to see whether
/// Ctrl-C was pressed; either raising stops the render after its current waves.
pub fn run(
    py: Python<'_>,
    scene: &Scene,
    accel: &(dyn Intersector + Sync),
    build: BuildInfo,
    s: &Settings,
    progress: Option<&Py<PyAny>>,
) -> PyResult<Rendered> {
    let stop = AtomicBool::new(false);
    let done = AtomicU64::new(0);
    let r = s.region();
    let total = (r.w * r.h) as u64 * s.sampling.spp.max(1) as u64;
    let (result, raised) = py.detach(|| {
        std::thread::scope(|sc| {
            let (tx, rx) = std::sync::mpsc::channel();
            let (stop, done) = (&stop, &done);
            sc.spawn(move || {
                let tick = |n: u64| {
                    done.fetch_add(n, Ordering::Relaxed);
                };
                // The plan is built on the render's thread, without the GIL; its effects go
                // back with the image for the stats.
                let out = wavepath::with_threads(s.execution.threads, || {
                    let plan = RenderPlan::new(scene, s);
                    let out = wavepath::render_plan(&plan, accel, Extent::of(s), &tick, stop)?;
                    Ok((out, plan.effects().clone()))
                })
                .and_then(|r| r);
                let _ = tx.send(out);
            });
            let mut raised: Option<PyErr> = None;
            loop {
                match rx.recv_timeout(POLL) {
                    Ok(out) => return (out, raised),
                    Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                        return (Err(anyhow::anyhow!("the render thread ended without a result")), raised);
                    }
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
                }
                if raised.is_some() {
                    continue;
                }
                let check = Python::attach(|py| -> PyResult<()> {
                    if let Some(cb) = progress {
                        cb.call1(py, (done.load(Ordering::Relaxed), total))?;
                    }
                    py.check_signals()
                });
                if let Err(e) = check {
                    stop.store(true, Ordering::Relaxed);
                    raised = Some(e);
                }
            }
        })
    });
    if let Some(e) = raised {
        return Err(e);
    }
    let (out, effects) = result.map_err(to_py)?;
    if let Some(cb) = progress {
        cb.call1(py, (done.load(Ordering::Relaxed), total))?;
    }
    let json = wavepath::stats_json(scene, s, &effects, &build, &out.stats);
    let stats_json = serde_json::to_string(&json).map_err(|e| value_error(e.to_string()))?;
    let log = log_lines(&out.stats);
    Ok(Rendered { out, stats_json, log })
}

fn log_lines(st: &RenderStats) -> Vec<String> {
    st.log_lines()
}
