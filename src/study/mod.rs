//! "What accuracy costs in time": sweeps one setting, renders each value at a ladder of
//! sample counts, and measures wall time, rays traced and the error against a converged
//! reference, so a user sees which setting buys the most accuracy per second.
//!
//! The reference is rendered once per scene and settings and cached (see [`reference`]);
//! it uses its own seed so it shares no random numbers with the renders it judges.
//!
//! The denoise sweep measures each render twice: as rendered, and denoised by Open Image
//! Denoise with the render's albedo and normal ([`denoise_point`]), both against the same
//! raw reference.

pub mod metrics;
pub mod plot;
pub mod reference;
pub mod report;
pub mod sweep;

pub use metrics::{ErrorStats, Reference, compare, compare_film, log_log_slope};
pub use sweep::{Curve, Ladder, SweepKind, curves, spp_ladder};

use anyhow::{Result, bail};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use wavepath::Film;
use wavepath::Intersector;
use wavepath::Scene;
use wavepath::Settings;
use wavepath::{Accumulator, Aov, Aux, Denoiser};
use wavepath::{InvalidValue, Names, Request};

/// The settings every render of a study starts from: the scene's defaults
/// ([`Settings::for_scene`], so a study measures the estimator a render of the scene uses,
/// roulette and sampler included), then the caller's request (resolution, depth, light
/// samples...), at one sample per pixel (the ladders set the count). A sweep then changes
/// only the value it sweeps.
pub fn base_settings(scene: &Scene, request: &Request, names: Names) -> Result<Settings, InvalidValue> {
    let mut s = request.apply(Settings::for_scene(scene), names)?;
    s.sampling.spp = 1;
    s.sampling.adaptive = None;
    Ok(s)
}

/// What a study runs.
#[derive(Clone, Debug)]
pub struct StudyConfig {
    pub sweep: SweepKind,
    /// What every render starts from ([`base_settings`]).
    pub base: Settings,
    /// Largest samples per pixel of a ladder (and the adaptive sweep's maximum).
    pub max_spp: u32,
    /// Samples per pixel of the reference.
    pub ref_spp: u32,
    /// A ladder stops after the first render slower than this many seconds (the next one
    /// would take about twice as long).
    pub time_budget: f64,
    pub cache_dir: PathBuf,
    /// Open Image Denoise, for sweeps that denoise ([`SweepKind::needs_denoiser`]; others
    /// ignore it).
    pub denoiser: Option<Arc<Denoiser>>,
}

/// One measured render.
#[derive(Clone, Debug)]
pub struct Point {
    /// Index into [`StudyResult::curves`].
    pub curve: usize,
    pub settings: Settings,
    /// Adaptive tolerance, if the render was adaptive.
    pub tolerance: Option<f32>,
    /// Wall time: the render's, plus the denoising's for a denoised point.
    pub seconds: f64,
    /// Of `seconds`, what denoising took (a denoised point only).
    pub denoise_seconds: Option<f64>,
    pub rays: u64,
    pub invalid_samples: u64,
    /// Against the reference; a denoised point's has no variance-based fields
    /// ([`ErrorStats::has_variance`]).
    pub error: ErrorStats,
    /// The image measured (denoised, for a denoised point).
    pub film: Film,
    /// Camera samples each pixel took.
    pub samples: Vec<u32>,
}

/// Everything a study measured.
#[derive(Clone, Debug)]
pub struct StudyResult {
    pub sweep: SweepKind,
    pub curves: Vec<Curve>,
    pub points: Vec<Point>,
    pub reference: Reference,
    pub reference_settings: Settings,
    pub reference_info: reference::ReferenceInfo,
}

impl StudyResult {
    pub fn curve_points(&self, curve: usize) -> impl Iterator<Item = &Point> {
        self.points.iter().filter(move |p| p.curve == curve)
    }

