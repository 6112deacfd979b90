//! `Scene.render`: keyword arguments as the engine's request (the command line's flags
//! become the same one), the render on its own thread without the GIL, and a waiting loop
//! that reports progress and honours Ctrl-C.

use crate::errors::{to_py, value_error};
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;
use wavepath::{
    Aov, AovSet, BuildInfo, Choice, Extent, Field, Intersector, RenderOutput, RenderPlan, RenderStats, Request, Scene,
    Settings,
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
    pub light_paths: Option<f64>,
    /// Output variables returned beside the image, by name.
    pub aovs: Option<Vec<String>>,
    /// The image is denoised (the albedo and normal it is fed are kept for it).
    pub denoise: bool,
}

/// Python's name for each checked value: the keyword argument's.
fn keyword(f: Field) -> &'static str {
    match f {
        Field::Width | Field::Height => "resolution",
        Field::Spp => "spp",
        Field::LightSamples => "light_samples",
        Field::MaxDepth => "max_depth",
        Field::Accumulate => "accumulate",
        Field::AdaptiveBatch | Field::AdaptiveTolerance => "adaptive",
        Field::Threads => "threads",
        Field::ContinueProb => "rr",
        Field::RouletteStart => "rr_depth",
        Field::CellX | Field::CellY | Field::CellWidth | Field::CellHeight => "cell",
        Field::LensRadius => "lens_radius",
        Field::FocalDistance => "focal_distance",
        Field::LightPaths => "light_paths",
    }
}

/// A setting's name given as a keyword argument, parsed by the engine's names.
fn choice<T: Choice>(option: &str, name: &Option<String>) -> PyResult<Option<T>> {
    name.as_deref().map(|n| T::from_name(n).map_err(|e| value_error(e.for_option(option).to_string()))).transpose()
}

/// The keyword arguments as the engine's request, which the command line's flags also
/// become: the same ranges, messages and rules.
pub fn request(o: &RenderOptions) -> PyResult<Request> {
    Ok(Request {
        resolution: o.resolution,
        spp: o.spp,
        light_samples: o.light_samples,
        max_depth: o.max_depth,
        accumulate: o.accumulate.map(i64::from),
        adaptive: o.adaptive,
        threads: o.threads,
        sampler: choice("sampler", &o.sampler)?,
        seed: o.seed,
        shading: choice("shading", &o.shading)?,
        integrator: choice("integrator", &o.integrator)?,
        hemisphere: o.hemisphere,
        mis: o.mis,
        roulette: choice("roulette", &o.roulette)?,
        rr: o.rr,
        rr_depth: o.rr_depth,
        isa: choice("isa", &o.isa)?,
        fov: choice("fov", &o.fov)?,
        lens_radius: o.lens_radius,
        focal_distance: o.focal_distance,
        light_paths: o.light_paths,
        aovs: Some(kept_aovs(o)?),
        ..Request::default()
    })
}

/// The output variables asked for by name (`aovs`), refused in one line if unknown.
pub fn asked_aovs(o: &RenderOptions) -> PyResult<AovSet> {
    let mut set = AovSet::NONE;
    for name in o.aovs.iter().flatten() {
        set = set.with(Aov::from_name(name).map_err(|e| value_error(e.for_option("aovs").to_string()))?);
    }
    Ok(set)
}

/// What the render keeps: the variables asked for and, to denoise, the albedo and normal.
fn kept_aovs(o: &RenderOptions) -> PyResult<AovSet> {
    let asked = asked_aovs(o)?;
    Ok(if o.denoise { asked.with(Aov::Albedo).with(Aov::Normal) } else { asked })
}

/// The settings of a render: [`Settings::for_scene`], then each option given (a left-out
/// option keeps the scene's default, as a flag left out does).
pub fn settings(scene: &Scene, r: &Request) -> PyResult<Settings> {
    r.apply(Settings::for_scene(scene), keyword).map_err(|e| value_error(e.to_string()))
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
