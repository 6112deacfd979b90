//! The `wavepath` command: parses arguments, runs the requested command, and turns every
//! error into one line on stderr and a non-zero exit.

mod args;
mod choices;
mod info;
mod merge_cmd;
mod part_cmd;
mod rays_cmd;
mod render_cmd;
mod settings_from_args;
pub mod study_cmd;
mod subdivide_cmd;
mod view_cmd;

pub use args::{Cli, Command, MergeArgs, RaysCommand, RenderArgs, SubdivideArgs, ViewArgs};

use clap::Parser;

/// Runs the command line; returns the process exit code.
pub fn main() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
                let _ = e.print();
                return 0;
            }
            // clap's message has usage lines after the first; keep the one that says what is wrong.
            let text = e.render().to_string();
            let first = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("invalid arguments");
            eprintln!("{} (see wavepath --help)", first.trim());
            return 2;
        }
    };
    let result = match &cli.command {
        Some(Command::Info(a)) => info::run(a),
        Some(Command::Rays(RaysCommand::Dump(a))) => rays_cmd::run_dump(a),
        Some(Command::Rays(RaysCommand::Trace(a))) => rays_cmd::run_trace(a),
        Some(Command::Merge(a)) => merge_cmd::run(a),
        Some(Command::Study(a)) => study_cmd::run(a),
        Some(Command::Subdivide(a)) => subdivide_cmd::run(a),
        Some(Command::View(a)) => view_cmd::run(a),
        None if cli.render.part.is_some() => part_cmd::run(&cli.render),
        None => render_cmd::run(&cli.render),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            // `{:#}` joins the context chain on one line: "file: what: why".
            let msg = format!("{e:#}").replace('\n', " ");
            eprintln!("error: {msg}");
            1
        }
    }
}

/// Loads a scene file and prints the loader's notes, which only a scene that loaded has.
/// A file whose mesh cannot fit in the memory left (about its size for binary meshes, times
/// four per `--subdivide` level) is refused before it is read.
fn load_scene(path: &std::path::Path, opts: &wavepath::LoadOptions) -> anyhow::Result<wavepath::Scene> {
    load_scene_within(path, opts, None)
}

fn load_scene_within(
    path: &std::path::Path,
    opts: &wavepath::LoadOptions,
    limit: Option<u64>,
) -> anyhow::Result<wavepath::Scene> {
    if let Ok(meta) = std::fs::metadata(path) {
        let need = (meta.len() as u128) << (2 * opts.subdivide.min(32));
        check_memory(path, need, "loading it", limit)?;
    }
    let scene = wavepath::load(path, opts)?;
    for n in &scene.notes {
        eprintln!("{n}");
    }
    Ok(scene)
}

/// Refuses, before the allocations, a BVH that cannot fit in the memory left.
fn check_build_memory(scene: &wavepath::Scene, layout: wavepath::LeafLayout, limit: Option<u64>) -> anyhow::Result<()> {
    let need = wavepath::Bvh::build_bytes(scene.primitive_count(), layout);
    check_memory(std::path::Path::new(&scene.name), need as u128, "building its BVH", limit)
}

/// An error naming `what` when `need` bytes exceed `limit` (`--max-memory`) or, without
/// one, the memory the system says is available.
fn check_memory(what: &std::path::Path, need: u128, doing: &str, limit: Option<u64>) -> anyhow::Result<()> {
    let Some((have, source)) =
        limit.map(|l| (l, "--max-memory")).or_else(|| available_memory().map(|a| (a, "available")))
    else {
        return Ok(());
    };
    if need > have as u128 {
        let size = |b: u128| match b {
            b if b >= 1_000_000_000 => format!("{:.2} GB", b as f64 / 1e9),
            b if b >= 1_000_000 => format!("{:.1} MB", b as f64 / 1e6),
            b => format!("{b} bytes"),
        };
        anyhow::bail!(
            "{}: {doing} needs about {} of memory, more than the {} {source}",
            what.display(),
            size(need),
            size(have as u128)
        );
    }
    Ok(())
}

/// The memory the system can still give (Linux `MemAvailable`), when it says.
fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// `--max-memory`: bytes, or a number with K, M, G or T (powers of 1000).
fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (num, mul) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let m = match c.to_ascii_uppercase() {
                'K' => 1e3,
                'M' => 1e6,
                'G' => 1e9,
                'T' => 1e12,
                _ => return Err(format!("'{s}': expected bytes, or a number with K, M, G or T")),
            };
            (&t[..i], m)
        }
        _ => (t, 1.0),
    };
    let x: f64 = num.parse().map_err(|_| format!("'{s}': expected bytes, or a number with K, M, G or T"))?;
    if !(x.is_finite() && x > 0.0 && x * mul < 1e18) {
        return Err(format!("'{s}': expected a positive size below 1e18 bytes"));
    }
    Ok((x * mul) as u64)
}

/// Runs `work`; on a terminal, a spinner with `label` appears if it takes more than a second
/// (loading and building a scanned mesh of tens of millions of triangles takes several).
fn with_spinner<T>(label: &str, work: impl FnOnce() -> T) -> T {
    use std::io::IsTerminal;
    use std::sync::mpsc::{RecvTimeoutError, channel};
    if !std::io::stderr().is_terminal() {
        return work();
    }
    let (done, wait) = channel::<()>();
    let label = label.to_string();
    std::thread::scope(|s| {
        s.spawn(move || {
            if wait.recv_timeout(std::time::Duration::from_secs(1)) != Err(RecvTimeoutError::Timeout) {
                return;
            }
            let bar = indicatif::ProgressBar::new_spinner();
            bar.set_style(
                indicatif::ProgressStyle::with_template("[wavepath] {spinner} {msg} {elapsed}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
            );
            bar.set_message(label);
            bar.enable_steady_tick(std::time::Duration::from_millis(100));
            let _ = wait.recv();
            bar.finish_and_clear();
        });
        let out = work();
        drop(done);
        out
    })
}
