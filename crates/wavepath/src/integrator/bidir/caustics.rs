//! The path tracer's side of path+light in the wavefront: what a camera path carries so
//! that the caustics it finds (light reached from a delta vertex, a mirror or smooth glass)
//! are weighed against light tracing, which draws the same paths from the emissive
//! triangles. One running number per path (`pl`, the ratio of light tracing's density of
//! the path so far to the camera's, squared), updated where a path leaves a vertex and
//! read where it reaches emission after a delta vertex: the quantity `d_pl` of
//! [`walk::PathState`](super::walk::PathState), in the form the wavefront's kernels use.

use super::importance::Importance;
use super::walk::mis;
use super::{Picker, light_path_count};
use crate::integrator::camera::CameraTerms;
use crate::lights::emission::SceneSphere;
use crate::lights::{LightSet, SampledLight};
use crate::settings::Settings;
use glam::Vec3;

/// What camera paths read to weigh caustics against light tracing.
#[derive(Clone, Debug)]
pub struct CausticTerms {
    camera: Importance,
    /// Light subpaths per iteration (sample index).
    light_paths: f32,
    /// Each light's probability of starting a light subpath.
    emit: Vec<f32>,
}

impl CausticTerms {
    /// The terms of a path+light render of `settings` (its whole image); `None` where the
    /// camera has no importance (not a pinhole: refused by [`super::unsupported`]).
    pub fn new(camera: &CameraTerms, lights: &LightSet, sphere: &SceneSphere, settings: &Settings) -> Option<Self> {
        let (w, h) = (settings.image.width, settings.image.height);
        Some(CausticTerms {
            camera: Importance::new(camera, w, h)?,
            light_paths: light_path_count(super::Mode::PathLight, settings) as f32,
            emit: emitters(lights, sphere).pick,
        })
    }

    /// `pl` after a path leaves its first vertex by a non-delta sample: the camera ray along
    /// `dir` reached the vertex at distance `t` and cosine `cos_in` to its geometric normal;
    /// the sample leaves at cosine `cos_out` with density `pdf`.
    #[inline(always)]
    pub fn first(&self, dir: Vec3, t: f32, cos_in: f32, cos_out: f32, pdf: f32) -> f32 {
        let camera_pdf_w = self.camera.pdf_w(self.camera.cos_of(dir));
        sane(mis(self.light_paths * t * t * cos_out / (camera_pdf_w * cos_in * pdf)))
    }

    /// `pl` after a path leaves a later vertex: arrived at cosine `cos_in`, leaves at `cos_out`
    /// by a delta lobe or with density `pdf` (and `pdf_rev` the reverse's).
    #[inline(always)]
    pub fn next(pl: f32, cos_in: f32, cos_out: f32, delta: bool, pdf: f32, pdf_rev: f32) -> f32 {
        let r = if delta { mis(cos_out / cos_in) } else { mis(cos_out * pdf_rev / (cos_in * pdf)) };
        sane(pl * r)
    }

    /// The weight of emission a camera path with `pl` finds after a delta vertex on triangle
    /// `prim`, reached along `dir`: the power heuristic against light tracing (1 where no
    /// light subpath starts on that triangle).
    #[inline]
    pub fn hit_weight(&self, lights: &LightSet, prim: u32, dir: Vec3, pl: f32) -> f32 {
        if pl <= 0.0 {
            return 1.0;
        }
        for (i, light) in lights.lights.iter().enumerate() {
            if let SampledLight::Emissive(e) = light
                && self.emit[i] > 0.0
                && let Some(p) = e.emission_pdf_per_cos(prim, -dir)
            {
                return 1.0 / (1.0 + mis(self.emit[i] * p) * pl);
            }
        }
        1.0
    }
}

/// A density ratio kept a number: a grazing vertex (cosine 0) makes light tracing certain
/// (the largest finite value) rather than NaN.
#[inline(always)]
fn sane(x: f32) -> f32 {
    if x.is_nan() { 0.0 } else { x.min(f32::MAX) }
}

/// The choice of light for path+light's light subpaths: the emissive triangles, by power (the
/// lights whose caustics the path tracer also finds; none when the scene has none).
pub(super) fn emitters(lights: &LightSet, sphere: &SceneSphere) -> Picker {
    let powers: Vec<f32> = lights
        .lights
        .iter()
        .map(|l| if matches!(l, SampledLight::Emissive(_)) { l.power(sphere) } else { 0.0 })
        .collect();
    if powers.iter().any(|&p| p > 0.0) { Picker::by_power(&powers) } else { Picker::none(powers.len()) }
}
