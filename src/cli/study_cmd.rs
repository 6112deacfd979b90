//! `wavepath study SCENE --sweep KIND`: what accuracy costs in time (see [`wavepath_apps::study`]).

use super::choices::{Sweep, named};
use super::settings_from_args::flag;
use anyhow::{Result, bail};
use clap::Args;
use std::path::PathBuf;
use std::sync::Arc;
use wavepath::Settings;
use wavepath::{CameraMode, FovRule, LoadOptions, Request, SamplerKind, default_scene};
use wavepath_apps::study::{StudyConfig, SweepKind};

#[derive(Args, Debug, Clone)]
#[command(long_about = "Sweeps one setting and, for each value, renders at samples per pixel \
    1, 2, 4, ... (up to --max-spp, or until a render takes longer than --time-budget), \
    measuring wall time, rays traced and the error against a converged reference (RMSE and \
    relative MSE over linear RGB, and the mean per-pixel 95% confidence half-width). The \
    reference is rendered once at --ref-spp and cached in --cache, keyed by a hash of the \
    scene file and the settings. Writes study.csv, error_vs_time.png/.svg (log-log, one curve \
    per setting), the images at equal time and report.md into --out.\n\n\
    Sweeps: spp (one curve); light-samples (-l 1..64); sampling (light importance vs uniform \
    hemisphere); depth (-m 1..16 without roulette, and -m 4, 16 with --rr); roulette (-m 16, \
    --rr 1.0 down to 0.1); adaptive (-a 64 T for T = 0.2..0.01, against fixed spp); sampler \
    (independent, stratified, sobol); mis (MIS of light and BSDF samples against light sampling \
    alone: it differs only where the scene's lights are emissive triangles or an environment \
    map); denoise (each render as it is and denoised by Open Image Denoise with its albedo and \
    normal, the denoised time adding the denoising; both judged against the raw reference, so \
    the denoised error is biased: needs the runtime, see --oidn).")]
pub struct StudyArgs {
    /// Scene file; omitted: the embedded Cornell box.
    pub scene: Option<PathBuf>,
    /// The setting to sweep.
    #[arg(long, value_enum)]
    pub sweep: Sweep,
    /// How a COLLADA camera's field of view follows -r; default: the whole 800x600 picture
    /// (a study's small renders would otherwise show the centre of it only).
    #[arg(long, value_parser = named::<FovRule>(), default_value = "frame")]
    pub fov: FovRule,
    /// Resolution of every render (small: a study renders many images).
    #[arg(short = 'r', num_args = 2, value_names = ["W", "H"], default_values_t = [64, 48])]
    pub resolution: Vec<i64>,
    /// Maximum ray depth of the renders (the depth and roulette sweeps vary it).
    #[arg(short = 'm', value_name = "N", default_value_t = 5)]
    pub max_depth: i64,
    /// Samples per area light (the light-samples sweep varies it).
    #[arg(short = 'l', value_name = "N", default_value_t = 1)]
    pub light_samples: i64,
    /// Russian roulette continue probability (the depth and roulette sweeps vary it).
    #[arg(long = "rr", value_name = "P", default_value_t = 0.65)]
    pub rr: f64,
    /// Largest samples per pixel of each ladder (and the adaptive sweep's maximum).
    #[arg(long, value_name = "N", default_value_t = 1024)]
    pub max_spp: i64,
    /// Samples per pixel of the reference.
    #[arg(long, value_name = "N", default_value_t = 4096)]
    pub ref_spp: i64,
    /// A ladder stops after the first render slower than this (seconds).
    #[arg(long, value_name = "S", default_value_t = 10.0)]
    pub time_budget: f64,
    /// Folder of cached references.
    #[arg(long, value_name = "DIR", default_value = ".wavepath-cache")]
    pub cache: PathBuf,
    /// Output folder; default: study-<scene>-<sweep>.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Base seed (the reference uses its own, derived from it).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (default, or 0: all cores).
    #[arg(short = 't', value_name = "N")]
    pub threads: Option<i64>,
    /// COLLADA camera framing.
    #[arg(long, value_parser = named::<CameraMode>(), default_value = "cs184")]
    pub camera: CameraMode,
    /// How each pixel's samples spread (the sampler sweep varies it); default as for a
    /// render: independent for .dae files and the embedded scene, sobol for other files.
    #[arg(long, value_parser = named::<SamplerKind>())]
    pub sampler: Option<SamplerKind>,
    /// Open Image Denoise's library, a folder holding it, or an installed pyoidn package, for
    /// the denoise sweep (other sweeps do not load it). Default: the pyoidn that `python3` on
    /// the PATH imports.
    #[arg(long, value_name = "PATH")]
    pub oidn: Option<PathBuf>,
}

fn in_range(name: &str, v: i64, lo: i64, hi: i64) -> Result<i64> {
    if v < lo || v > hi {
        bail!("{name} must be between {lo} and {hi}, got {v}");
    }
    Ok(v)
}

/// The render flags a study shares with a render, as the engine's request: checked and
/// applied as a render's are, on top of the scene's defaults.
fn request(a: &StudyArgs) -> Request {
    Request {
        resolution: Some((a.resolution[0], a.resolution[1])),
        max_depth: Some(a.max_depth),
        light_samples: Some(a.light_samples),
        rr: Some(a.rr),
        seed: Some(a.seed),
        threads: a.threads,
        sampler: a.sampler,
        fov: Some(a.fov),
        ..Request::default()
    }
}

/// The study's own flags around `base` (the settings every render starts from).
fn config(a: &StudyArgs, base: Settings) -> Result<StudyConfig> {
    if !(a.time_budget.is_finite() && a.time_budget > 0.0) {
        bail!("--time-budget must be a positive number of seconds, got {}", a.time_budget);
    }
    Ok(StudyConfig {
        sweep: a.sweep.into(),
        base,
        max_spp: in_range("--max-spp", a.max_spp, 1, 1 << 20)? as u32,
        ref_spp: in_range("--ref-spp", a.ref_spp, 1, 1 << 24)? as u32,
        time_budget: a.time_budget,
        cache_dir: a.cache.clone(),
        denoiser: None,
    })
}

pub fn run(a: &StudyArgs) -> Result<()> {
    // Every flag is checked before the load, as a render's are.
    let request = request(a);
    config(a, request.apply(Settings::default(), flag)?)?;
    // The denoiser is loaded before the (possibly long) load and the renders.
    let sweep: SweepKind = a.sweep.into();
    let denoiser = if sweep.needs_denoiser() {
        let lib = wavepath_apps::oidn_runtime::find_oidn(a.oidn.as_deref())?;
        Some(Arc::new(wavepath::Denoiser::load(&lib)?))
    } else {
        None
    };
    let scene = match &a.scene {
        Some(p) => super::load_scene(p, &LoadOptions { camera: a.camera, ..LoadOptions::default() })?,
        None => default_scene(),
    };
    let cfg = StudyConfig { denoiser, ..config(a, wavepath_apps::study::base_settings(&scene, &request, flag)?)? };
    let identity = wavepath_apps::study::reference::scene_identity(a.scene.as_deref())?;
    let stem = a.scene.as_ref().and_then(|p| p.file_stem()).and_then(|s| s.to_str()).unwrap_or("default").to_string();
    let out = a.out.clone().unwrap_or_else(|| PathBuf::from(format!("study-{stem}-{}", cfg.sweep.name())));
    let camera_label = format!("{:?} {:?}", a.camera, a.fov);
    let command = std::iter::once("wavepath".to_string()).chain(std::env::args().skip(1)).collect::<Vec<_>>().join(" ");
    let log = |m: &str| eprintln!("[wavepath study] {m}");
    let result = wavepath::with_threads(cfg.base.execution.threads, || -> Result<_> {
        let (accel, _) = wavepath::build_accel(&scene, &cfg.base);
        wavepath_apps::study::run(&scene, accel.as_ref(), &identity, &camera_label, &stem, &cfg, &log)
    })??;
    wavepath_apps::study::report::write_all(&result, &out, &stem, &command)?;
    log(&format!("wrote {}/report.md, study.csv, error_vs_time.png and .svg", out.display()));
    Ok(())
}
