//! `wavepath view SCENE [render flags]`: load, build, serve the viewer until Ctrl-C.

use super::ViewArgs;
use super::render_cmd::prepare_scene;
use super::settings_from_args::settings;
use anyhow::{Result, bail};
use std::net::SocketAddr;
use std::sync::Arc;
use wavepath::{AovSet, Bvh, Denoiser, Settings};
use wavepath_apps::view::{ViewOptions, Viewer};

/// The samples-per-pixel cap when `-s` is left at its default of 1.
const DEFAULT_CAP: u32 = 1024;

pub fn run(a: &ViewArgs) -> Result<()> {
    // The flags are checked before the (possibly long) load.
    settings(&a.render, Settings::default())?;
    if let Some(d) = &a.save_dir
        && !d.is_dir()
    {
        bail!("{}: --save-dir is not a folder", d.display());
    }
    // The page shows one output variable at a time: `--aov NAME` is the one shown first.
    if a.render.aov.len() > 1 {
        bail!("--aov: the viewer shows one output variable at a time (its page switches between them)");
    }
    let denoiser = denoiser(a)?;
    let scene = super::with_spinner("loading", || prepare_scene(&a.render))?;
    let mut s = settings(&a.render, Settings::for_scene(&scene))?;
    if a.render.spp == 1 {
        s.sampling.spp = DEFAULT_CAP;
    }
    // The session keeps first-hit sums only while its page shows a variable or denoises.
    s.image.aovs = AovSet::NONE;
    super::check_build_memory(&scene, s.accel.bvh.leaves, a.render.max_memory)?;
    let bvh =
        super::with_spinner("building the BVH", || Bvh::build_with(&scene, s.accel.bvh).with_isa(s.execution.isa));
    let opts = ViewOptions {
        listen: SocketAddr::new(a.listen, a.port),
        save_dir: a.save_dir.clone(),
        scene_path: a.render.scene.as_ref().map(|p| p.display().to_string()),
        envmap_path: a.render.envmap.as_ref().map(|p| p.display().to_string()),
        sampler: s.sampling.sampler.name().to_string(),
        denoiser,
        show: a.render.aov.first().copied(),
        denoise: a.render.denoise,
    };
    let viewer = Viewer::bind(&scene, s.clone(), &opts)?;
    // The URL on stdout (scripts and tests read it); everything else on stderr.
    println!("http://{}/", viewer.addr);
    eprintln!(
        "[wavepath view] {} at {}x{}, up to {} spp; Ctrl-C stops",
        scene.name, s.image.width, s.image.height, s.sampling.spp
    );
    if !a.listen.is_loopback() {
        eprintln!("[wavepath view] listening on {}: reachable from the network", a.listen);
    }
    let session = viewer.session.clone();
    ctrlc::set_handler(move || session.stop())?;
    viewer.run(scene, &bvh, &opts, s.execution.threads)?;
    eprintln!("[wavepath view] stopped");
    // The render thread has been joined. Connections whose clients stopped reading may still
    // block their writers (and the server's drop on them): the process ends without waiting.
    std::process::exit(0)
}

/// Open Image Denoise for the page's denoise box: the runtime `--oidn` names (which must
/// load), else the pyoidn of python3 if there is one. Without one the viewer runs with the box
/// off, unless `--denoise` asked for it from the start.
fn denoiser(a: &ViewArgs) -> Result<Option<Arc<Denoiser>>> {
    let found = wavepath_apps::oidn_runtime::find_oidn(a.render.oidn.as_deref()).and_then(|p| Denoiser::load(&p));
    match found {
        Ok(d) => {
            eprintln!("[wavepath view] denoiser: {}", d.library().display());
            Ok(Some(Arc::new(d)))
        }
        Err(e) if a.render.oidn.is_some() || a.render.denoise => Err(e),
        Err(e) => {
            eprintln!("[wavepath view] denoising off: {e:#}");
            Ok(None)
        }
    }
}
