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
fn load_scene(path: &std::path::Path, opts: &wavepath::load::LoadOptions) -> anyhow::Result<wavepath::scene::Scene> {
    let scene = wavepath::load::load(path, opts)?;
    for n in &scene.notes {
        eprintln!("{n}");
    }
    Ok(scene)
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
