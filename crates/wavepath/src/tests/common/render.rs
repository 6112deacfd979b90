//! Small-image settings and the two integrators over brute-force intersection, shared by the
//! tests that compare renders (the engine's and the applications': only the face is used).

use wavepath::{Accumulator, BruteForce, IntegratorKind, RenderStats, Scene, Settings, Shading, render_sums};

/// A `width` x `height` render at depth `max_depth` (direct light at 1, global above) with
/// `spp` samples, the rest default.
pub fn settings(width: usize, height: usize, max_depth: u32, spp: u32) -> Settings {
    Settings::default().with(|s| {
        s.image.width = width;
        s.image.height = height;
        s.sampling.spp = spp;
        s.paths.max_depth = max_depth;
        s.paths.shading = if max_depth > 1 { Shading::Global } else { Shading::Direct }
    })
}

/// [`settings`] with two light samples.
pub fn small_settings(width: usize, height: usize, max_depth: u32, spp: u32) -> Settings {
    settings(width, height, max_depth, spp).with(|s| s.sampling.light_samples = 2)
}

fn with(scene: &Scene, s: &Settings, integrator: IntegratorKind) -> (Accumulator, RenderStats) {
    let mut s = s.clone();
    s.execution.integrator = integrator;
    render_sums(scene, &BruteForce::new(scene), &s, &|_| {}).expect("light transport keeps sums")
}

pub fn wavefront(scene: &Scene, s: &Settings) -> (Accumulator, RenderStats) {
    with(scene, s, IntegratorKind::Wavefront)
}

pub fn recursive(scene: &Scene, s: &Settings) -> (Accumulator, RenderStats) {
    with(scene, s, IntegratorKind::Recursive)
}
