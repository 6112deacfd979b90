use super::branch_free::pow;
use super::dielectric::fresnel_dielectric;
use super::microfacet::normalized;
use super::mirror::reflect;
use super::{BsdfSample, Distribution, Microfacet};
use crate::sampling::warp;
use crate::scene::Layers;
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, TAU};

/// Smallest sheen roughness: below it the Charlie distribution's exponent overflows.
const MIN_SHEEN_ALPHA: f32 = 1e-3;
/// Entries of a sheen albedo table, over cos(theta_o) in [0, 1].
pub const SHEEN_TABLE: usize = 32;

/// glTF's metallic-roughness model with the layers its material extensions add, as the
/// Khronos specifications compose them:
///
/// f = coat (Fc, clearcoat GGX) + (1 - Fc) [sheen + s (dielectric and metal base)],
///
/// - base: a diffuse lobe and a delta transmission lobe sharing the dielectric's
///   non-reflected light in the ratio (1 - transmission) : transmission
///   (`KHR_materials_transmission`), under a GGX specular lobe whose Fresnel term is the
///   metal's Schlick (f0 = base colour) mixed by metalness with the dielectric's
///   (f0 = ((ior - 1) / (ior + 1))^2 x specular colour, f90 = 1, weighted by the specular
///   factor: `KHR_materials_ior`, `KHR_materials_specular`);
/// - sheen (`KHR_materials_sheen`): the Charlie distribution (Estevez and Kulla 2017) with
///   Neubelt and Pettineo's visibility term, colour `sheen`; the base below it is scaled by
///   s = 1 - max(sheen) E(cos_o), E the sheen lobe's own directional albedo;
/// - clearcoat (`KHR_materials_clearcoat`): a second GGX lobe with Fresnel
///   clearcoat x Schlick(0.04, wo.h), attenuating everything under it by 1 - Fc,
///   Fc = clearcoat x Schlick(0.04, cos_o) (as the Khronos sample viewer does: with wo.h
///   there, a coat on a white base gave back 0.3% more than it received at cos_o = 0.5).
///
/// Transmission is smooth (a delta lobe whatever the roughness): through a thin wall
/// (no `KHR_materials_volume`) light goes straight on, into a volume it refracts with
/// relative index `eta` (a ray whose refraction is total reflects instead). Reflection is
/// glossy (GGX, visible-normal sampling); each continuous lobe is sampled in proportion to
/// its share of the reflectance seen from `wo`, and `pdf` is the mixture's, so light
/// sampling and BSDF sampling combine by MIS as for any glossy model. The delta lobe's
/// samples carry `delta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layered {
    /// Diffusely reflected colour: (1 - metallic) (1 - transmission) base.
    pub diffuse: Vec3,
    /// Transmitted colour: (1 - metallic) transmission base.
    pub transmit: Vec3,
    /// The specular lobe's Fresnel: f0 + (f90 - f0)(1 - c)^5.
    pub f0: Vec3,
    pub f90: f32,
    /// The dielectric's reflectance (f0 and weight): the diffuse and transmitted light is
    /// what it leaves, 1 - weight x Schlick(dielectric_f0).
    pub dielectric_f0: Vec3,
    pub specular_weight: f32,
    pub alpha: f32,
    /// Relative index of refraction into the volume (1 / ior seen from inside).
    pub eta: f32,
    pub thin: bool,
    pub clearcoat: f32,
    pub coat_alpha: f32,
    pub sheen: Vec3,
    pub sheen_alpha: f32,
    /// 1 - max(sheen) E(cos_o): set per vertex by [`Layered::seen_from`].
    pub sheen_scaling: f32,
}

/// Schlick's Fresnel with reflectance `f0` at normal incidence and `f90` at grazing.
#[inline(always)]
fn schlick(f0: Vec3, f90: f32, cos: f32) -> Vec3 {
    let m = 1.0 - cos.clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (Vec3::splat(f90) - f0) * (m2 * m2 * m)
}

#[inline(always)]
fn ggx(alpha: f32) -> Microfacet {
    Microfacet { alpha, eta: Vec3::ZERO, k: Vec3::ZERO, distribution: Distribution::Ggx }
}

