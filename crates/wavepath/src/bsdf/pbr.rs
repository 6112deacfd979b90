use super::microfacet::normalized;
use super::{BsdfSample, Distribution, Microfacet};
use crate::sampling::warp;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// glTF's material model (the core specification's appendix B): a diffuse base under a
/// GGX specular layer whose Schlick Fresnel reflectance at normal incidence is `f0`.
///
/// f = diffuse (1 - F_d(wo.h)) / pi + F(wo.h) D(h) G(wo, wi) / (4 cos_o cos_i), with Schlick's
/// F(c) = f0 + (1 - f0)(1 - c)^5 and F_d the same with `diffuse_f0`. Metallic-roughness
/// materials give diffuse = (1 - metallic) base, f0 = lerp(0.04, base, metallic) and
/// diffuse_f0 = 0.04: Schlick is linear in f0, so this is exactly the specification's mix of
/// its dielectric (ior 1.5) and metal BRDFs. Specular-glossiness materials give
/// f0 = diffuse_f0 = specular and diffuse = diffuse (1 - max(specular)), as that extension's
/// reference does. The GGX lobe is the rough conductor's code (height-correlated Smith G).
///
/// Sampling picks the specular lobe with the probability of its share of the reflectance
/// seen from `wo` and the cosine lobe otherwise; `pdf` is the mixture's, so light sampling
/// and BSDF sampling combine by MIS like any glossy model. The specular lobe draws visible
/// normals (Heitz 2018): its sample weight F G / G1(wo) stays below 1 at grazing angles,
/// where drawing from D alone gives weights of order 1 / alpha.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pbr {
    pub diffuse: Vec3,
    pub f0: Vec3,
    /// Normal-incidence reflectance of the layer the diffuse light passes through.
    pub diffuse_f0: Vec3,
    pub alpha: f32,
}

impl Pbr {
    /// glTF `pbrMetallicRoughness` (alpha = roughness^2, the specification's mapping).
    pub fn metallic_roughness(base: Vec3, metallic: f32, roughness: f32) -> Pbr {
        let m = metallic.clamp(0.0, 1.0);
        let r = roughness.clamp(0.0, 1.0);
        let base = base.clamp(Vec3::ZERO, Vec3::ONE);
        let dielectric = Vec3::splat(0.04);
        Pbr { diffuse: base * (1.0 - m), f0: dielectric.lerp(base, m), diffuse_f0: dielectric, alpha: r * r }
    }

    /// `KHR_materials_pbrSpecularGlossiness` (roughness = 1 - glossiness).
    pub fn specular_glossiness(diffuse: Vec3, specular: Vec3, glossiness: f32) -> Pbr {
        let specular = specular.clamp(Vec3::ZERO, Vec3::ONE);
        let r = 1.0 - glossiness.clamp(0.0, 1.0);
        let diffuse = diffuse.clamp(Vec3::ZERO, Vec3::ONE) * (1.0 - specular.max_element());
        Pbr { diffuse, f0: specular, diffuse_f0: specular, alpha: r * r }
    }

    /// The GGX lobe (D, G and the conductor's numerical guards; its Fresnel is not used).
    #[inline(always)]
    fn lobe(&self) -> Microfacet {
        Microfacet { alpha: self.alpha, eta: Vec3::ZERO, k: Vec3::ZERO, distribution: Distribution::Ggx }
    }

    /// Schlick's Fresnel for reflectance `f0` at normal incidence.
    #[inline(always)]
    fn schlick(f0: Vec3, cos: f32) -> Vec3 {
        let m = 1.0 - cos.clamp(0.0, 1.0);
        let m2 = m * m;
        f0 + (Vec3::ONE - f0) * (m2 * m2 * m)
    }

    /// Probability of sampling the specular lobe from `wo`: its Fresnel reflectance against
    /// the diffuse colour. The diffuse share is not reduced by the Fresnel term at `wo`: the
    /// diffuse term weighs (1 - F) at the half vector, which stays large for most directions
    /// even when `wo` grazes, and a diffuse lobe chosen rarely there would give fireflies.
    #[inline(always)]
    fn specular_probability(&self, wo: Vec3) -> f32 {
        let s = Self::schlick(self.f0, wo.z).element_sum();
        let d = self.diffuse.element_sum();
        if s + d > 0.0 { (s / (s + d)).clamp(0.0, 1.0) } else { 1.0 }
    }

    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let Some(h) = (wo + wi).try_normalize() else { return Vec3::ZERO };
        let oh = wo.dot(h);
        let lobe = self.lobe();
        let spec = lobe.d(h) * lobe.g(wo, wi) / (4.0 * wo.z * wi.z);
        let spec = if spec.is_finite() { spec } else { 0.0 };
        self.diffuse * (Vec3::ONE - Self::schlick(self.diffuse_f0, oh)) * FRAC_1_PI + Self::schlick(self.f0, oh) * spec
    }

    /// `u[2]` chooses the lobe, `u[0]` and `u[1]` the direction within it.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: [f32; 3]) -> Option<BsdfSample> {
        let (s, ok) = self.sample_at(wo, u, (std::f32::consts::TAU * u[1]).sin_cos());
        ok.then_some(s)
    }

    /// [`sample`](Self::sample) with the sine and cosine of `2 pi u[1]` given (a lane kernel
    /// takes them one lane at a time), without branches: the sample and whether there is one
    /// (what `sample` returns as `None`: the specular lobe found no direction, or the density
    /// or the weight is not a finite positive number).
    #[inline(always)]
    pub fn sample_at(&self, wo: Vec3, u: [f32; 3], sin_cos: (f32, f32)) -> (BsdfSample, bool) {
        let specular = u[2] < self.specular_probability(wo);
        let (visible, visible_ok) = self.lobe().sample_visible_at(wo, u[0], sin_cos);
        let wi = if specular { visible } else { warp::cosine_hemisphere(u[0], u[1]) };
        let (f, pdf) = self.eval_pdf(wo, wi);
        let weight = f * (wi.z / pdf);
        let ok = wo.z > 0.0 && (visible_ok || !specular) && pdf > 0.0 && pdf.is_finite() && weight.is_finite();
        (BsdfSample { wi, weight, pdf, delta: false }, ok)
    }

    /// [`eval`](Self::eval) and [`pdf`](Self::pdf) at once (the half vector, D and Smith's
    /// Lambda(wo) shared), bit for bit the two calls' values; without branches (every case
    /// computed, the valid one kept), so that a lane kernel's loop over it vectorises.
    #[inline(always)]
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let above = wo.z > 0.0 && wi.z > 0.0;
        let p = self.specular_probability(wo);
        let diffuse_pdf = (1.0 - p) * warp::cosine_hemisphere_pdf(wi.z);
        let (h, has_h) = normalized(wo + wi);
        let oh = wo.dot(h);
        let (spec, visible) = self.lobe().spec_and_visible_pdf(wo, wi, h);
        let f = self.diffuse * (Vec3::ONE - Self::schlick(self.diffuse_f0, oh)) * FRAC_1_PI
            + Self::schlick(self.f0, oh) * spec;
        let pdf = if has_h { p * visible + diffuse_pdf } else { diffuse_pdf };
        (if above && has_h { f } else { Vec3::ZERO }, if above { pdf } else { 0.0 })
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let p = self.specular_probability(wo);
        p * self.lobe().visible_pdf(wo, wi) + (1.0 - p) * warp::cosine_hemisphere_pdf(wi.z)
    }
}
