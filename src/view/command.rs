//! "Copy command": the offline `wavepath` command line and camera file (`-c`, the CS184
//! format) that render what the viewer shows.

use super::options::ViewOptions;
use super::session::ViewState;
use wavepath::RouletteKind;
use wavepath::format_camera_settings;

/// The camera file's name in the command.
pub const CAMERA_FILE: &str = "view-camera.txt";

/// `{"command": "...", "camera_file": "...", "camera_file_name": "..."}` for `st`.
pub fn reproduce(st: &ViewState, opts: &ViewOptions) -> serde_json::Value {
    let s = &st.settings;
    // The fields of view as this image size has them, written out (the file's are kept as
    // written).
    let cam = s.image.camera(&st.orbit.camera);
    let quote = |p: &str| {
        if p.chars().all(|c| c.is_ascii_alphanumeric() || "/._-+".contains(c)) {
            p.to_string()
        } else {
            format!("'{}'", p.replace('\'', "'\\''"))
        }
    };
    let mut args = vec!["wavepath".to_string()];
    if let Some(p) = &opts.scene_path {
        args.push(quote(p));
    }
    args.push(format!(
        "-r {} {} -s {} -l {} -m {}",
        s.image.width, s.image.height, s.sampling.spp, s.sampling.light_samples, s.paths.max_depth
    ));
    args.push(format!("--shading {}", s.paths.shading.name()));
    if s.paths.roulette.kind == RouletteKind::Throughput {
        args.push(format!("--roulette throughput --rr-depth {}", s.paths.roulette.start_depth));
    } else {
        args.push(format!(
            "--roulette fixed --rr {} --rr-depth {}",
            s.paths.roulette.continue_prob, s.paths.roulette.start_depth
        ));
    }
    args.push(format!("--sampler {} --seed {}", opts.sampler, s.sampling.seed));
    if s.paths.hemisphere {
        args.push("-H".into());
    }
    if !s.paths.mis {
        args.push("--no-mis".into());
    }
    if cam.lens_radius > 0.0 {
        args.push(format!("-b {} -d {}", cam.lens_radius, cam.focal_distance));
    }
    if let (true, Some(e)) = (st.environment, &opts.envmap_path) {
        args.push(format!("-e {}", quote(e)));
    }
    // The variable shown is written beside the picture; the picture denoised as shown.
    if let Some(a) = st.look.show {
        args.push(format!("--aov {}", a.name()));
    }
    if st.look.denoise {
        args.push("--denoise".into());
    }
    args.push(format!("-c {CAMERA_FILE} -f view.png"));
    serde_json::json!({
        "command": args.join(" "),
        "camera_file_name": CAMERA_FILE,
        "camera_file": format_camera_settings(&cam, s.image.width, s.image.height),
    })
}
