use super::BsdfSample;
use crate::sampling::warp;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Ideal diffuse reflection, sampled cosine-weighted (weight = albedo exactly).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert {
    pub albedo: Vec3,
}

impl Lambert {
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z > 0.0 && wi.z > 0.0 { self.albedo * FRAC_1_PI } else { Vec3::ZERO }
    }

    #[inline]
    pub fn sample(&self, wo: Vec3, u: [f32; 2]) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = warp::cosine_hemisphere(u[0], u[1]);
        let pdf = warp::cosine_hemisphere_pdf(wi.z);
        (pdf > 0.0).then_some(BsdfSample { wi, weight: self.albedo, pdf, delta: false })
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z > 0.0 { warp::cosine_hemisphere_pdf(wi.z) } else { 0.0 }
    }
}
