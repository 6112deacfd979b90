//! `wavepath [FLAGS] [SCENE]`: load, build, render, write.

use super::RenderArgs;
use super::settings_from_args::{request, settings};
use anyhow::{Result, bail};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use wavepath::RenderStats;
use wavepath::Settings;
use wavepath::{Extent, RenderPlan};
use wavepath::{LoadOptions, default_scene};
use wavepath::{Scene, read_camera_file};

/// Loads the scene the arguments name (or the default) with the camera file and lens
/// applied; its fit to the image is the render plan's (from the settings' `--fov`).
pub fn prepare_scene(a: &RenderArgs) -> Result<Scene> {
    let mut scene = match &a.scene {
        Some(p) => super::load_scene_within(
            p,
            &LoadOptions {
                camera: a.camera,
                two_sided_emission: a.two_sided_emission,
                subdivide: a.subdivide,
                ..LoadOptions::default()
            },
            a.max_memory,
        )?,
        None => default_scene(),
    };
    scene.drop_unused_uvs();
    if let Some(c) = &a.camera_file {
        scene.camera = read_camera_file(c)?;
    }
    scene.camera = request(a).camera(scene.camera);
    if let Some(e) = &a.envmap {
        scene.set_environment(wavepath::Environment::Map(std::sync::Arc::new(wavepath::EnvMap::load(e)?)));
    }
    Ok(scene)
}

pub fn run(a: &RenderArgs) -> Result<()> {
    // The flags are checked before the (possibly long) load, then applied on top of the
    // defaults of the dialect the loader found.
    settings(a, Settings::default())?;
    let out: PathBuf = a.output.clone().unwrap_or_else(|| PathBuf::from("wavepath.png"));
    check_output_extension(&out)?;
    // The denoiser is found before the (possibly long) load and render.
    let denoiser = if a.denoise {
        let lib = wavepath_apps::oidn_runtime::find_oidn(a.oidn.as_deref())?;
        Some(wavepath::Denoiser::load(&lib)?)
    } else {
        None
    };
    let t0 = Instant::now();
    let scene = super::with_spinner("loading", || prepare_scene(a))?;
    let s = settings(a, Settings::for_scene(&scene))?;
    let load_s = t0.elapsed().as_secs_f64();
    eprintln!(
        "[wavepath] Loaded {} in {:.3} s ({} reader, {} dialect): {} triangles, {} spheres, {} lights",
        scene.name,
        load_s,
        scene.source.reader,
        scene.source.dialect.name(),
        scene.mesh.triangle_count(),
        scene.spheres.len(),
        scene.lights.len()
    );
    if s.accel.use_bvh {
        super::check_build_memory(&scene, s.accel.bvh.leaves, a.max_memory)?;
    }
    // One plan for the render: the effects logged here are the ones it renders with.
    let plan = RenderPlan::new(&scene, &s);
    let effects = plan.effects();
    for e in &effects.on {
        eprintln!("[wavepath] Effect on: {} ({})", e.name, e.reason);
    }
    eprintln!("[wavepath] Integrator: {} ({})", effects.integrator.name, effects.integrator.reason);
    if s.cs184.light_pdf {
        eprintln!(
            "[wavepath] --cs184-light-pdf: area-light samples use the course renderer's pdf, dist / (area cos): \
             biased, each estimate times the distance to the light"
        );
    }
    let (film, build) = wavepath::with_threads(s.execution.threads, || -> Result<_> {
        eprintln!("[wavepath] Collected {} primitives", scene.primitive_count());
        let (accel, build) = super::with_spinner("building the BVH", || wavepath::build_accel(&scene, &s));
        let mb = |b: usize| b as f64 / 1e6;
        eprintln!(
            "[wavepath] Built {} in {:.4} s ({} nodes, {} leaves, depth {}); resident: mesh {:.1} MB, nodes {:.1} MB, leaves {:.1} MB",
            accel.name(),
            build.build_s,
            build.nodes,
            build.leaves,
            build.depth,
            mb(scene.mesh.bytes()),
            mb(build.node_bytes),
            mb(build.leaf_bytes)
        );
        let bar = progress_bar(&s);
        let tick = |n: u64| {
            if let Some(b) = &bar {
                b.inc(n);
            }
        };
        let never = AtomicBool::new(false);
        let result = wavepath::render_plan(&plan, accel.as_ref(), Extent::of(&s), &tick, &never)?;
        if let Some(b) = &bar {
            b.finish_and_clear();
        }
        Ok((result, build))
    })??;
    let wavepath::RenderOutput { film, stats, samples, aovs } = film;
    // A denoised picture keeps the noisy one beside it (a layer of an .exr).
    let (film, noisy, denoise_s) = match &denoiser {
        Some(d) => {
            let t = Instant::now();
            let denoised = denoise(d, &film, &aovs)?;
            (denoised, Some(film), Some(t.elapsed().as_secs_f64()))
        }
        None => (film, None, None),
    };
    // Only the variables asked for are written (a denoiser's albedo and normal are its own).
    let written: Vec<_> = aovs.into_iter().filter(|v| a.aov.contains(&v.aov)).collect();
    let files = wavepath::write_image_with_aovs(&film, &written, noisy.as_ref(), &out, a.tonemap)?;
    // The sample-rate image shows where adaptive sampling spent its samples; a fixed-rate
    // render's would be one flat grey nobody asked for.
    if s.sampling.adaptive.is_some() && s.paths.shading != wavepath::Shading::Normals {
        let rate_path = rate_image_path(&out);
        let rate = wavepath::rate_film(film.width, film.height, &samples, s.sampling.spp);
        wavepath::write_rate_image(&rate, &rate_path)?;
        eprintln!("[wavepath] Wrote sample-rate image {}", rate_path.display());
    }
    for line in stats.log_lines() {
        eprintln!("[wavepath] {line}");
    }
    for f in &files {
        eprintln!("[wavepath] Wrote {}", f.display());
    }
    if let Some(p) = &a.stats {
        let mut json = wavepath::stats_json(&scene, &s, effects, &build, &stats);
        if let (Some(t), Some(m)) = (denoise_s, json.as_object_mut()) {
            m.insert("denoise_s".into(), t.into());
        }
        write_atomic(p, serde_json::to_string_pretty(&json)?.as_bytes())?;
    }
    let _: &RenderStats = &stats;
    Ok(())
}

