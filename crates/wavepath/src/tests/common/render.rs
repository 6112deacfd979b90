//! Small-image settings and the two integrators over brute-force intersection, shared by the
//! tests that compare renders (the engine's and the applications': only the face is used).

use wavepath::{
    Accumulator, BruteForce, IntegratorKind, Intersector, RenderStats, Scene, Settings, Shading, render_sums,
};

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

/// The sums of a render of `scene` with `integrator`, whatever `s` names, over `accel`.
pub fn sums_with(
    integrator: IntegratorKind,
    scene: &Scene,
    accel: &dyn Intersector,
    s: &Settings,
    progress: &(dyn Fn(u64) + Sync),
) -> (Accumulator, RenderStats) {
    let mut s = s.clone();
    s.execution.integrator = integrator;
    render_sums(scene, accel, &s, progress).expect("light transport keeps sums")
}

fn with(scene: &Scene, s: &Settings, integrator: IntegratorKind) -> (Accumulator, RenderStats) {
    sums_with(integrator, scene, &BruteForce::new(scene), s, &|_| {})
}

pub fn wavefront(scene: &Scene, s: &Settings) -> (Accumulator, RenderStats) {
    with(scene, s, IntegratorKind::Wavefront)
}

pub fn recursive(scene: &Scene, s: &Settings) -> (Accumulator, RenderStats) {
    with(scene, s, IntegratorKind::Recursive)
}