impl Layered {
    /// The model at a point with base colour `base`, `metallic`, `roughness` and
    /// `transmission` (textures applied), with the material's other extension values.
    pub fn new(base: Vec3, metallic: f32, roughness: f32, transmission: f32, l: &Layers) -> Layered {
        let m = metallic.clamp(0.0, 1.0);
        let r = roughness.clamp(0.0, 1.0);
        let tr = transmission.clamp(0.0, 1.0);
        let base = base.clamp(Vec3::ZERO, Vec3::ONE);
        let ior = if l.ior.is_finite() { l.ior.max(1.0) } else { 1.5 };
        let f0_ior = ((ior - 1.0) / (ior + 1.0)).powi(2);
        let dielectric_f0 = (Vec3::splat(f0_ior) * l.specular_color).min(Vec3::ONE);
        let w = l.specular.clamp(0.0, 1.0);
        let cr = l.clearcoat_roughness.clamp(0.0, 1.0);
        let sr = l.sheen_roughness.clamp(0.0, 1.0);
        Layered {
            diffuse: base * ((1.0 - m) * (1.0 - tr)),
            transmit: base * ((1.0 - m) * tr),
            f0: (dielectric_f0 * w).lerp(base, m),
            f90: w + (1.0 - w) * m,
            dielectric_f0,
            specular_weight: w,
            alpha: r * r,
            eta: ior,
            thin: l.thickness <= 0.0,
            clearcoat: l.clearcoat.clamp(0.0, 1.0),
            coat_alpha: cr * cr,
            sheen: l.sheen_color.clamp(Vec3::ZERO, Vec3::ONE),
            sheen_alpha: (sr * sr).max(MIN_SHEEN_ALPHA),
            sheen_scaling: 1.0,
        }
    }

    /// This model on the inside of its volume: the relative index inverted.
    #[inline]
    pub fn inside(self) -> Layered {
        Layered { eta: 1.0 / self.eta, ..self }
    }

    /// This model seen from a direction of cosine `cos_o`, with the sheen albedo table of
    /// its material ([`sheen_albedo_table`]).
    #[inline]
    pub fn seen_from(self, cos_o: f32, table: &[f32; SHEEN_TABLE]) -> Layered {
        if self.sheen == Vec3::ZERO {
            return self;
        }
        let e = lookup(table, cos_o);
        Layered { sheen_scaling: (1.0 - self.sheen.max_element() * e).clamp(0.0, 1.0), ..self }
    }

    /// The Charlie sheen distribution (Estevez and Kulla 2017); its power through the
    /// branch-free [`pow`], so that the lane kernel's loops over it vectorise.
    #[inline(always)]
    fn charlie(&self, h: Vec3) -> f32 {
        let inv = 1.0 / self.sheen_alpha;
        let sin2 = (1.0 - h.z * h.z).max(0.0);
        (2.0 + inv) * pow(sin2, 0.5 * inv) / TAU
    }

    /// The sheen lobe, f (no cosine): D V with Neubelt and Pettineo's visibility.
    #[inline(always)]
    fn sheen_f(&self, wo: Vec3, wi: Vec3, h: Vec3) -> f32 {
        let v = 1.0 / (4.0 * (wi.z + wo.z - wi.z * wo.z));
        let f = self.charlie(h) * v;
        if f.is_finite() { f } else { 0.0 }
    }

