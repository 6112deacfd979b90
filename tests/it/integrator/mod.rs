//! Rendering through the command line: Russian roulette's options and environment maps.

mod envmap;
mod roulette;
