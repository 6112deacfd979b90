//! The render flags as the engine's [`Request`]: the engine checks every range and applies
//! the values, so a bad value gets the message Python and the viewer give, under the flag's
//! name.

use super::RenderArgs;
use anyhow::Result;
use wavepath::{Aov, AovSet, Field, Request, Settings};

/// The command line's name for each checked value, as its messages show it.
pub fn flag(f: Field) -> &'static str {
    match f {
        Field::Width | Field::Height => "-r",
        Field::Spp => "-s",
        Field::LightSamples => "-l",
        Field::MaxDepth => "-m",
        Field::Accumulate => "-o",
        Field::AdaptiveBatch | Field::AdaptiveTolerance => "-a",
        Field::Threads => "-t",
        Field::ContinueProb => "--rr",
        Field::RouletteStart => "--rr-depth",
        Field::CellX | Field::CellY | Field::CellWidth | Field::CellHeight => "-p",
        Field::LensRadius => "-b",
        Field::FocalDistance => "-d",
        Field::LightPaths => "--light-paths",
    }
}

/// The render flags as a request: every flag with a default is given (its default is the
/// command line's), the others only when the user gave them.
pub fn request(a: &RenderArgs) -> Request {
    Request {
        resolution: a.resolution.as_ref().map(|r| (r[0], r[1])),
        cell: a.cell.as_ref().map(|p| [p[0], p[1], p[2], p[3]]),
        spp: Some(a.spp),
        light_samples: Some(a.light_samples),
        adaptive: a.adaptive.as_ref().map(|v| (v[0], v[1])),
        sampler: a.sampler,
        seed: Some(a.seed),
        max_depth: Some(a.max_depth),
        accumulate: Some(a.accumulate),
        shading: a.shading,
        hemisphere: Some(a.hemisphere),
        mis: Some(!a.no_mis),
        roulette: a.roulette,
        rr: Some(a.rr),
        rr_depth: a.rr_depth,
        use_bvh: Some(!a.no_bvh),
        bvh_build: Some(a.bvh_build),
        bvh_leaves: Some(a.bvh_leaves),
        threads: a.threads,
        integrator: Some(a.integrator),
        isa: Some(a.isa),
        all_effects: Some(a.all_effects),
        cs184_light_pdf: Some(a.cs184_light_pdf),
        fov: Some(a.fov),
        lens_radius: a.lens_radius,
        focal_distance: a.focal_distance,
        light_paths: a.light_paths,
        aovs: Some(kept_aovs(a)),
    }
}

/// The output variables the render keeps: those asked for with `--aov`, and the albedo and
/// normal a denoiser is fed.
pub fn kept_aovs(a: &RenderArgs) -> AovSet {
    let asked = a.aov.iter().fold(AovSet::NONE, |s, &v| s.with(v));
    if a.denoise { asked.with(Aov::Albedo).with(Aov::Normal) } else { asked }
}

/// The flags applied on top of `base`, normally [`Settings::for_scene`] of the loaded scene:
/// a flag the user gave overrides the dialect's default, one left out keeps it.
pub fn settings(a: &RenderArgs, base: Settings) -> Result<Settings> {
    Ok(request(a).apply(base, flag)?)
}
