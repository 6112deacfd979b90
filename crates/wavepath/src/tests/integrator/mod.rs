//! Rendering: closed-form answers, the wavefront integrator against the recursive
//! reference, effects and stages, environment maps, the thin lens, ray offsets and
//! numerical stability.

mod agree_controls;
mod analytic;
mod aov;
mod bidir;
mod effects;
pub mod emitter_filter;
mod emitter_sides;
mod envmap;
mod lens;
pub mod mis;
mod offsets;
mod plan;
mod stability;
mod stop;
mod transport;
mod wavefront;
