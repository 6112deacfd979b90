//! Turning a scene into a film: chooses the integrator the settings ask for.

mod normals;

pub use normals::render_normals;

use crate::accel::Intersector;
use crate::film::{Accumulator, AovImage, Film, PixelSums};
use crate::integrator::bidir::render_bidir_into;
use crate::integrator::plan::{Extent, RenderPlan};
use crate::integrator::recursive::render_recursive_into;
use crate::integrator::wavefront::{RenderJob, WaveWorkers, render_wavefront_into};
use crate::scene::Scene;
use crate::settings::{IntegratorKind, Settings, Shading};
use crate::stats::RenderStats;
use anyhow::Result;
use std::sync::atomic::AtomicBool;

/// A finished render: the image, its statistics, and the camera samples taken per pixel
/// of the whole image (for the sample-rate image).
pub struct RenderOutput {
    pub film: Film,
    pub stats: RenderStats,
    pub samples: Vec<u32>,
    /// The output variables the settings asked for (`image.aovs`), in [`crate::Aov::ALL`]'s order.
    pub aovs: Vec<AovImage>,
}

/// Renders `scene` with `settings`; the film covers the whole image, pixels outside a
/// `-p` cell stay black.
pub fn render(scene: &Scene, accel: &dyn Intersector, settings: &Settings) -> Result<(Film, RenderStats)> {
    let out = render_with_progress(scene, accel, settings, &|_| {})?;
    Ok((out.film, out.stats))
}

/// As [`render`]; `progress` is told how many camera samples have finished.
pub fn render_with_progress(
    scene: &Scene,
    accel: &dyn Intersector,
    settings: &Settings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RenderOutput> {
    render_until(scene, accel, settings, progress, &AtomicBool::new(false))
}

/// The error of a render that [`render_until`] was told to stop, inside the `anyhow::Error`
/// it returns: a caller tells it from a failure by type (`err.is::<Interrupted>()`), not by
/// its message, which may change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Interrupted;

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("render interrupted")
    }
}

impl std::error::Error for Interrupted {}

/// As [`render_with_progress`], for callers that may want the render to end early (an
/// interpreter's Ctrl-C, a closed window): once `stop` is set no new wave (or row, for the
/// recursive reference) starts, and the render ends with the error [`Interrupted`], after at
/// most one wave per thread.
pub fn render_until(
    scene: &Scene,
    accel: &dyn Intersector,
    settings: &Settings,
    progress: &(dyn Fn(u64) + Sync),
    stop: &AtomicBool,
) -> Result<RenderOutput> {
    render_plan(&RenderPlan::new(scene, settings), accel, Extent::of(settings), progress, stop)
}

/// Renders `extent` of `plan` (see [`render_until`] for `progress` and `stop`); the film
/// covers the whole image, pixels outside the extent's cell stay black. One plan renders any
/// number of extents without deriving anything from the scene again.
pub fn render_plan(
    plan: &RenderPlan,
    accel: &dyn Intersector,
    extent: Extent,
    progress: &(dyn Fn(u64) + Sync),
    stop: &AtomicBool,
) -> Result<RenderOutput> {
    let settings = plan.settings_in(extent);
    if settings.paths.shading == Shading::Normals {
        if !settings.image.aovs.is_empty() {
            anyhow::bail!("the normals view keeps no output variables; drop --aov or render light transport");
        }
        let (film, stats) = render_normals(plan.scene(), plan.camera(), accel, &settings);
        let samples = vec![settings.sampling.spp; film.pixels.len()];
        return Ok(RenderOutput { film, stats, samples, aovs: Vec::new() });
    }
    let (acc, stats) = transport(plan, &settings, accel, progress, stop)?;
    let aovs = acc.aov_images(settings.image.aovs);
    Ok(RenderOutput { film: acc.to_film(), samples: acc.samples_taken(), stats, aovs })
}

