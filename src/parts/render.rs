//! Rendering one part: its bands of rows or its range of samples, into whole-image sums.

use super::spec::PartSpec;
use super::stats::PartStats;
use anyhow::Result;
use std::sync::atomic::AtomicBool;
use wavepath::Accumulator;
use wavepath::Intersector;
use wavepath::Scene;
use wavepath::Settings;
use wavepath::{Extent, RenderPlan};

/// Renders part `spec` of the render `s` describes; pixels the part does not own keep
/// zero sums. `progress` is told how many camera samples finished.
pub fn render_part(
    scene: &Scene,
    accel: &dyn Intersector,
    s: &Settings,
    spec: &PartSpec,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(Accumulator, PartStats)> {
    spec.check(s)?;
    let mut stats = PartStats::default();
    let (first, end) = spec.sample_range(s.sampling.spp);
    let mut acc = Accumulator::new(s.image.width, s.image.height);
    // Each band is one render of a `-p` cell with the part's one plan: the integrators give a
    // pixel the same sums whatever the cell, which is what makes the tile merge exact.
    let plan = RenderPlan::new(scene, s);
    let never = AtomicBool::new(false);
    for cell in spec.cells(s.image.width, s.image.height) {
        let extent = Extent { cell: Some(cell), samples: Some((first, end)) };
        let (sums, st) = wavepath::render_plan_sums(&plan, accel, extent, progress, &never)?;
        stats.add_render(&st);
        let rows = cell.y * s.image.width..(cell.y + cell.h) * s.image.width;
        acc.pixels[rows.clone()].copy_from_slice(&sums.pixels[rows]);
    }
    Ok((acc, stats))
}
