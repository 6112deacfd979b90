//! Turning a scene into a film: chooses the integrator the settings ask for.

mod normals;

pub use normals::render_normals;

use crate::accel::Intersector;
use crate::film::Film;
use crate::scene::Scene;
use crate::settings::{Settings, Shading};
use crate::stats::RenderStats;
use anyhow::{Result, bail};

/// Renders `scene` with `settings`; the film covers the whole image, pixels outside a
/// `-p` cell stay black.
pub fn render(scene: &Scene, accel: &dyn Intersector, settings: &Settings) -> Result<(Film, RenderStats)> {
    match settings.shading {
        Shading::Normals => Ok(render_normals(scene, accel, settings)),
        Shading::Direct | Shading::Global => {
            bail!(
                "--shading direct/global is not yet supported (the wavefront integrator is in progress); use --shading normals"
            )
        }
    }
}

/// Runs `f` on a rayon pool with `threads` workers (0 = all cores).
pub fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> Result<T> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    Ok(pool.install(f))
}
