//! The applications on the wavepath engine: the interactive viewer, accuracy-versus-time
//! studies, split renders and their merge, and ray files for the peers' harness. Each uses
//! only the engine's face (`wavepath::*`); the `wavepath` command (`main.rs`, `cli/`) puts
//! them on the command line.

pub mod oidn_runtime;
pub mod parts;
pub mod rayfile;
pub mod study;
pub mod view;