    /// The clearcoat's Fresnel weight at cosine `c`.
    #[inline(always)]
    fn coat_fresnel(&self, c: f32) -> f32 {
        self.clearcoat * schlick(Vec3::splat(0.04), 1.0, c).x
    }

    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        self.eval_pdf(wo, wi).0
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.eval_pdf(wo, wi).1
    }

    /// The value f (no cosine) and the density of the continuous lobes' mixture toward
    /// `wi`, without branches (every layer computed, a missing one weighing zero), so that
    /// a lane kernel's loop over it vectorises; the one-path code calls it too.
    #[inline(always)]
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let above = wo.z > 0.0 && wi.z > 0.0;
        let (h, has_h) = normalized(wo + wi);
        let oh = wo.dot(h);
        let (spec, visible) = ggx(self.alpha).spec_and_visible_pdf(wo, wi, h);
        let (coat, coat_visible) = ggx(self.coat_alpha).spec_and_visible_pdf(wo, wi, h);
        let diffuse =
            self.diffuse * (Vec3::ONE - self.specular_weight * schlick(self.dielectric_f0, 1.0, oh)) * FRAC_1_PI;
        let base = diffuse + schlick(self.f0, self.f90, oh) * spec;
        let f = base * self.sheen_scaling + self.sheen * self.sheen_f(wo, wi, h);
        let f = f * (1.0 - self.coat_fresnel(wo.z)) + Vec3::splat(self.coat_fresnel(oh) * coat);
        let [pc, ps, pd, _] = self.lobe_probabilities(wo);
        let glossy = if ps > 0.0 { ps * visible } else { 0.0 } + if pc > 0.0 { pc * coat_visible } else { 0.0 };
        let pdf = pd * warp::cosine_hemisphere_pdf(wi.z) + if has_h { glossy } else { 0.0 };
        (if above && has_h { f } else { Vec3::ZERO }, if above { pdf } else { 0.0 })
    }

    /// The lobes' probabilities seen from `wo`: clearcoat, specular, diffuse (and sheen,
    /// sampled with it), transmission; they sum to 1.
    #[inline(always)]
    fn lobe_probabilities(&self, wo: Vec3) -> [f32; 4] {
        let fc = self.coat_fresnel(wo.z);
        let under = (1.0 - fc) * self.sheen_scaling;
        let c = fc * 3.0;
        let s = under * schlick(self.f0, self.f90, wo.z).element_sum();
        let d = under * self.diffuse.element_sum() + (1.0 - fc) * self.sheen.element_sum();
        let t = under * self.transmit.element_sum();
        let sum = c + s + d + t;
        let ok = sum > 0.0 && sum.is_finite();
        let share = |x: f32, otherwise: f32| if ok { x / sum } else { otherwise };
        [share(c, 0.0), share(s, 1.0), share(d, 0.0), share(t, 0.0)]
    }

    /// `u[2]` chooses the lobe, `u[0]` and `u[1]` the direction within it.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: [f32; 3]) -> Option<BsdfSample> {
        let (s, ok) = self.sample_at(wo, u, (TAU * u[1]).sin_cos());
        ok.then_some(s)
    }

    /// [`sample`](Self::sample) with the sine and cosine of `2 pi u[1]` given (a lane kernel
    /// takes them one lane at a time), without branches: every lobe's direction computed and
    /// the chosen one kept, with whether there is a sample.
    #[inline(always)]
    pub fn sample_at(&self, wo: Vec3, u: [f32; 3], sin_cos: (f32, f32)) -> (BsdfSample, bool) {
        let [pc, ps, pd, pt] = self.lobe_probabilities(wo);
        let x = u[2];
        let transmitted = x >= pc + ps + pd && pt > 0.0;
        let (coat_wi, coat_ok) = ggx(self.coat_alpha).sample_visible_at(wo, u[0], sin_cos);
        let (spec_wi, spec_ok) = ggx(self.alpha).sample_visible_at(wo, u[0], sin_cos);
        let (wi, wi_ok) = if x < pc {
            (coat_wi, coat_ok)
        } else if x < pc + ps {
            (spec_wi, spec_ok)
        } else {
            (warp::cosine_hemisphere(u[0], u[1]), true)
        };
        let (f, pdf) = self.eval_pdf(wo, wi);
        let weight = f * (wi.z / pdf);
        let continuous = wi_ok && pdf > 0.0 && pdf.is_finite() && weight.is_finite();
        let (delta, delta_ok) = self.transmission_at(wo, pt);
        let s = if transmitted { delta } else { BsdfSample { wi, weight, pdf, delta: false } };
        (s, wo.z > 0.0 && if transmitted { delta_ok } else { continuous })
    }

    /// The delta transmission lobe, chosen with probability `pt`: what the layers above
    /// and the dielectric's reflection leave, tinted by the base colour; without branches,
    /// with whether it carries light.
    #[inline(always)]
    fn transmission_at(&self, wo: Vec3, pt: f32) -> (BsdfSample, bool) {
        let c = wo.z;
        let left = (1.0 - self.coat_fresnel(c))
            * self.sheen_scaling
            * (Vec3::ONE - self.specular_weight * schlick(self.dielectric_f0, 1.0, c));
        let t = self.transmit * left;
        let sin2_t = (1.0 - c * c).max(0.0) / (self.eta * self.eta);
        let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
        // Radiance is compressed into the narrower cone by 1 / eta^2.
        let refracted = (Vec3::new(-wo.x / self.eta, -wo.y / self.eta, -cos_t), 1.0 / (self.eta * self.eta));
        let (wi, scale) = if self.thin {
            (-wo, 1.0)
        } else if fresnel_dielectric(c, self.eta) >= 1.0 {
            // Total internal reflection: the light stays on this side.
            (reflect(wo), 1.0)
        } else {
            refracted
        };
        let weight = t * (scale / pt);
        (BsdfSample { wi, weight, pdf: pt, delta: true }, weight.is_finite() && t != Vec3::ZERO)
    }
}

