//! Rendering one part: its bands of rows or its range of samples, into whole-image sums.

use super::spec::PartSpec;
use super::stats::PartStats;
use anyhow::Result;
use wavepath::Accumulator;
use wavepath::Intersector;
use wavepath::Scene;
use wavepath::Settings;

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
    // Each band is one ordinary render of a `-p` cell: the integrators give a pixel the same
    // sums whatever the cell, which is what makes the tile merge exact.
    for cell in spec.cells(s.image.width, s.image.height) {
        let mut part = s.clone();
        part.image.cell = Some(cell);
        part.sampling.sample_range = Some((first, end));
        let (sums, st) = wavepath::render_sums(scene, accel, &part, progress)?;
        stats.add_render(&st);
        let rows = cell.y * s.image.width..(cell.y + cell.h) * s.image.width;
        acc.pixels[rows.clone()].copy_from_slice(&sums.pixels[rows]);
    }
    Ok((acc, stats))
}
