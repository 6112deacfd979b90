use super::BsdfSample;
use super::branch_free::exp;
use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// The microfacet normal distribution: Beckmann (what the CS184 scenes specify) or GGX.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Distribution {
    Beckmann,
    Ggx,
}

/// A rough conductor (Cook–Torrance): f = F(wi.h) D(h) G(wo, wi) / (4 cos_o cos_i), with
/// the exact conductor Fresnel term per RGB channel from the file's `eta` and `k`, and the
/// height-correlated Smith shadowing G = 1 / (1 + Lambda(wo) + Lambda(wi)). Sampling draws
/// the half vector from D(h) cos(h) (the reference's strategy), so the sample weight is
/// F G (wo.h) / (cos_o cos_h): bounded even as alpha goes to 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub alpha: f32,
    pub eta: Vec3,
    pub k: Vec3,
    pub distribution: Distribution,
}

/// Smallest roughness used: below it D overflows f32 in its peak.
const MIN_ALPHA: f32 = 1e-4;

/// Fresnel reflectance of a conductor with complex index eta + i k for incident cosine
/// `cos_i` (pbrt's FrConductor, after Lengyel): 1 for a perfect conductor (eta = 0, k > 0).
#[inline(always)]
pub fn fresnel_conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c = cos_i.clamp(0.0, 1.0);
    let (c2, s2) = (c * c, 1.0 - c * c);
    let (e2, k2) = (eta * eta, k * k);
    let t0 = e2 - k2 - s2;
    let a2b2 = (t0 * t0 + 4.0 * e2 * k2).sqrt();
    let t1 = a2b2 + c2;
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let t2 = 2.0 * c * a;
    let rs = (t1 - t2) / (t1 + t2).max(1e-12);
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4).max(1e-12);
    (0.5 * (rp + rs)).clamp(0.0, 1.0)
}

/// `v` normalised as `Vec3::try_normalize` does it (the same operations), without a branch:
/// the unit vector and whether there is one.
#[inline(always)]
pub fn normalized(v: Vec3) -> (Vec3, bool) {
    let rcp = v.length_recip();
    (v * rcp, rcp.is_finite() && rcp > 0.0)
}

impl Microfacet {
    #[inline(always)]
    fn a(&self) -> f32 {
        self.alpha.max(MIN_ALPHA)
    }

    /// Normal distribution D(h) (per unit projected area: its integral of D cos is 1).
    /// Branch-free (every case computed, the valid one kept), so that the lane kernels'
    /// loops over it vectorise; the same values as the early-return form.
    #[inline(always)]
    pub fn d(&self, h: Vec3) -> f32 {
        let c2 = h.z * h.z;
        let a2 = self.a() * self.a();
        let tan2 = (1.0 - c2).max(0.0) / c2;
        let v = match self.distribution {
            Distribution::Beckmann => exp(-tan2 / a2) / (PI * a2 * c2 * c2),
            Distribution::Ggx => {
                let t = a2 + tan2;
                a2 / (PI * c2 * c2 * t * t)
            }
        };
        if h.z > 0.0 && c2 > 0.0 && v.is_finite() { v } else { 0.0 }
    }

    /// Smith's Lambda for direction `w` (Beckmann: Walter's rational approximation);
    /// branch-free as [`d`](Self::d) is.
    #[inline(always)]
    fn lambda(&self, w: Vec3) -> f32 {
        let c = w.z.abs();
        let tan = (1.0 - c * c).max(0.0).sqrt() / c;
        let v = match self.distribution {
            Distribution::Beckmann => {
                let x = 1.0 / (self.a() * tan);
                if x >= 1.6 { 0.0 } else { (1.0 - 1.259 * x + 0.396 * x * x) / (3.535 * x + 2.181 * x * x) }
            }
            Distribution::Ggx => {
                let at = self.a() * tan;
                0.5 * (-1.0 + (1.0 + at * at).sqrt())
            }
        };
        if c >= 1.0 {
            0.0
        } else if !tan.is_finite() {
            f32::INFINITY
        } else {
            v
        }
    }

