use super::microfacet::normalized;
use super::{BsdfSample, Distribution, Microfacet};
use crate::sampling::warp;
use crate::scene::phong_alpha;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// The Phong model of MTL files (`illum 2`: `Kd`, `Ks`, `Ns`) and of COLLADA's `<phong>` and
/// `<blinn>`, as a physically based renderer shades it: a Lambertian lobe plus a GGX
/// microfacet lobe of constant reflectance `specular`,
///
///   f = diffuse / pi + specular D(h) G(wo, wi) / (4 cos_o cos_i),
///
/// with no Fresnel term: `Ks` is the file's specular colour at every angle, as in the Phong
/// model it stands for (and as a `Ks` mirror, `illum 3`, reflects Fresnel-free). D and G are
/// the rough conductor's GGX (height-correlated Smith G).
///
/// The Phong exponent n becomes a roughness by the Phong–Beckmann correspondence of Walter et
/// al. 2007 ("Microfacet Models for Refraction through Rough Surfaces", section 5.2:
/// n = 2 / alpha^2 - 2, so alpha = sqrt(2 / (n + 2))), the usual exponent-to-roughness rule
/// of physically based renderers; GGX takes it as its alpha, the two distributions agreeing
/// near their peaks. `Ns 0` gives alpha 1, `Ns 10` 0.41, `Ns 1000` 0.045.
///
/// Energy: the lobes reflect at most `diffuse + specular` (the specular lobe a little less:
/// single-scattering microfacets lose what bounces between facets would return: about 1%
/// of `Ks` at alpha 0.045, `Ns 1000`; tens of percent at alpha 1, where facets steeper than
/// 45 degrees reflect into the surface), so `diffuse`
/// is scaled down, keeping its hue, where `Kd + Ks` exceeds 1 in a channel: the condition
/// Phong's energy-conserving form puts on its parameters (Lafortune and Willems 1994).
///
/// Sampling picks the specular lobe with the probability of its share of the reflectance
/// (constant over directions) and draws visible normals; `pdf` is the mixture's, so light
/// and BSDF samples combine by MIS as for any glossy model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glossy {
    pub diffuse: Vec3,
    pub specular: Vec3,
    pub alpha: f32,
}

impl Glossy {
    /// From the file's colours and exponent: `specular` clamped to [0, 1], `diffuse` scaled
    /// so that `diffuse + specular <= 1` in every channel.
    pub fn phong(diffuse: Vec3, specular: Vec3, exponent: f32) -> Glossy {
        let specular = specular.clamp(Vec3::ZERO, Vec3::ONE);
        let diffuse = diffuse.max(Vec3::ZERO);
        let room = Vec3::ONE - specular;
        let mut scale = 1.0f32;
        for c in 0..3 {
            if diffuse[c] > room[c] {
                scale = scale.min(room[c] / diffuse[c]);
            }
        }
        Glossy { diffuse: diffuse * scale, specular, alpha: phong_alpha(exponent) }
    }

    #[inline(always)]
    fn lobe(&self) -> Microfacet {
        Microfacet { alpha: self.alpha, eta: Vec3::ZERO, k: Vec3::ZERO, distribution: Distribution::Ggx }
    }

    /// Probability of sampling the specular lobe.
    #[inline(always)]
    fn specular_probability(&self) -> f32 {
        let (s, d) = (self.specular.element_sum(), self.diffuse.element_sum());
        if s + d > 0.0 { s / (s + d) } else { 0.0 }
    }

    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let Some(h) = (wo + wi).try_normalize() else { return self.diffuse * FRAC_1_PI };
        let lobe = self.lobe();
        let spec = lobe.d(h) * lobe.g(wo, wi) / (4.0 * wo.z * wi.z);
        let spec = if spec.is_finite() { spec } else { 0.0 };
        self.diffuse * FRAC_1_PI + self.specular * spec
    }

    /// `u[2]` chooses the lobe, `u[0]` and `u[1]` the direction within it.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: [f32; 3]) -> Option<BsdfSample> {
        let (s, ok) = self.sample_at(wo, u, (std::f32::consts::TAU * u[1]).sin_cos());
        ok.then_some(s)
    }

    /// [`sample`](Self::sample) with the sine and cosine of `2 pi u[1]` given, without
    /// branches: the sample and whether there is one (as `Pbr::sample_at`).
    #[inline(always)]
    pub fn sample_at(&self, wo: Vec3, u: [f32; 3], sin_cos: (f32, f32)) -> (BsdfSample, bool) {
        let specular = u[2] < self.specular_probability();
        let (visible, visible_ok) = self.lobe().sample_visible_at(wo, u[0], sin_cos);
        let wi = if specular { visible } else { warp::cosine_hemisphere(u[0], u[1]) };
        let (f, pdf) = self.eval_pdf(wo, wi);
        let weight = f * (wi.z / pdf);
        let reflects = self.diffuse.max(self.specular).max_element() > 0.0;
        let ok =
            wo.z > 0.0 && reflects && (visible_ok || !specular) && pdf > 0.0 && pdf.is_finite() && weight.is_finite();
        (BsdfSample { wi, weight, pdf, delta: false }, ok)
    }

    /// [`eval`](Self::eval) and [`pdf`](Self::pdf) at once (the half vector, D and Smith's
    /// Lambda(wo) shared), bit for bit the two calls' values; without branches, as
    /// `Pbr::eval_pdf`.
    #[inline(always)]
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let above = wo.z > 0.0 && wi.z > 0.0;
        let p = self.specular_probability();
        let diffuse_pdf = (1.0 - p) * warp::cosine_hemisphere_pdf(wi.z);
        let (h, has_h) = normalized(wo + wi);
        let (spec, visible) = self.lobe().spec_and_visible_pdf(wo, wi, h);
        let spec_pdf = if p > 0.0 { p * visible } else { 0.0 };
        let diffuse = self.diffuse * FRAC_1_PI;
        let (f, pdf) =
            if has_h { (diffuse + self.specular * spec, spec_pdf + diffuse_pdf) } else { (diffuse, diffuse_pdf) };
        if above { (f, pdf) } else { (Vec3::ZERO, 0.0) }
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let p = self.specular_probability();
        let spec = if p > 0.0 { p * self.lobe().visible_pdf(wo, wi) } else { 0.0 };
        spec + (1.0 - p) * warp::cosine_hemisphere_pdf(wi.z)
    }
}