    /// The time every curve reaches (the smallest of the curves' longest renders), and for
    /// each curve its point closest to that time (log scale): the equal-time comparison.
    pub fn equal_time(&self) -> (f64, Vec<Option<&Point>>) {
        let longest: Vec<f64> = (0..self.curves.len())
            .map(|c| self.curve_points(c).map(|p| p.seconds).fold(0.0, f64::max))
            .filter(|&t| t > 0.0)
            .collect();
        let target = longest.iter().copied().fold(f64::INFINITY, f64::min);
        let picks = (0..self.curves.len())
            .map(|c| {
                self.curve_points(c).min_by(|a, b| {
                    let da = (a.seconds.max(1e-9) / target).ln().abs();
                    let db = (b.seconds.max(1e-9) / target).ln().abs();
                    da.total_cmp(&db)
                })
            })
            .collect();
        (target, picks)
    }
}

/// Runs the study on a loaded scene. `identity` is what keys the reference cache (the scene
/// file's bytes), `stem` names the cache entry; `log` is told what is happening.
pub fn run(
    scene: &Scene,
    accel: &dyn Intersector,
    identity: &[u8],
    camera_label: &str,
    stem: &str,
    cfg: &StudyConfig,
    log: &dyn Fn(&str),
) -> Result<StudyResult> {
    let curves = curves(cfg.sweep, &cfg.base);
    let denoiser = match (&cfg.denoiser, curves.iter().any(|c| matches!(c.ladder, Ladder::Denoised { .. }))) {
        (None, true) => bail!("the {} sweep needs Open Image Denoise; {}", cfg.sweep.name(), wavepath::OIDN_HELP),
        (d, true) => d.as_deref(),
        (_, false) => None,
    };
    let mut ref_base = cfg.base.clone();
    if cfg.sweep.needs_deep_reference() {
        ref_base.paths.max_depth = ref_base.paths.max_depth.max(sweep::DEEP);
        ref_base.paths.shading = wavepath::Shading::Global;
    }
    let ref_settings = reference::reference_settings(&ref_base, cfg.ref_spp);
    log(&format!(
        "reference: {}x{} at {} spp, -l {} -m {}",
        ref_settings.image.width,
        ref_settings.image.height,
        ref_settings.sampling.spp,
        ref_settings.sampling.light_samples,
        ref_settings.paths.max_depth
    ));
    let (reference, reference_info) =
        reference::reference(scene, accel, &ref_settings, identity, camera_label, &cfg.cache_dir, stem)?;
    log(&if reference_info.cached {
        format!("reference: reused {}", reference_info.path.display())
    } else {
        format!("reference: rendered in {:.2} s -> {}", reference_info.seconds, reference_info.path.display())
    });
    // One untimed render first (and one untimed denoising), so thread start-up and cold
    // caches do not land on the first measured point.
    if let Some(d) = denoiser {
        log(&format!("denoiser: Open Image Denoise, {}", d.library().display()));
        let warm = curves[0].settings.clone().with(|s| s.sampling.spp = 1);
        let (acc, _) = wavepath::render_sums(scene, accel, &warm, &|_| {})?;
        denoise_film(d, &acc)?;
    } else {
        let _ = wavepath::render_sums(scene, accel, &cfg.base, &|_| {})?;
    }
    let mut points = Vec::new();
    for (ci, c) in curves.iter().enumerate() {
        let runs: Vec<(Settings, Option<f32>)> = match &c.ladder {
            Ladder::Spp => spp_ladder(cfg.max_spp)
                .into_iter()
                .map(|s| (c.settings.clone().with(|t| t.sampling.spp = s), None))
                .collect(),
            Ladder::Tolerances(ts) => ts
                .iter()
                .map(|&t| {
                    let batch = sweep::ADAPTIVE_BATCH.min(cfg.max_spp.max(1));
                    (
                        c.settings.clone().with(|s| {
                            s.sampling.spp = cfg.max_spp.max(1);
                            s.sampling.adaptive = Some((batch, t))
                        }),
                        Some(t),
                    )
                })
                .collect(),
            // Made from the renders of the curve it denoises, below.
            Ladder::Denoised { .. } => continue,
        };
        // The curve of this curve's renders denoised, if any.
        let denoised = curves.iter().position(|d| d.ladder == Ladder::Denoised { of: ci });
        for (s, tolerance) in runs {
            let (p, acc) = render_point(scene, accel, &s, tolerance, ci, &reference)?;
            log(&format!(
                "{:<28} spp {:>5} {}{:>8.3} s  {:>10} rays  rmse {:.5}  relMSE {:.5}  ci95 {:.5}",
                c.label,
                s.sampling.spp,
                tolerance.map(|t| format!("T {t:<5} mean spp {:>7.1} ", p.error.mean_spp)).unwrap_or_default(),
                p.seconds,
                p.rays,
                p.error.rmse,
                p.error.rel_mse,
                p.error.ci95
            ));
            let mut slow = p.seconds > cfg.time_budget;
            let dp = match (denoised, denoiser) {
                (Some(di), Some(d)) => Some(denoise_point(d, &p, &acc, di, &reference)?),
                _ => None,
            };
            points.push(p);
            if let Some(dp) = dp {
                log(&format!(
                    "{:<28} spp {:>5} {:>8.3} s  (denoising {:.3} s)  rmse {:.5}  relMSE {:.5}  (biased)",
                    curves[dp.curve].label,
                    s.sampling.spp,
                    dp.seconds,
                    dp.denoise_seconds.unwrap_or(0.0),
                    dp.error.rmse,
                    dp.error.rel_mse
                ));
                slow |= dp.seconds > cfg.time_budget;
                points.push(dp);
            }
            if slow {
                break;
            }
        }
    }
    Ok(StudyResult { sweep: cfg.sweep, curves, points, reference, reference_settings: ref_settings, reference_info })
}

