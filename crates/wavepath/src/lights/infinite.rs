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
        self.sample_pdf(n, u).map(|(ls, _)| ls)
    }

    /// As [`sample`](Self::sample), with the sample's solid-angle density. The steps are
    /// the ones the lane kernels take for all lanes at once (the map's table read, then
    /// [`Sky::drawn`], then for a mixture the map looked up toward the direction chosen
    /// and [`Sky::mixed`]), so one lane and many compute the same bits.
    #[inline]
    pub fn sample_pdf(&self, n: Vec3, u: [f32; 2]) -> Option<(LightSample, f32)> {
        let sky = self.sky();
        let Some(map) = &self.map else {
            let (wi, weight, valid) = sky.sample_cosine(n, u);
            return valid.then(|| (LightSample { wi, target: None, weight }, sky.pdf_with(n, wi, 0.0, false)));
        };
        let (uv, index) = map.draw(sky.map_numbers(u));
        let (texel, pdf_uv) = map.texel_at(index);
        let s = sky.drawn(n, u, uv, pdf_uv, texel);
        let s = if sky.map_alone() {
            s
        } else {
            let (l, p) = map.lookup(s.wi);
            sky.mixed(n, s, l, p)
        };
        s.valid.then_some((LightSample { wi: s.wi, target: None, weight: s.weight }, s.pdf))
    }

    /// [`radiance`](Self::radiance) and [`pdf`](Self::pdf) toward `wi` from one lookup of the map.
    #[inline]
    pub fn radiance_pdf(&self, n: Vec3, wi: Vec3) -> (Vec3, f32) {
        let (mapped, mapped_pdf) = self.map.as_ref().map_or((Vec3::ZERO, 0.0), |m| m.lookup(wi));
        let (sky, has_map) = (self.sky(), self.map.is_some());
        (sky.radiance_with(wi, mapped, has_map), sky.pdf_with(n, wi, mapped_pdf, has_map))
    }

    /// The solid-angle density with which [`sample`](Self::sample) draws `wi` at a point with
    /// shading normal `n` (for multiple importance sampling).
    #[inline]
    pub fn pdf(&self, n: Vec3, wi: Vec3) -> f32 {
        let mapped = self.map.as_ref().map_or(0.0, |m| m.pdf(wi));
        self.sky().pdf_with(n, wi, mapped, self.map.is_some())
    }
}

/// A sample of the light from infinity: direction, radiance over density, density, and
/// whether it carries light.
#[derive(Clone, Copy, Debug)]
pub struct SkySample {
    pub wi: Vec3,
    pub weight: Vec3,
    pub pdf: f32,
    pub valid: bool,
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
        if self.map_alone() { 1.0 } else { 0.5 }
    }

    /// Whether a map is the only light from infinity (its samples need no second lookup).
    #[inline(always)]
    pub fn map_alone(&self) -> bool {
        self.upper == Vec3::ZERO && self.all == Vec3::ZERO
    }

    /// The numbers the map's table reads for a sample from `u` (for a mixture, `u[0]`
    /// rescaled over the map's share; unused where the lobe is chosen).
    #[inline(always)]
    pub fn map_numbers(&self, u: [f32; 2]) -> [f32; 2] {
        let f = self.map_fraction();
        if f == 1.0 { u } else { [u[0] / f, u[1]] }
    }

    /// A sample from the map's draw (`uv` from [`EnvMap::draw`] at
    /// [`map_numbers`](Self::map_numbers)`(u)`, `texel` and `pdf_uv` of the texel it drew): with the map alone, complete (the texel
    /// drawn is the radiance, the draw's density the pdf); in a mixture, only the direction
    /// (the map's or the cosine lobe's, chosen by `u[0]`), which [`mixed`](Self::mixed) weighs.
    #[inline(always)]
    pub fn drawn(&self, n: Vec3, u: [f32; 2], uv: [f32; 2], pdf_uv: f32, texel: Vec3) -> SkySample {
        let (d, pdf) = EnvMap::sampled(uv, pdf_uv);
        let f = self.map_fraction();
        if f == 1.0 {
            let valid = pdf > 0.0;
            return SkySample { wi: d, weight: if valid { texel / pdf } else { Vec3::ZERO }, pdf, valid };
        }
        let a = ((u[0] - f) / (1.0 - f)).min(1.0 - f32::EPSILON);
        let lobe = Frame::new(n).to_world(warp::cosine_hemisphere(a, u[1]));
        let from_map = u[0] < f;
        let wi = if from_map { d } else { lobe };
        SkySample { wi, weight: Vec3::ZERO, pdf: 0.0, valid: !from_map || pdf > 0.0 }
    }

    /// A mixture's sample `s` (from [`drawn`](Self::drawn)) completed with the map's
    /// radiance `mapped` and density `mapped_pdf` toward its direction.
    #[inline(always)]
    pub fn mixed(&self, n: Vec3, s: SkySample, mapped: Vec3, mapped_pdf: f32) -> SkySample {
        let pdf = self.pdf_with(n, s.wi, mapped_pdf, true);
        let l = self.radiance_with(s.wi, mapped, true);
        let valid = s.valid & (pdf > 0.0) & (l != Vec3::ZERO);
        SkySample { wi: s.wi, weight: if valid { l / pdf } else { Vec3::ZERO }, pdf, valid }
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
