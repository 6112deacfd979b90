//! The path rules: what a pixel counts, how deep paths go, how direct light is estimated
//! (light or hemisphere samples, MIS) and when Russian roulette stops a path.

use super::DIM_ROULETTE;
use crate::effects::Effects;
use crate::lights::LightSet;
use crate::sampling::Numbers;
use crate::settings::{RouletteKind, Settings, Shading};
use glam::Vec3;

/// Which optional parts of the vertex kernel a render runs, from the effects table: a part
/// whose effect is off is skipped (a stage not run, a branch not taken). Tested at run time,
/// once per path or group of lanes and always the same way in a render, so the branch is
/// predicted; compiling a kernel per combination (2^6 copies of the wavefront) cost most of
/// the engine's build and bought no measurable speed (docs/decisions.md, "Compile time").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Features {
    /// Emission seen by camera rays.
    pub emission: bool,
    /// The environment seen by camera rays that miss.
    pub environment: bool,
    /// Direct-light rays and the shadow stage.
    pub direct: bool,
    /// Continuation rays and the bounce (compact) stage.
    pub indirect: bool,
    /// Russian roulette (played in shade, where the vertex stream is at hand).
    pub roulette: bool,
    /// Materials other than Lambertian: shading goes through the BSDF models, and a path's
    /// ray can find light (after a mirror, glass or glossy bounce).
    pub non_diffuse: bool,
}

impl Features {
    /// Every part on: the same image as the parts a scene needs, only slower.
    pub const ALL: Features =
        Features { emission: true, environment: true, direct: true, indirect: true, roulette: true, non_diffuse: true };

    /// The parts the effects call for.
    pub fn of(e: &Effects) -> Features {
        Features {
            emission: e.emission,
            environment: e.environment,
            direct: e.direct,
            indirect: e.indirect,
            roulette: e.russian_roulette,
            non_diffuse: e.non_diffuse,
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct Rules {
    /// The kernel's optional parts.
    pub features: Features,
    pub max_depth: u32,
    pub accumulate: bool,
    pub hemisphere: bool,
    pub light_samples: u32,
    /// Shadow (or hemisphere probe) rays one vertex casts at most.
    pub direct_per_vertex: u32,
    pub rr_continue: f32,
    /// Continue probability from the path's throughput instead of `rr_continue`.
    pub rr_throughput: bool,
    /// First depth that plays roulette.
    pub rr_depth: u32,
    /// Diffuse vertices weigh their light samples against their BSDF sample by MIS
    /// ([`diffuse_mis`](Self::diffuse_mis)) where the scene calls for it (the `mis` effect).
    pub mis: bool,
}

impl Rules {
    pub fn new(settings: &Settings, effects: &Effects, lights: &LightSet) -> Rules {
        let max_depth = if settings.paths.shading == Shading::Direct {
            settings.paths.max_depth.min(1)
        } else {
            settings.paths.max_depth
        };
        let light_samples = settings.sampling.light_samples.max(1);
        let direct_per_vertex = if settings.paths.hemisphere {
            // As the seed: as many hemisphere samples as light sampling would take for
            // area lights, lights x -l.
            (lights.lights.len() as u32 * light_samples).max(light_samples)
        } else {
            lights.samples_per_point(light_samples)
        };
        Rules {
            features: Features::of(effects),
            max_depth,
            accumulate: settings.paths.accumulate,
            hemisphere: settings.paths.hemisphere,
            light_samples,
            direct_per_vertex,
            rr_continue: settings.paths.roulette.continue_prob.clamp(1e-3, 1.0),
            rr_throughput: settings.paths.roulette.kind == RouletteKind::Throughput,
            rr_depth: settings.paths.roulette.start_depth.max(1),
            mis: effects.mis,
        }
    }

    /// Whether emission seen directly by the camera is part of the image.
    #[inline]
    pub fn counts_emission(&self) -> bool {
        self.accumulate || self.max_depth == 0
    }

    /// Whether direct light at a vertex of `depth` (0 = the camera's hit) is part of the image:
    /// it took `depth + 1` bounces.
    #[inline]
    pub fn counts_direct(&self, depth: u32) -> bool {
        depth < self.max_depth && (self.accumulate || depth + 1 == self.max_depth)
    }

    /// Whether a diffuse vertex at `depth` combines its light samples with its BSDF-sampled
    /// ray by the power heuristic: wherever its direct light counts, the last depth included.
    /// There the ray is traced for the light it finds and nothing more
    /// ([`diffuse_continues`](Self::diffuse_continues)), as glossy vertices do: light sampling
    /// alone at the last vertex left an emitter's near neighbourhood (a light hung just below
    /// a ceiling) to unweighted samples worth Le cos cos A / r^2, fireflies a thousand times
    /// the image's mean.
    #[inline(always)]
    pub fn diffuse_mis(&self, depth: u32) -> bool {
        self.mis && self.counts_direct(depth)
    }

    /// Whether a diffuse vertex at `depth` sends a BSDF-sampled ray: to continue the path, or
    /// at the last depth to collect the light MIS weighs against its light samples.
    #[inline(always)]
    pub fn diffuse_continues(&self, depth: u32) -> bool {
        self.continues(depth) || self.diffuse_mis(depth)
    }

    /// Whether a vertex of `depth` spawns a continuation ray.
    #[inline]
    pub fn continues(&self, depth: u32) -> bool {
        depth + 1 < self.max_depth
    }

    /// Russian roulette for the continuation of a vertex at `depth` whose path throughput,
    /// the continuation's BSDF weight included, is `throughput`: `None` stops the path,
    /// otherwise the factor (1 / continue probability) its throughput is multiplied by. It
    /// is played from depth `rr_depth` on (at least 1: it never stops the first indirect
    /// bounce, the continuation of the camera's hit).
    #[inline]
    pub fn roulette(&self, depth: u32, rng: impl Numbers, throughput: Vec3) -> Option<f32> {
        if !self.plays_roulette(depth) {
            return Some(1.0);
        }
        self.roulette_with(rng.at(DIM_ROULETTE).next_f32(), throughput)
    }

    /// Whether the continuation of a vertex at `depth` plays Russian roulette.
    #[inline(always)]
    pub fn plays_roulette(&self, depth: u32) -> bool {
        depth >= self.rr_depth && (self.rr_throughput || self.rr_continue < 1.0)
    }

    /// [`roulette`](Self::roulette) where it is played, from the vertex stream's number at
    /// [`DIM_ROULETTE`] (drawn eight paths at a time by the lane kernel). By throughput, the
    /// surviving path's throughput has its largest component at most 1: its weight stays
    /// bounded, and paths that carry little are the ones that stop.
    #[inline(always)]
    pub fn roulette_with(&self, u: f32, throughput: Vec3) -> Option<f32> {
        let p = if self.rr_throughput { throughput.max_element().min(1.0) } else { self.rr_continue };
        if p >= 1.0 {
            return Some(1.0);
        }
        (u < p).then(|| 1.0 / p)
    }
}
