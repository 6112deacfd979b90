//! `wavepath [FLAGS] SCENE --part I/N|auto -f PART.exr`: renders one part of a split render.

use super::RenderArgs;
use super::render_cmd::prepare_scene;
use super::settings_from_args::settings;
use anyhow::{Result, bail};
use std::path::PathBuf;
use std::time::Instant;
use wavepath::Settings;
use wavepath_apps::parts::{PartMeta, PartSpec, PartStats, identity};

pub fn run(a: &RenderArgs) -> Result<()> {
    let t0 = Instant::now();
    if !a.aov.is_empty() || a.denoise {
        bail!("--aov and --denoise need the whole render in one process: a part file keeps only the picture's sums");
    }
    let checked = settings(a, Settings::default())?;
    let text = a.part.as_deref().unwrap_or("auto");
    let spec = PartSpec::parse(text, a.parts, a.split.into(), &|k| std::env::var(k).ok())?;
    spec.check(&checked)?;
    let out: PathBuf = match &a.output {
        Some(p) if p.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("exr")) => p.clone(),
        Some(p) => bail!("{}: a part is written as OpenEXR; give -f PART.exr", p.display()),
        None => bail!("--part needs -f PART.exr (where the part file goes)"),
    };
    let scene = prepare_scene(a)?;
    let s = settings(a, Settings::for_scene(&scene))?;
    if s.accel.use_bvh {
        super::check_build_memory(&scene, s.accel.bvh.leaves, a.max_memory)?;
    }
    let scene_hash = identity::scene_hash(&scene);
    let (acc, mut stats) = wavepath::with_threads(s.execution.threads, || -> Result<_> {
        let (accel, build) = wavepath::build_accel(&scene, &s);
        let (acc, mut stats) = wavepath_apps::parts::render_part(&scene, accel.as_ref(), &s, &spec, &|_| {})?;
        stats.build_s = build.build_s;
        stats.threads = rayon::current_num_threads();
        Ok((acc, stats))
    })??;
    stats.host = host_name();
    stats.wall_s = t0.elapsed().as_secs_f64();
    let meta = PartMeta {
        format: wavepath_apps::parts::file::FORMAT,
        part: spec,
        scene: scene.name.clone(),
        scene_hash,
        settings: identity::settings_key(&s),
        width: s.image.width,
        height: s.image.height,
        spp: s.sampling.spp,
        adaptive: s.sampling.adaptive.is_some(),
        stats: stats.clone(),
        pixels: String::new(),
    };
    wavepath_apps::parts::file::write(&out, &meta, &acc)?;
    let _: &PartStats = &stats;
    eprintln!(
        "[wavepath] Part {} ({} split) of {}: {} rays in {:.3} s render, {:.3} s wall; wrote {}",
        spec.label(),
        spec.split.name(),
        scene.name,
        stats.rays(),
        stats.render_s,
        stats.wall_s,
        out.display()
    );
    Ok(())
}

/// The host name for the stats (which node ran a part), without spawning a process.
fn host_name() -> String {
    std::env::var("HOSTNAME")
        .ok()
        .or_else(|| std::fs::read_to_string("/proc/sys/kernel/hostname").ok())
        .map(|h| h.trim().to_string())
        .unwrap_or_default()
}
