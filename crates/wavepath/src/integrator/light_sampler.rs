//! The light sampler: the scene's light set with its sampling tables, the fast path's area
//! lights and each light's shadow-ray margin.

use super::area::AreaLight;
use super::emitter_filter::EmitterFilter;
use crate::geometry::offset::shadow_margin;
use crate::lights::{LightSet, SampledLight};
use crate::scene::Scene;
use crate::settings::Settings;

pub struct LightSampler {
    pub set: LightSet,
    /// Per light: its sampling data when it is an area light.
    pub area_lights: Vec<Option<AreaLight>>,
    /// Per light: [`shadow_margin`] of its points.
    pub shadow_margins: Vec<f32>,
    /// Some light is an area light, which a ray can reach before the surface it hits.
    pub area_arrivals: bool,
    /// The light from infinity's place in the set, if the scene has one.
    pub infinite: Option<usize>,
    /// Where emissive triangles are the only light a ray can find: the test that lets a
    /// last-depth ray that misses them all end untraced.
    pub emitters: Option<EmitterFilter>,
}

impl LightSampler {
    pub fn new(scene: &Scene, settings: &Settings) -> LightSampler {
        let mut set = LightSet::new(scene);
        if settings.cs184.light_pdf {
            set.use_cs184_area_pdf();
        }
        let shadow_margins: Vec<f32> = set.lights.iter().map(|l| shadow_margin(l.point_error())).collect();
        let area_lights = set
            .lights
            .iter()
            .zip(&shadow_margins)
            .map(|(l, &margin)| match *l {
                // The fast path computes the correct estimator only; the biased one goes
                // through the general light sample.
                SampledLight::Area { position, normal, dim_x, dim_y, area, cs184_pdf: false, .. } => {
                    Some(AreaLight { position, normal, dim_x, dim_y, area, margin })
                }
                _ => None,
            })
            .collect();
        let area_arrivals = set.lights.iter().any(|l| matches!(l, SampledLight::Area { .. }));
        let infinite = set.lights.iter().position(|l| matches!(l, SampledLight::Infinite(_)));
        let emitters = EmitterFilter::new(scene, area_arrivals || infinite.is_some(), settings.execution.isa);
        LightSampler { set, area_lights, shadow_margins, area_arrivals, infinite, emitters }
    }
}
