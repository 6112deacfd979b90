use super::LightSample;
use crate::sampling::{Frame, warp};
use glam::Vec3;

/// Radiance arriving from infinity: `upper` from directions with y > 0 (the CS184 hemisphere
/// light), `all` from every direction (a constant environment).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Infinite {
    pub upper: Vec3,
    pub all: Vec3,
}

impl Infinite {
    /// Radiance arriving along `-wi` (looking toward `wi`).
    #[inline]
    pub fn radiance(&self, wi: Vec3) -> Vec3 {
        if wi.y > 0.0 { self.upper + self.all } else { self.all }
    }

    /// Draws a direction about the shading normal `n` (cosine-weighted) from two uniform
    /// numbers; the sample's weight is radiance / pdf.
    #[inline]
    pub fn sample(&self, n: Vec3, u: [f32; 2]) -> Option<LightSample> {
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
        Some(LightSample { wi, target: None, weight: l / pdf })
    }

    /// The solid-angle density with which [`sample`](Self::sample) draws `wi` at a point with
    /// shading normal `n` (for multiple importance sampling).
    #[inline]
    pub fn pdf(&self, n: Vec3, wi: Vec3) -> f32 {
        warp::cosine_hemisphere_pdf(wi.dot(n).max(0.0))
    }
}
