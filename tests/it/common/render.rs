//! Small-image settings and the two integrators over brute-force intersection, shared by the
//! integration tests that compare renders.

use wavepath::accel::BruteForce;
use wavepath::film::Accumulator;
use wavepath::integrator::recursive::render_recursive;
use wavepath::integrator::wavefront::render_wavefront;
use wavepath::scene::Scene;
use wavepath::settings::{Settings, Shading};
use wavepath::stats::RenderStats;

/// A `width` x `height` render at depth `max_depth` (direct light at 1, global above) with
/// `spp` samples, the rest default.
pub fn settings(width: usize, height: usize, max_depth: u32, spp: u32) -> Settings {
    Settings {
        width,
        height,
        spp,
        max_depth,
        shading: if max_depth > 1 { Shading::Global } else { Shading::Direct },
        ..Settings::default()
    }
}

/// [`settings`] with two light samples.
pub fn small_settings(width: usize, height: usize, max_depth: u32, spp: u32) -> Settings {
    Settings { light_samples: 2, ..settings(width, height, max_depth, spp) }
}

pub fn wavefront(scene: &Scene, s: &Settings) -> (Accumulator, RenderStats) {
    render_wavefront(scene, &BruteForce::new(scene), s, &|_| {})
}

pub fn recursive(scene: &Scene, s: &Settings) -> (Accumulator, RenderStats) {
    render_recursive(scene, &BruteForce::new(scene), s, &|_| {})
}
