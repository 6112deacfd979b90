//! `wavepath view`: the render as it converges, in a browser, with the camera and settings
//! under the user's hands. One render thread runs the same wavefront integrator as an
//! offline render, frame by frame ([`session`]); a small HTTP server on loopback serves the
//! page, a stream of frames and the controls ([`server`]).

pub mod command;
pub mod controls;
pub mod options;
pub mod orbit;
pub mod pacing;
pub mod server;
pub mod session;

pub use options::ViewOptions;
pub use server::Viewer;
