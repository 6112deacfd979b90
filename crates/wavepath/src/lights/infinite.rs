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
        let mapped = self.map.as_ref().map_or(Vec3::ZERO, |m| m.radiance(wi));
        self.sky().radiance_with(wi, mapped, self.map.is_some())
    }

    /// Its constant terms, which the lane kernels keep in registers.
    #[inline(always)]
    pub fn sky(&self) -> Sky {
        Sky { upper: self.upper, all: self.all }
    }

    /// Draws a direction about the shading normal `n` from two uniform numbers; the sample's
    /// weight is radiance / pdf (the density [`pdf`](Self::pdf) reports).
    #[inline]
    pub fn sample(&self, n: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let Some(map) = &self.map else {
            let (wi, weight, valid) = self.sky().sample_cosine(n, u);
            return valid.then_some(LightSample { wi, target: None, weight });
        };
        let f = self.sky().map_fraction();
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
        let mapped = self.map.as_ref().map_or(0.0, |m| m.pdf(wi));
        self.sky().pdf_with(n, wi, mapped, self.map.is_some())
    }
}

/// The constant terms of the light from infinity (the hemisphere light and the constant
/// environment), a copy small enough for registers: the branch-free functions here are what
/// the one-path code and the lane kernels (which look the map up one lane at a time and pass
/// its values in) both compute with.
#[derive(Clone, Copy, Debug)]
pub struct Sky {
    pub upper: Vec3,
    pub all: Vec3,
}

impl Sky {
    /// [`Infinite::radiance`] with the map's own radiance toward `wi` looked up by the caller
    /// (`mapped`, read only when `has_map`).
    #[inline(always)]
    pub fn radiance_with(&self, wi: Vec3, mapped: Vec3, has_map: bool) -> Vec3 {
        let c = if wi.y > 0.0 { self.upper + self.all } else { self.all };
        if has_map { c + mapped } else { c }
    }

    /// Probability of drawing from the map rather than the cosine lobe.
    #[inline(always)]
    fn map_fraction(&self) -> f32 {
        if self.upper == Vec3::ZERO && self.all == Vec3::ZERO { 1.0 } else { 0.5 }
    }

    /// [`Infinite::sample`] where there is no map, without branches (the lane kernels
    /// call it on every lane): the direction, radiance over density, and whether it carries
    /// light.
    #[inline(always)]
    pub fn sample_cosine(&self, n: Vec3, u: [f32; 2]) -> (Vec3, Vec3, bool) {
        let local = warp::cosine_hemisphere(u[0], u[1]);
        let wi = Frame::new(n).to_world(local);
        let pdf = warp::cosine_hemisphere_pdf(local.z);
        let l = self.radiance_with(wi, Vec3::ZERO, false);
        (wi, l / pdf, (pdf > 0.0) & (l != Vec3::ZERO))
    }

    /// [`Infinite::pdf`] with the map's own density of `wi` looked up by the caller
    /// (`mapped`, read only when `has_map`), as [`radiance_with`](Self::radiance_with).
    #[inline(always)]
    pub fn pdf_with(&self, n: Vec3, wi: Vec3, mapped: f32, has_map: bool) -> f32 {
        let cos = warp::cosine_hemisphere_pdf(wi.dot(n).max(0.0));
        if has_map {
            let f = self.map_fraction();
            f * mapped + (1.0 - f) * cos
        } else {
            cos
        }
    }
}
