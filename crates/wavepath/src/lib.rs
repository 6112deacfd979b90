//! wavepath: a physically based, data-oriented wavefront path tracer for the CPU.
//!
//! This is the engine's whole face; every module behind it is private, so the applications
//! (the `wavepath` command, the viewer, studies, split renders, ray files) and any other
//! caller see exactly what is listed here. A render is four steps:
//!
//! ```no_run
//! # fn main() -> anyhow::Result<()> {
//! use wavepath::{LoadOptions, Settings, Tonemap, build_accel, load, render, write_image};
//!
//! // 1. A scene: from a file (.dae, .obj, .ply, .gltf, .glb), `default_scene()`, or built
//! //    from arrays (`Scene { mesh: Mesh { positions, triangles, .. }, .. }`).
//! let scene = load("dragon.ply".as_ref(), &LoadOptions::default())?;
//! // 2. Settings: the defaults for the scene's dialect, then what the caller changes.
//! let mut settings = Settings::for_scene(&scene);
//! settings.image.width = 320;
//! settings.image.height = 240;
//! // 3. The acceleration structure (a BVH, or brute force), which also answers ray queries.
//! let (accel, _info) = build_accel(&scene, &settings);
//! // 4. The render: an image and what it cost.
//! let (film, stats) = render(&scene, accel.as_ref(), &settings)?;
//! write_image(&film, "dragon.png".as_ref(), Tonemap::Cs184)?;
//! println!("{:.1} Mrays/s", stats.mrays_per_s());
//! # Ok(()) }
//! ```
//!
//! A caller that renders one scene with one set of settings in pieces (cells of a split
//! render, the viewer's bands and passes) builds a [`RenderPlan`] once and renders each piece
//! as an [`Extent`] of it (`render_plan`, `render_plan_sums`); `render` and its siblings build
//! the plan themselves.
//!
//! Inside, modules form layers, lowest first: each uses only layers before it
//! (ARCHITECTURE.md; the layer test in `tests/layers.rs` checks it).

// Below all: settings chosen by name.
mod choice;
// 0: run-time CPU features; rays, error bounds, offsets.
mod cpu;
mod geometry;
// 1: random streams and warps.
mod sampling;
// 2: the CS184 dialect's rules, in one place.
mod cs184;
// 3: plain data: the scene, then the settings (whose defaults follow the scene's dialect).
mod scene;
mod settings;
// 3: what the integrators are built from.
mod accel;
mod bsdf;
mod effects;
mod film;
mod lights;
mod load;
mod request;
// 4: what a render measured; denoising a rendered film (Open Image Denoise, loaded at run time).
mod denoise;
mod stats;
// 5: light transport: the shared vertex logic, the wavefront stages, the recursive reference.
mod integrator;
// 6: a whole render; the standard ray sets of a scene.
mod raysets;
mod render;

// The tests' shared helpers name the face as `wavepath::`, in this crate as in the
// applications' tests that include them.
#[cfg(test)]
extern crate self as wavepath;
#[cfg(test)]
mod tests;

// Scenes: load one, or build one from plain data.
pub use load::{CameraMode, LoadOptions, default_scene, load, write_ply};
pub use scene::{
    Bsdf, Camera, DEFAULT_SKY, EnvMap, Environment, FovFit, FovRule, Light, Material, MaterialIds, Mesh, Scene,
    SceneSource, Sphere, Texture, format_camera_settings, parse_camera_settings, read_camera_file, subdivide, texture,
};

// What a render does: settings, their names, and a request checked into settings.
pub use choice::{Choice, UnknownName};
pub use cpu::Isa;
pub use cs184::Dialect;
pub use request::{Field, InvalidValue, MAX_PIXELS, MAX_SIDE, Names, Range, Request, check_resolution};
pub use sampling::SamplerKind;
pub use settings::{
    AccelSettings, Aov, AovSet, BvhBuild, BvhOptions, Cell, Cs184Compat, Execution, ImageSettings, IntegratorKind,
    LeafLayout, PathRules, Roulette, RouletteKind, Sampling, Settings, Shading,
};

// Rays: the acceleration structures and their queries.
pub use accel::{BruteForce, BuildInfo, Bvh, Intersector, TraceCounters, build as build_accel};
pub use geometry::{Hit, Ray};
pub use raysets::{diffuse_rays, primary_rays};

// Renders and what they produce.
pub use denoise::{Aux, Denoiser, OIDN_HELP};
pub use effects::{Effect, Effects};
pub use film::{
    Accumulator, AovImage, Film, PixelSums, Tonemap, rate_film, write_image, write_image_with_aovs, write_rate_image,
};
pub use integrator::plan::{Extent, RenderPlan};
pub use render::{
    Canvas, Interrupted, RenderOutput, render, render_plan, render_plan_sums, render_sums, render_until,
    render_with_progress, with_threads,
};
pub use stats::{RenderStats, StageTimes, roulette_json, to_json as stats_json};