/// The per-pixel sums behind the film, for renders that are merged later (`--part`):
/// light transport only, since normals shading keeps no sums.
pub fn render_sums(
    scene: &Scene,
    accel: &dyn Intersector,
    settings: &Settings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(Accumulator, RenderStats)> {
    let plan = RenderPlan::new(scene, settings);
    render_plan_sums(&plan, accel, Extent::of(settings), progress, &AtomicBool::new(false))
}

/// [`render_sums`] of `extent` of `plan`, which may be stopped as [`render_until`]: the
/// sums of every pixel inside the extent, zero outside, so extents' sums merge into the
/// whole render's.
pub fn render_plan_sums(
    plan: &RenderPlan,
    accel: &dyn Intersector,
    extent: Extent,
    progress: &(dyn Fn(u64) + Sync),
    stop: &AtomicBool,
) -> Result<(Accumulator, RenderStats)> {
    transport(plan, &sums_settings(plan, extent)?, accel, progress, stop)
}

/// The settings of `extent` of `plan` for a render that keeps per-pixel sums: light
/// transport only, since normals shading keeps none.
fn sums_settings(plan: &RenderPlan, extent: Extent) -> Result<Settings> {
    let s = plan.settings_in(extent);
    if s.paths.shading == Shading::Normals {
        anyhow::bail!("normals shading keeps no per-pixel sums");
    }
    Ok(s)
}

/// Light transport of the part `settings` covers with the integrator it asks for, into a
/// canvas of its own.
fn transport(
    plan: &RenderPlan,
    settings: &Settings,
    accel: &dyn Intersector,
    progress: &(dyn Fn(u64) + Sync),
    stop: &AtomicBool,
) -> Result<(Accumulator, RenderStats)> {
    let (w, h) = (settings.image.width, settings.image.height);
    let sums = Accumulator::with_aovs(w, h, settings.image.aovs.traced());
    let mut canvas = Canvas { sums, workers: WaveWorkers::for_current_pool() };
    let stats = canvas.add(plan, settings, accel, progress, stop)?;
    Ok((canvas.sums, stats))
}

/// The sums of one image that many renders of extents of one plan add into, and the worker
/// threads' queues they share: the viewer renders a band of rows after another without a
/// whole image's sums and a set of queues allocated per band (each costs page faults of its
/// own), and its threads keep their caches warm from band to band. A pixel's sums are those
/// of one render of all its extents.
pub struct Canvas {
    sums: Accumulator,
    workers: WaveWorkers,
}

impl Canvas {
    /// Zero sums for a `width x height` image; queues for the threads of the current rayon
    /// pool (render on the same pool).
    pub fn new(width: usize, height: usize) -> Canvas {
        Canvas { sums: Accumulator::new(width, height), workers: WaveWorkers::for_current_pool() }
    }

    /// As [`new`](Self::new), keeping first-hit sums for the output variables `aovs` (when
    /// [`AovSet::traced`](crate::settings::AovSet::traced)); renders into it may then ask for
    /// any of them.
    pub fn with_aovs(width: usize, height: usize, aovs: crate::settings::AovSet) -> Canvas {
        let sums = Accumulator::with_aovs(width, height, aovs.traced());
        Canvas { sums, workers: WaveWorkers::for_current_pool() }
    }

    /// The images of the output variables `aovs` from the sums added so far (first-hit ones
    /// are zero unless the canvas keeps them: [`with_aovs`](Self::with_aovs)).
    pub fn aov_images(&self, aovs: crate::settings::AovSet) -> Vec<AovImage> {
        self.sums.aov_images(aovs)
    }

    /// The sums added so far.
    pub fn sums(&self) -> &Accumulator {
        &self.sums
    }

    /// Back to zero sums, keeping the memory and the queues (a new view of the same size).
    pub fn clear(&mut self) {
        self.sums.pixels.fill(PixelSums::default());
        self.sums.aovs.fill(Default::default());
    }

    /// Renders `extent` of `plan` (an image of the canvas's size) into the sums; stopped as
    /// [`render_until`] (a stopped render has added part of its extent). The statistics'
    /// samples per pixel and invalid samples are the canvas's in the extent's region.
    pub fn render(
        &mut self,
        plan: &RenderPlan,
        accel: &dyn Intersector,
        extent: Extent,
        progress: &(dyn Fn(u64) + Sync),
        stop: &AtomicBool,
    ) -> Result<RenderStats> {
        let s = sums_settings(plan, extent)?;
        if (s.image.width, s.image.height) != (self.sums.width, self.sums.height) {
            anyhow::bail!(
                "a {}x{} render cannot add into a {}x{} canvas",
                s.image.width,
                s.image.height,
                self.sums.width,
                self.sums.height
            );
        }
        self.add(plan, &s, accel, progress, stop)
    }

    /// Light transport of the part `settings` (an image of the canvas's size) covers, added
    /// into the sums by the integrator the settings ask for.
    fn add(
        &mut self,
        plan: &RenderPlan,
        settings: &Settings,
        accel: &dyn Intersector,
        progress: &(dyn Fn(u64) + Sync),
        stop: &AtomicBool,
    ) -> Result<RenderStats> {
        if settings.image.aovs.traced() && self.sums.aovs.len() != self.sums.pixels.len() {
            anyhow::bail!("this canvas keeps no first-hit sums for the output variables {}", settings.image.aovs);
        }
        let done = match settings.execution.integrator {
            IntegratorKind::Auto | IntegratorKind::Wavefront | IntegratorKind::PathLight => {
                if settings.execution.integrator == IntegratorKind::PathLight {
                    if let Some(why) = crate::integrator::bidir::unsupported(plan.transport(), settings) {
                        anyhow::bail!(why);
                    }
                    if plan.transport().caustics.is_none() {
                        anyhow::bail!("path+light: the camera cannot be inverted");
                    }
                }
                let (transport, effects, lanes) = (plan.transport(), plan.effects(), plan.lanes());
                let splats = plan.kept_splats();
                let job = RenderJob { transport, effects, lanes, splats, settings, accel, progress, stop };
                render_wavefront_into(&job, &self.workers, &mut self.sums)
            }
            IntegratorKind::Recursive if settings.image.aovs.traced() => anyhow::bail!(
                "the recursive reference records no first hits: --aov {} needs the wavefront integrator",
                settings.image.aovs
            ),
            IntegratorKind::Recursive => {
                render_recursive_into(plan.transport(), settings, accel, progress, stop, &mut self.sums)
            }
            kind @ (IntegratorKind::Light | IntegratorKind::Bdpt | IntegratorKind::Vcm) => {
                if settings.image.aovs.traced() {
                    anyhow::bail!(
                        "{} records no first hits: --aov {} needs the wavefront integrator",
                        kind.name(),
                        settings.image.aovs
                    );
                }
                let mode = crate::integrator::bidir::Mode::of(kind).expect("a bidirectional integrator");
                render_bidir_into(plan.transport(), settings, accel, mode, progress, stop, &mut self.sums)?
            }
        };
        done.ok_or_else(|| anyhow::Error::new(Interrupted))
    }
}

/// Runs `f` on a rayon pool with `threads` workers (0 = all cores).
pub fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> Result<T> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    Ok(pool.install(f))
}