    /// Smith's masking of direction `w` alone, G1 = 1 / (1 + Lambda(w)).
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        let v = 1.0 / (1.0 + self.lambda(w));
        if v.is_finite() { v } else { 0.0 }
    }

    /// Height-correlated Smith shadowing-masking.
    #[inline(always)]
    pub fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        let v = 1.0 / (1.0 + self.lambda(wo) + self.lambda(wi));
        if v.is_finite() { v } else { 0.0 }
    }

    #[inline(always)]
    fn fresnel(&self, cos: f32) -> Vec3 {
        Vec3::new(
            fresnel_conductor(cos, self.eta.x, self.k.x),
            fresnel_conductor(cos, self.eta.y, self.k.y),
            fresnel_conductor(cos, self.eta.z, self.k.z),
        )
    }

    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        self.eval_pdf(wo, wi).0
    }

    /// [`eval`](Self::eval) and [`pdf`](Self::pdf) of one direction, without branches (for
    /// the lane kernels' loops; every case computed and the valid one kept): D(h) once.
    #[inline(always)]
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let above = wo.z > 0.0 && wi.z > 0.0;
        let (h, h_ok) = normalized(wo + wi);
        let d = self.d(h);
        let v = d * self.g(wo, wi) / (4.0 * wo.z * wi.z);
        let f = self.fresnel(wi.dot(h)) * v;
        let oh = wo.dot(h);
        let p = d * h.z / (4.0 * oh);
        let usable = above && h_ok;
        let f = if usable && v.is_finite() { f } else { Vec3::ZERO };
        (f, if usable && oh > 0.0 && p.is_finite() { p } else { 0.0 })
    }

    /// The library calls [`sample_at`](Self::sample_at) needs for the numbers `u`, made
    /// apart (a lane kernel makes them one lane at a time): the sine and cosine of the
    /// azimuth `2 pi u[1]` and, for Beckmann, ln(1 - u[0]).
    #[inline(always)]
    pub fn sample_calls(&self, u: [f32; 2]) -> [f32; 3] {
        let (sin, cos) = (TAU * u[1]).sin_cos();
        let ln = match self.distribution {
            Distribution::Beckmann => (1.0 - u[0].min(1.0 - f32::EPSILON)).ln(),
            Distribution::Ggx => 0.0,
        };
        [sin, cos, ln]
    }

    /// The half vector drawn from D(h) cos(h), then `wo` reflected about it.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: [f32; 2]) -> Option<BsdfSample> {
        let (s, ok) = self.sample_at(wo, u, self.sample_calls(u));
        ok.then_some(s)
    }

    /// [`sample`](Self::sample) from `u` and its [`sample_calls`](Self::sample_calls),
    /// without branches: the sample and whether there is one.
    #[inline(always)]
    pub fn sample_at(&self, wo: Vec3, u: [f32; 2], [sin_phi, cos_phi, ln]: [f32; 3]) -> (BsdfSample, bool) {
        let a2 = self.a() * self.a();
        let u0 = u[0].min(1.0 - f32::EPSILON);
        let tan2 = match self.distribution {
            Distribution::Beckmann => -a2 * ln,
            Distribution::Ggx => a2 * u0 / (1.0 - u0),
        };
        let cos = 1.0 / (1.0 + tan2).sqrt();
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let h = Vec3::new(sin * cos_phi, sin * sin_phi, cos);
        let oh = wo.dot(h);
        let wi = 2.0 * oh * h - wo;
        let pdf = self.d(h) * h.z / (4.0 * oh);
        let weight = self.fresnel(oh) * (self.g(wo, wi) * oh / (wo.z * h.z));
        let drawn = wo.z > 0.0 && oh > 0.0 && cos > 0.0 && wi.z > 0.0;
        let ok = drawn && pdf > 0.0 && pdf.is_finite() && weight.is_finite();
        (BsdfSample { wi, weight, pdf, delta: false }, ok)
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.eval_pdf(wo, wi).1
    }

    /// GGX only: `wo` reflected about a normal drawn from those visible from `wo` (Heitz
    /// 2018, the stretched hemisphere construction). Its sample weight F G / G1(wo) stays
    /// below F at grazing angles, where drawing from D alone gives weights of order 1 / alpha.
    #[inline]
    pub fn sample_visible(&self, wo: Vec3, u: [f32; 2]) -> Option<Vec3> {
        let (wi, ok) = self.sample_visible_at(wo, u[0], (std::f32::consts::TAU * u[1]).sin_cos());
        ok.then_some(wi)
    }

    /// [`sample_visible`](Self::sample_visible) from `u[0]` and the sine and cosine of the
    /// disk angle `2 pi u[1]` (computed apart: a lane kernel takes them one lane at a time),
    /// without branches: the direction and whether it is one.
    #[inline(always)]
    pub fn sample_visible_at(&self, wo: Vec3, u0: f32, (sin, cos): (f32, f32)) -> (Vec3, bool) {
        let a = self.a();
        let (vh, vh_ok) = normalized(Vec3::new(a * wo.x, a * wo.y, wo.z));
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt() } else { Vec3::X };
        let t2 = vh.cross(t1);
        let r = u0.sqrt();
        let (p1, p2) = (r * cos, r * sin);
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        let (h, h_ok) = normalized(Vec3::new(a * nh.x, a * nh.y, nh.z.max(1e-6)));
        let oh = wo.dot(h);
        let wi = 2.0 * oh * h - wo;
        (wi, vh_ok && h_ok && oh > 0.0 && wi.z > 0.0)
    }

    /// The specular term D(h) G(wo, wi) / (4 cos_o cos_i) (0 where not finite) and the
    /// density of [`sample_visible`](Self::sample_visible) for the half vector `h` of `wo`
    /// and `wi` (both above the surface): what [`visible_pdf`](Self::visible_pdf) and a
    /// model's `eval` compute apart, with D(h) and Lambda(wo) computed once — the same
    /// operations, so the same bits.
    #[inline(always)]
    pub fn spec_and_visible_pdf(&self, wo: Vec3, wi: Vec3, h: Vec3) -> (f32, f32) {
        let d = self.d(h);
        let lo = self.lambda(wo);
        let g = 1.0 / (1.0 + lo + self.lambda(wi));
        let g = if g.is_finite() { g } else { 0.0 };
        let spec = d * g / (4.0 * wo.z * wi.z);
        let spec = if spec.is_finite() { spec } else { 0.0 };
        let g1 = 1.0 / (1.0 + lo);
        let g1 = if g1.is_finite() { g1 } else { 0.0 };
        let p = g1 * d / (4.0 * wo.z);
        (spec, if wo.dot(h) > 0.0 && p.is_finite() { p } else { 0.0 })
    }

    /// Density of [`sample_visible`](Self::sample_visible): G1(wo) D(h) / (4 cos_o).
    #[inline]
    pub fn visible_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some(h) = (wo + wi).try_normalize() else { return 0.0 };
        if wo.dot(h) <= 0.0 {
            return 0.0;
        }
        let p = self.g1(wo) * self.d(h) / (4.0 * wo.z);
        if p.is_finite() { p } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conductor_fresnel_limits() {
        // A perfect conductor reflects everything at every angle.
        for c in [0.0, 0.1, 0.5, 1.0] {
            assert!((fresnel_conductor(c, 0.0, 1.0) - 1.0).abs() < 1e-6);
        }
        // k = 0 is a dielectric: normal incidence ((n - 1) / (n + 1))^2.
        assert!((fresnel_conductor(1.0, 1.5, 0.0) - 0.04).abs() < 1e-6);
        // Normal incidence of a conductor: ((n-1)^2 + k^2) / ((n+1)^2 + k^2).
        let (n, k) = (0.2, 3.0);
        let expect = ((n - 1.0f32).powi(2) + k * k) / ((n + 1.0f32).powi(2) + k * k);
        assert!((fresnel_conductor(1.0, n, k) - expect).abs() < 1e-5);
        assert!((fresnel_conductor(0.0, n, k) - 1.0).abs() < 1e-5);
    }

    /// Beckmann's conductor: `sample`'s density is `pdf`'s of the direction drawn, its weight
    /// `eval` cos / pdf, and `eval_pdf` is `eval` and `pdf` bit for bit.
    #[test]
    fn beckmann_sample_matches_eval_and_pdf() {
        let m = Microfacet {
            alpha: 0.3,
            eta: Vec3::new(0.2, 0.9, 1.1),
            k: Vec3::new(3.9, 2.4, 2.2),
            distribution: Distribution::Beckmann,
        };
        let wo = Vec3::new(0.5, -0.2, 0.7).normalize();
        let mut n = 0;
        for i in 0..64 {
            for j in 0..64 {
                let u = [(i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0];
                let Some(s) = m.sample(wo, u) else { continue };
                n += 1;
                let (f, pdf) = m.eval_pdf(wo, s.wi);
                assert_eq!((f, pdf), (m.eval(wo, s.wi), m.pdf(wo, s.wi)));
                assert!((pdf - s.pdf).abs() <= 1e-4 * s.pdf, "{pdf} vs {}", s.pdf);
                let w = f * s.wi.z / pdf;
                assert!((w - s.weight).abs().max_element() <= 1e-4 * s.weight.max_element().max(1e-3));
            }
        }
        assert!(n > 3000, "{n} samples of 4096");
    }

    #[test]
    fn distributions_are_normalised() {
        // The integral of D(h) cos(h) over the hemisphere is 1 (midpoint rule in cos).
        for distribution in [Distribution::Beckmann, Distribution::Ggx] {
            for alpha in [0.05f32, 0.25, 0.7] {
                let m = Microfacet { alpha, eta: Vec3::ZERO, k: Vec3::ONE, distribution };
                let n = 200_000;
                let mut s = 0.0f64;
                for i in 0..n {
                    let c = (i as f64 + 0.5) / n as f64;
                    let h = Vec3::new((1.0 - c * c).sqrt() as f32, 0.0, c as f32);
                    s += m.d(h) as f64 * c * TAU as f64 / n as f64;
                }
                assert!((s - 1.0).abs() < 2e-3, "{distribution:?} alpha {alpha}: {s}");
            }
        }
    }
}
