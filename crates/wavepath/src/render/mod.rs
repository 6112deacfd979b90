//! Turning a scene into a film: chooses the integrator the settings ask for.

mod normals;

pub use normals::render_normals;

use crate::accel::Intersector;
use crate::film::{Accumulator, Film};
use crate::integrator::recursive::{render_recursive, render_recursive_until};
use crate::integrator::wavefront::{render_wavefront, render_wavefront_until};
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

/// The error of a render that [`render_until`] was told to stop.
pub const INTERRUPTED: &str = "render interrupted";

/// As [`render_with_progress`], for callers that may want the render to end early (an
/// interpreter's Ctrl-C, a closed window): once `stop` is set no new wave (or row, for the
/// recursive reference) starts, and the render ends with an error that says it was
/// interrupted, after at most one wave per thread.
pub fn render_until(
    scene: &Scene,
    accel: &dyn Intersector,
    settings: &Settings,
    progress: &(dyn Fn(u64) + Sync),
    stop: &AtomicBool,
) -> Result<RenderOutput> {
    let done = match settings.paths.shading {
        Shading::Normals => {
            let (film, stats) = render_normals(scene, accel, settings);
            let samples = vec![settings.sampling.spp; film.pixels.len()];
            return Ok(RenderOutput { film, stats, samples });
        }
        Shading::Direct | Shading::Global => match settings.execution.integrator {
            IntegratorKind::Wavefront => render_wavefront_until(scene, accel, settings, progress, stop),
            IntegratorKind::Recursive => render_recursive_until(scene, accel, settings, progress, stop),
        },
    };
    let Some((acc, stats)) = done else { return Err(anyhow::anyhow!(INTERRUPTED)) };
    Ok(RenderOutput { film: acc.to_film(), samples: acc.samples_taken(), stats })
}

/// The per-pixel sums behind the film, for renders that are merged later (`--part`):
/// light transport only, since normals shading keeps no sums.
pub fn render_sums(
    scene: &Scene,
    accel: &dyn Intersector,
    settings: &Settings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(Accumulator, RenderStats)> {
    Ok(match (settings.paths.shading, settings.execution.integrator) {
        (Shading::Normals, _) => anyhow::bail!("normals shading keeps no per-pixel sums"),
        (_, IntegratorKind::Wavefront) => render_wavefront(scene, accel, settings, progress),
        (_, IntegratorKind::Recursive) => render_recursive(scene, accel, settings, progress),
    })
}

/// Runs `f` on a rayon pool with `threads` workers (0 = all cores).
pub fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> Result<T> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    Ok(pool.install(f))
}
