use super::dielectric::fresnel_dielectric;
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
#[inline]
fn schlick(f0: Vec3, f90: f32, cos: f32) -> Vec3 {
    let m = 1.0 - cos.clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (Vec3::splat(f90) - f0) * (m2 * m2 * m)
}

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

    /// The Charlie sheen distribution (Estevez and Kulla 2017).
    #[inline]
    fn charlie(&self, h: Vec3) -> f32 {
        let inv = 1.0 / self.sheen_alpha;
        let sin2 = (1.0 - h.z * h.z).max(0.0);
        (2.0 + inv) * sin2.powf(0.5 * inv) / TAU
    }

    /// The sheen lobe, f (no cosine): D V with Neubelt and Pettineo's visibility.
    #[inline]
    fn sheen_f(&self, wo: Vec3, wi: Vec3, h: Vec3) -> f32 {
        let v = 1.0 / (4.0 * (wi.z + wo.z - wi.z * wo.z));
        let f = self.charlie(h) * v;
        if f.is_finite() { f } else { 0.0 }
    }

    /// The clearcoat's Fresnel weight at cosine `c`.
    #[inline]
    fn coat_fresnel(&self, c: f32) -> f32 {
        self.clearcoat * schlick(Vec3::splat(0.04), 1.0, c).x
    }

    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let Some(h) = (wo + wi).try_normalize() else { return Vec3::ZERO };
        let oh = wo.dot(h);
        let geometric = 4.0 * wo.z * wi.z;
        let lobe = ggx(self.alpha);
        let spec = lobe.d(h) * lobe.g(wo, wi) / geometric;
        let spec = if spec.is_finite() { spec } else { 0.0 };
        let diffuse =
            self.diffuse * (Vec3::ONE - self.specular_weight * schlick(self.dielectric_f0, 1.0, oh)) * FRAC_1_PI;
        let base = diffuse + schlick(self.f0, self.f90, oh) * spec;
        let mut f = base * self.sheen_scaling;
        if self.sheen != Vec3::ZERO {
            f += self.sheen * self.sheen_f(wo, wi, h);
        }
        if self.clearcoat > 0.0 {
            let coat = ggx(self.coat_alpha);
            let c = coat.d(h) * coat.g(wo, wi) / geometric;
            let c = if c.is_finite() { self.coat_fresnel(oh) * c } else { 0.0 };
            f = f * (1.0 - self.coat_fresnel(wo.z)) + Vec3::splat(c);
        }
        f
    }

    /// The lobes' probabilities seen from `wo`: clearcoat, specular, diffuse (and sheen,
    /// sampled with it), transmission; they sum to 1.
    #[inline]
    fn lobe_probabilities(&self, wo: Vec3) -> [f32; 4] {
        let fc = self.coat_fresnel(wo.z);
        let under = (1.0 - fc) * self.sheen_scaling;
        let c = fc * 3.0;
        let s = under * schlick(self.f0, self.f90, wo.z).element_sum();
        let d = under * self.diffuse.element_sum() + (1.0 - fc) * self.sheen.element_sum();
        let t = under * self.transmit.element_sum();
        let sum = c + s + d + t;
        if !(sum > 0.0 && sum.is_finite()) {
            return [0.0, 1.0, 0.0, 0.0];
        }
        [c / sum, s / sum, d / sum, t / sum]
    }

    /// `u[2]` chooses the lobe, `u[0]` and `u[1]` the direction within it.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: [f32; 3]) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let [pc, ps, pd, pt] = self.lobe_probabilities(wo);
        let x = u[2];
        if x >= pc + ps + pd && pt > 0.0 {
            return self.sample_transmission(wo, pt);
        }
        let wi = if x < pc {
            ggx(self.coat_alpha).sample_visible(wo, [u[0], u[1]])?
        } else if x < pc + ps {
            ggx(self.alpha).sample_visible(wo, [u[0], u[1]])?
        } else {
            warp::cosine_hemisphere(u[0], u[1])
        };
        BsdfSample::continuous(wi, self.pdf(wo, wi), || self.eval(wo, wi))
    }

    /// The delta transmission lobe, chosen with probability `pt`: what the layers above
    /// and the dielectric's reflection leave, tinted by the base colour.
    #[inline]
    fn sample_transmission(&self, wo: Vec3, pt: f32) -> Option<BsdfSample> {
        let c = wo.z;
        let left = (1.0 - self.coat_fresnel(c))
            * self.sheen_scaling
            * (Vec3::ONE - self.specular_weight * schlick(self.dielectric_f0, 1.0, c));
        let t = self.transmit * left;
        let (wi, scale) = if self.thin {
            (-wo, 1.0)
        } else if fresnel_dielectric(c, self.eta) >= 1.0 {
            // Total internal reflection: the light stays on this side.
            (reflect(wo), 1.0)
        } else {
            let sin2_t = (1.0 - c * c).max(0.0) / (self.eta * self.eta);
            let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
            // Radiance is compressed into the narrower cone by 1 / eta^2.
            (Vec3::new(-wo.x / self.eta, -wo.y / self.eta, -cos_t), 1.0 / (self.eta * self.eta))
        };
        let weight = t * (scale / pt);
        (weight.is_finite() && t != Vec3::ZERO).then_some(BsdfSample { wi, weight, pdf: pt, delta: true })
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let [pc, ps, pd, _] = self.lobe_probabilities(wo);
        let mut p = pd * warp::cosine_hemisphere_pdf(wi.z);
        if ps > 0.0 {
            p += ps * ggx(self.alpha).visible_pdf(wo, wi);
        }
        if pc > 0.0 {
            p += pc * ggx(self.coat_alpha).visible_pdf(wo, wi);
        }
        p
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
