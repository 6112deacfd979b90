//! Helpers of the applications' tests: the binary, the browser, and those shared with the
//! engine's tests (which use only the face).

// Shared with the engine's tests.
#[path = "../../../crates/wavepath/src/tests/common/agree.rs"]
pub mod agree;
pub mod cdp;
#[path = "../../../crates/wavepath/src/tests/common/cutout.rs"]
pub mod cutout;
#[path = "../../../crates/wavepath/src/tests/common/meshgen.rs"]
pub mod meshgen;
pub mod pfm;
// Some helpers of these files only the engine's tests use.
#[allow(dead_code)]
#[path = "../../../crates/wavepath/src/tests/common/render.rs"]
pub mod render;
#[allow(dead_code)]
#[path = "../../../crates/wavepath/src/tests/common/shared.rs"]
mod shared;
#[path = "../../../crates/wavepath/src/tests/common/special.rs"]
pub mod special;

pub use shared::*;
use std::path::PathBuf;
use std::process::{Command, Output};

/// Path of the built `wavepath` binary (integration tests only).
pub fn wavepath_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_wavepath"))
}

/// Runs the built `wavepath` binary with `args` (strings or paths) and waits for it.
pub fn run_wavepath<S: AsRef<std::ffi::OsStr>>(args: impl IntoIterator<Item = S>) -> Output {
    Command::new(wavepath_bin()).args(args).output().expect("wavepath runs")
}