/// The sheen lobe's directional albedo E(cos_o) = integral of D V cos_i over the
/// hemisphere, for sheen roughness `roughness` (white sheen), at [`SHEEN_TABLE`] cosines
/// (midpoint quadrature in cos_i and phi): what the base under the sheen loses.
pub fn sheen_albedo_table(roughness: f32) -> [f32; SHEEN_TABLE] {
    let l = Layers { sheen_color: Vec3::ONE, sheen_roughness: roughness, ..Layers::default() };
    let m = Layered::new(Vec3::ZERO, 0.0, 1.0, 0.0, &l);
    let (nc, np) = (128, 64);
    let mut table = [0.0; SHEEN_TABLE];
    for (k, e) in table.iter_mut().enumerate() {
        let cos_o = (k as f32 / (SHEEN_TABLE - 1) as f32).max(1e-3);
        let wo = Vec3::new((1.0 - cos_o * cos_o).sqrt(), 0.0, cos_o);
        let mut sum = 0.0f64;
        for i in 0..nc {
            let ci = (i as f32 + 0.5) / nc as f32;
            let si = (1.0 - ci * ci).sqrt();
            for j in 0..np {
                let phi = TAU * (j as f32 + 0.5) / np as f32;
                let wi = Vec3::new(si * phi.cos(), si * phi.sin(), ci);
                let Some(h) = (wo + wi).try_normalize() else { continue };
                sum += (m.sheen_f(wo, wi, h) * ci) as f64;
            }
        }
        *e = (sum * (TAU as f64 / (nc * np) as f64)).min(1.0) as f32;
    }
    table
}

/// `table` at cosine `cos` (linear interpolation).
#[inline]
fn lookup(table: &[f32; SHEEN_TABLE], cos: f32) -> f32 {
    let x = cos.clamp(0.0, 1.0) * (SHEEN_TABLE - 1) as f32;
    let i = (x as usize).min(SHEEN_TABLE - 2);
    let t = x - i as f32;
    table[i] * (1.0 - t) + table[i + 1] * t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn charlie_distribution_is_normalised() {
        // The integral of D(h) cos(h) over the hemisphere is 1.
        for r in [0.3f32, 0.6, 1.0] {
            let l = Layers { sheen_color: Vec3::ONE, sheen_roughness: r, ..Layers::default() };
            let m = Layered::new(Vec3::ZERO, 0.0, 1.0, 0.0, &l);
            let n = 200_000;
            let s: f64 = (0..n)
                .map(|i| {
                    let c = (i as f64 + 0.5) / n as f64;
                    let h = Vec3::new((1.0 - c * c).sqrt() as f32, 0.0, c as f32);
                    m.charlie(h) as f64 * c * TAU as f64 / n as f64
                })
                .sum();
            assert!((s - 1.0).abs() < 2e-3, "roughness {r}: {s}");
        }
    }
}
