use super::LightSample;
use crate::sampling::{Frame, warp};
use crate::scene::EnvMap;
use glam::Vec3;
use std::sync::Arc;

/// Radiance arriving from infinity: `upper` from directions with y > 0 (the CS184 hemisphere
/// light), `all` from every direction (a constant environment), plus an environment map.
///
/// Without a map it is sampled cosine-weighted about the shading normal exactly as before
/// (one predictable branch on `map`). With a map, directions come from the map's
/// luminance distribution, mixed half and half with cosine sampling when a constant or
/// hemisphere term is present too (so every direction with light has density).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Infinite {
    pub upper: Vec3,
    pub all: Vec3,
    pub map: Option<Arc<EnvMap>>,
}

impl Infinite {
    /// Radiance arriving along `-wi` (looking toward `wi`).
    #[inline]
    pub fn radiance(&self, wi: Vec3) -> Vec3 {
        let c = if wi.y > 0.0 { self.upper + self.all } else { self.all };
        match &self.map {
            None => c,
            Some(m) => c + m.radiance(wi),
        }
    }

    /// Probability of drawing from the map rather than the cosine lobe.
    #[inline]
    fn map_fraction(&self) -> f32 {
        if self.upper == Vec3::ZERO && self.all == Vec3::ZERO { 1.0 } else { 0.5 }
    }

    /// Draws a direction about the shading normal `n` from two uniform numbers; the sample's
    /// weight is radiance / pdf (the density [`pdf`](Self::pdf) reports).
    #[inline]
    pub fn sample(&self, n: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let Some(map) = &self.map else {
            let local = warp::cosine_hemisphere(u[0], u[1]);
            let wi = Frame::new(n).to_world(local);
            let pdf = warp::cosine_hemisphere_pdf(local.z);
            if pdf <= 0.0 {
                return None;
            }
            let l = self.radiance(wi);
            if l == Vec3::ZERO {
                return None;
            }
            return Some(LightSample { wi, target: None, weight: l / pdf });
        };
        let f = self.map_fraction();
        if f == 1.0 {
            // The map alone: its own density and the texel drawn, no second lookup.
            let (wi, pdf, l) = map.sample_texel(u)?;
            return Some(LightSample { wi, target: None, weight: l / pdf });
        }
        let wi = if u[0] < f {
            map.sample_dir([u[0] / f, u[1]])?.0
        } else {
            let a = ((u[0] - f) / (1.0 - f)).min(1.0 - f32::EPSILON);
            Frame::new(n).to_world(warp::cosine_hemisphere(a, u[1]))
        };
        let pdf = self.pdf(n, wi);
        let l = self.radiance(wi);
        if pdf <= 0.0 || l == Vec3::ZERO {
            return None;
        }
        Some(LightSample { wi, target: None, weight: l / pdf })
    }

    /// The solid-angle density with which [`sample`](Self::sample) draws `wi` at a point with
    /// shading normal `n` (for multiple importance sampling).
    #[inline]
    pub fn pdf(&self, n: Vec3, wi: Vec3) -> f32 {
        let cos = warp::cosine_hemisphere_pdf(wi.dot(n).max(0.0));
        match &self.map {
            None => cos,
            Some(m) => {
                let f = self.map_fraction();
                f * m.pdf(wi) + (1.0 - f) * cos
            }
        }
    }
}
