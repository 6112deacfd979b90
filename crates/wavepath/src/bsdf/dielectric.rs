use super::BsdfSample;
use super::mirror::reflect;
use glam::Vec3;

/// A smooth dielectric interface (glass). `eta` is the relative index of refraction, the
/// side `wi` refracts into over the side `wo` is on ([`super::Model::oriented`] inverts it
/// for hits from inside). With `reflect`, reflection and refraction are chosen with the
/// exact Fresnel probability (total internal reflection always reflects); without it
/// (`Bsdf::Refraction`) the surface only transmits and total internal reflection ends the
/// path, as the CS184 refraction BSDF does.
///
/// Transmitted radiance is scaled by 1 / eta^2 (radiance is compressed into a narrower
/// cone); a path that enters and leaves a medium gets eta^2 back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    pub reflectance: Vec3,
    pub transmittance: Vec3,
    pub eta: f32,
    pub reflect: bool,
}

/// Unpolarised Fresnel reflectance of a dielectric interface for an incident cosine
/// `cos_i` in [0, 1] and relative index `eta` (transmitted over incident); 1 under total
/// internal reflection.
#[inline(always)]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    // Every case computed and the valid one kept (no branch: the lane kernels' loops over it
    // vectorise); `cos_t`'s clamp changes nothing where it is used.
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let f = (0.5 * (rs * rs + rp * rp)).clamp(0.0, 1.0);
    if sin2_t >= 1.0 || eta <= 0.0 { 1.0 } else { f }
}

impl Dielectric {
    /// `u` chooses reflection (u < F) or refraction.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: f32) -> Option<BsdfSample> {
        let (s, ok) = self.sample_at(wo, u);
        ok.then_some(s)
    }

    /// [`sample`](Self::sample) without a branch (both lobes computed, the chosen one kept),
    /// for the lane kernels' loops: the sample and whether there is one.
    #[inline(always)]
    pub fn sample_at(&self, wo: Vec3, u: f32) -> (BsdfSample, bool) {
        let cos_i = wo.z;
        let usable = cos_i > 0.0 && self.eta > 0.0;
        let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (self.eta * self.eta);
        let tir = sin2_t >= 1.0;
        let f = fresnel_dielectric(cos_i, self.eta);
        // Without `reflect` the surface only transmits, and total internal reflection ends
        // the path.
        let reflects = self.reflect & (tir | (u < f));
        let refracted = self.refracted(wo, sin2_t);
        let transmitted = self.transmittance / (self.eta * self.eta);
        let wi = if reflects { reflect(wo) } else { refracted };
        let weight = if reflects { self.reflectance } else { transmitted };
        let pdf = if !self.reflect {
            1.0
        } else if reflects {
            f
        } else {
            1.0 - f
        };
        (BsdfSample { wi, weight, pdf, delta: true }, usable & (self.reflect | !tir))
    }

    #[inline(always)]
    fn refracted(&self, wo: Vec3, sin2_t: f32) -> Vec3 {
        let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
        Vec3::new(-wo.x / self.eta, -wo.y / self.eta, -cos_t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_known_values() {
        // Normal incidence: ((1 - n) / (1 + n))^2 = 0.04 for n = 1.5, from either side.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
        // Brewster's angle: tan(theta) = n, p-polarisation vanishes: F = rs^2 / 2.
        let th = 1.5f32.atan();
        let (ci, ct) = (th.cos(), (1.0 - th.sin().powi(2) / 2.25).sqrt());
        let rs = (ci - 1.5 * ct) / (ci + 1.5 * ct);
        assert!((fresnel_dielectric(ci, 1.5) - 0.5 * rs * rs).abs() < 1e-6);
        // Grazing: everything reflects; beyond the critical angle inside: total reflection.
        assert_eq!(fresnel_dielectric(0.0, 1.5), 1.0);
        assert_eq!(fresnel_dielectric(0.5, 1.0 / 1.5), 1.0);
    }

    #[test]
    fn refraction_obeys_snell_and_total_internal_reflection_reflects() {
        let g = Dielectric { reflectance: Vec3::ONE, transmittance: Vec3::ONE, eta: 1.5, reflect: true };
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let s = g.sample(wo, 0.99).unwrap();
        assert!(s.wi.z < 0.0 && (s.wi.length() - 1.0).abs() < 1e-5);
        let sin_t = (1.0 - s.wi.z * s.wi.z).sqrt();
        assert!((0.6 - 1.5 * sin_t).abs() < 1e-5, "Snell: sin_i = eta sin_t");
        assert!((s.weight - Vec3::splat(1.0 / 2.25)).length() < 1e-6);
        // From inside at sin 0.8 > 1 / 1.5: beyond the critical angle.
        let inside = Dielectric { eta: 1.0 / 1.5, ..g };
        let wo = Vec3::new(0.8, 0.0, 0.6);
        for u in [0.0, 0.5, 0.999] {
            let s = inside.sample(wo, u).unwrap();
            assert_eq!(s.wi, Vec3::new(-0.8, 0.0, 0.6));
        }
        assert!(Dielectric { reflect: false, ..inside }.sample(wo, 0.5).is_none());
    }
}