/// The picture denoised with the render's albedo and normal (prefiltered: they carry the
/// render's own noise), with the time it took logged.
fn denoise(d: &wavepath::Denoiser, film: &wavepath::Film, aovs: &[wavepath::AovImage]) -> Result<wavepath::Film> {
    let find = |k: wavepath::Aov| aovs.iter().find(|v| v.aov == k).map(|v| v.to_film());
    let (albedo, normal) = (find(wavepath::Aov::Albedo), find(wavepath::Aov::Normal));
    let t = Instant::now();
    let aux = wavepath::Aux { albedo: albedo.as_ref(), normal: normal.as_ref(), prefilter: true };
    let out = d.denoise(film, aux)?;
    eprintln!(
        "[wavepath] Denoised in {:.3} s (Open Image Denoise, {})",
        t.elapsed().as_secs_f64(),
        d.library().display()
    );
    Ok(out)
}

/// `<out>_rate.png` beside the output image.
pub fn rate_image_path(out: &Path) -> PathBuf {
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("wavepath");
    out.with_file_name(format!("{stem}_rate.png"))
}

/// A progress bar over camera samples, only when stderr is a terminal.
fn progress_bar(s: &Settings) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() || s.paths.shading == wavepath::Shading::Normals {
        return None;
    }
    let r = s.region();
    let total = (r.w * r.h) as u64 * s.sampling.spp.max(1) as u64;
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template("[wavepath] {bar:40} {percent:>3}% {elapsed_precise} eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    Some(bar)
}

pub fn check_output_extension(out: &Path) -> Result<()> {
    let ext = out.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    if !matches!(ext.as_str(), "png" | "exr" | "hdr" | "pfm") {
        bail!("{}: unknown image format; use .png, .exr, .hdr or .pfm", out.display());
    }
    Ok(())
}

/// Writes via a temporary file and a rename, so readers never see half a file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))?;
    std::fs::rename(&tmp, path).map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))?;
    Ok(())
}
