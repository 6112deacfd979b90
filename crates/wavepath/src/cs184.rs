//! The CS184 dialect: the conventions of the Berkeley CS184 course renderer, which the seed
//! reproduced and whose scenes (.dae files, the embedded default scene) keep its pictures.
//!
//! Every rule of the course that wavepath follows is listed here, with where it applies, so
//! that one page answers "what does CS184 compatibility change?". The rules that are pure
//! functions or numbers live in this module and the code that applies them calls in; the
//! others are named here and their code refers back.
//!
//! Which scenes follow the dialect:
//! - [`Dialect`]: recorded by the loader on `Scene::source` (`load/collada`: Cs184; the
//!   embedded `load::default_scene`: Cs184; OBJ, PLY, glTF and scenes built from arrays:
//!   Standard).
//!
//! Render defaults of the dialect (`Settings::for_dialect` in `settings.rs`):
//! - Russian roulette with the fixed continue probability [`RR_CONTINUE`] from depth
//!   [`RR_START_DEPTH`] (the first indirect bounce); other files: by throughput from depth 5;
//! - independent random numbers ([`SAMPLER`]); other files: Sobol points;
//! - light sampling alone on area, point and hemisphere lights: `effects.rs` turns MIS on
//!   only for emissive triangles and environment maps, so the course's scenes keep its
//!   estimator.
//!
//! Camera:
//! - placement (`--camera cs184`, the default): the file's view direction only, the camera
//!   at 1.5 bounding-box diagonals from the box's centre, +Y up (`Camera::cs184_place`,
//!   `scene/camera.rs`; applied by `load/collada/camera.rs` and the embedded scene);
//! - field of view fitted once to the course's 800x600 start-up window
//!   ([`fov_fit_tan_half_600`], held by `FovFit::Cs184` in `scene/camera.rs`);
//! - thin-lens focal distance [`FOCAL_DISTANCE`] (`scene/camera.rs`, the glTF loader);
//! - the camera settings file of `-c` is the text the course renderer dumps
//!   (`scene/camera_file.rs`).
//!
//! COLLADA reading (`load/collada/`, see COLLADA-CS184.md in the shared scenes):
//! - the extensions sit in `<technique profile="CGL">` (or "CMU462", the 2015 files):
//!   `xml.rs`; `<area>` lights (`lights.rs`), analytic `<sphere>`s (`geometry.rs`), BSDF
//!   extras (`materials.rs`); the up axis becomes +Y as the course's loader does
//!   (`transform.rs`);
//! - effects without an extra are diffuse with the common profile's diffuse colour in the
//!   course's files (those with its extensions or from its Blender versions: `dialect.rs`);
//!   other files' common profile is read in full (`common.rs`);
//! - vertex normals recomputed as the course's half-edge mesh does
//!   (`scene::cs184_vertex_normals` in `scene/normals.rs`, applied by `instance.rs` when
//!   `LoadOptions::smooth_normals`).
//!
//! Lights and materials (`lights/mod.rs`, `scene/material.rs`, `bsdf/`):
//! - point and spot lights ignore COLLADA attenuation; area lights are one-sided; the
//!   ambient light is a hemisphere of constant radiance over +Y (`lights/infinite.rs`);
//! - emissive triangles are not sampled when the scene has an area light (the course's
//!   Cornell boxes pair one with an emissive quad only the camera sees);
//! - the `<emission>` BSDF emits from both faces (`Material::two_sided_emission`);
//! - the mirror has no Fresnel term, glass ignores its roughness, microfacets are Beckmann;
//! - environment maps are oriented as the course's `dir_to_theta_phi` (`scene/envmap.rs`).
//!
//! Opt-in, changing the estimate (`Settings::cs184`, `--cs184-light-pdf`):
//! - the course's biased area-light pdf ([`area_pdf_distance`], [`area_light_pdf_weight`];
//!   applied in `lights/mod.rs`).
//!
//! Images (`film/`):
//! - pixel (0, 0) is the bottom-left one (`film/mod.rs`);
//! - the PNG transfer curve [`transfer`] and the bytes truncated, not rounded ([`byte`]),
//!   as `Tonemap::Cs184` (`film/write.rs`), the default.

use crate::sampling::SamplerKind;

/// Which conventions a scene follows, recorded by the loader that read it, so that the
/// library (not each application) chooses the defaults that depend on the kind of file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Dialect {
    /// The CS184 course's scenes: COLLADA files and the embedded default scene.
    Cs184,
    /// Every other file (OBJ, PLY, glTF), and scenes built from arrays: nothing about them
    /// asks for the course's conventions.
    #[default]
    Standard,
}

impl Dialect {
    /// Lowercase name for the log, `info` and the stats.
    pub fn name(self) -> &'static str {
        match self {
            Dialect::Cs184 => "cs184",
            Dialect::Standard => "standard",
        }
    }
}

/// The course's Russian-roulette continue probability.
pub const RR_CONTINUE: f32 = 0.65;
/// The course's roulette starts at the first indirect bounce.
pub const RR_START_DEPTH: u32 = 1;
/// The course draws independent random numbers.
pub const SAMPLER: SamplerKind = SamplerKind::Independent;

/// The course renderer's thin-lens focal distance when a file gives none.
pub const FOCAL_DISTANCE: f32 = 4.7;

/// The course renderer fits a file's optics once to its 4:3 start-up window, widening
/// whichever angle is too narrow for it: the tangent of half the vertical field at 600 rows,
/// `max(tan(vfov/2), 0.75 tan(hfov/2))`.
pub fn fov_fit_tan_half_600(hfov_deg: f32, vfov_deg: f32) -> f32 {
    let half_tan = |deg: f32| (deg.to_radians() * 0.5).tan();
    half_tan(vfov_deg).max(0.75 * half_tan(hfov_deg))
}

/// The distance term of the course's area-light pdf, `dist / (area cos)`: `dist` where the
/// correct solid-angle pdf has `dist^2` (its skeleton takes the light-side cosine from the
/// unnormalised vector to the light point).
#[inline]
pub fn area_pdf_distance(dist: f32) -> f32 {
    dist
}

/// What that pdf does to an estimate: the correct one times the distance to the light
/// point (the ratio of the correct pdf to the course's).
#[inline]
pub fn area_light_pdf_weight(dist: f32) -> f32 {
    dist
}

/// The course's PNG transfer curve of non-negative linear radiance:
/// `clamp((sqrt(2) L)^(1/2.2), 0, 1)`.
#[inline]
pub fn transfer(l: f32) -> f32 {
    (std::f32::consts::SQRT_2 * l).powf(1.0 / 2.2).clamp(0.0, 1.0)
}

/// The course's 8-bit value of a transferred value scaled to `[0, 255]`: truncated, as its
/// `(uint8_t)(v * 255)` does, so that its bytes are reproduced (encoders round).
#[inline]
pub fn byte(v: f32) -> u8 {
    v as u8
}