/// Renders once with `s` and measures it.
pub fn measure(
    scene: &Scene,
    accel: &dyn Intersector,
    s: &Settings,
    tolerance: Option<f32>,
    curve: usize,
    reference: &Reference,
) -> Result<Point> {
    Ok(render_point(scene, accel, s, tolerance, curve, reference)?.0)
}

/// [`measure`], keeping the render's sums (with the output variables `s` asks for).
fn render_point(
    scene: &Scene,
    accel: &dyn Intersector,
    s: &Settings,
    tolerance: Option<f32>,
    curve: usize,
    reference: &Reference,
) -> Result<(Point, Accumulator)> {
    let t0 = Instant::now();
    let (acc, stats) = wavepath::render_sums(scene, accel, s, &|_| {})?;
    let seconds = t0.elapsed().as_secs_f64();
    let p = Point {
        curve,
        settings: s.clone(),
        tolerance,
        seconds,
        denoise_seconds: None,
        rays: stats.total_rays(),
        invalid_samples: stats.invalid_samples,
        error: compare(&acc, reference),
        film: acc.to_film(),
        samples: acc.samples_taken(),
    };
    Ok((p, acc))
}

/// The render `raw` (whose sums are `acc`, kept with albedo and normal) denoised, as a point
/// of curve `curve`: its time is the render's plus the denoising's (measured), its error
/// against the same raw reference ([`compare_film`]: no variance-based fields).
pub fn denoise_point(
    denoiser: &Denoiser,
    raw: &Point,
    acc: &Accumulator,
    curve: usize,
    reference: &Reference,
) -> Result<Point> {
    let t0 = Instant::now();
    let film = denoise_film(denoiser, acc)?;
    let denoise_seconds = t0.elapsed().as_secs_f64();
    Ok(Point {
        curve,
        seconds: raw.seconds + denoise_seconds,
        denoise_seconds: Some(denoise_seconds),
        error: compare_film(&film, reference, raw.error.mean_spp),
        film,
        ..raw.clone()
    })
}

/// The sums' picture denoised with their albedo and normal, prefiltered (they carry the
/// render's noise), as `wavepath --denoise` does.
fn denoise_film(denoiser: &Denoiser, acc: &Accumulator) -> Result<Film> {
    // Without first-hit sums the albedo and normal images would be black.
    if acc.aovs.is_empty() {
        bail!("the render kept no albedo and normal for the denoiser");
    }
    let aovs = acc.aov_images(sweep::denoiser_aovs());
    let find = |k: Aov| aovs.iter().find(|v| v.aov == k).map(|v| v.to_film());
    let (albedo, normal) = (find(Aov::Albedo), find(Aov::Normal));
    denoiser.denoise(&acc.to_film(), Aux { albedo: albedo.as_ref(), normal: normal.as_ref(), prefilter: true })
}
