//! The per-sample math of direct light from every light but the area lights and emissive
//! triangles (which have [`super::area`]): the light from infinity, point, spot and
//! directional lights, and the light from infinity a BSDF sample finds. Written once, without branches, for the one-vertex code and the lane
//! kernels: the lane kernels draw each lane's sample (a table lookup, a normalisation) and
//! then call these functions on every lane in fixed loops that the compiler vectorises, so
//! both give the same bits.

use super::area::{LightRay, ShadingPoint};
use crate::bsdf::power_heuristic;
use crate::geometry::Ray;
use crate::geometry::offset::{offset_origin, shadow_tmax_at};
use crate::lights::{LightSample, Sky};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// One light sample as a lane holds it: the direction, radiance over density, the density
/// (for MIS; unused without it), the light point for a light at a finite distance, and
/// whether the light gave a sample at all.
#[derive(Clone, Copy, Debug)]
pub struct LightPoint {
    pub wi: Vec3,
    pub weight: Vec3,
    pub pdf: f32,
    pub target: Vec3,
    pub finite: bool,
    pub valid: bool,
}

impl LightPoint {
    /// No sample: every ray made from it is invalid.
    pub const NONE: LightPoint =
        LightPoint { wi: Vec3::Z, weight: Vec3::ZERO, pdf: 0.0, target: Vec3::ZERO, finite: false, valid: false };

    /// A sample of `SampledLight::sample_pdf` (or of `sample`, with any density).
    #[inline(always)]
    pub fn of(s: Option<(LightSample, f32)>) -> LightPoint {
        match s {
            None => LightPoint::NONE,
            Some((ls, pdf)) => LightPoint {
                wi: ls.wi,
                weight: ls.weight,
                pdf,
                target: ls.target.unwrap_or(Vec3::ZERO),
                finite: ls.target.is_some(),
                valid: true,
            },
        }
    }
}

/// The shadow ray from `origin` (already offset) along `wi` or, for a light point (`finite`),
/// aimed from `origin` at `target` and stopped short of it by the light's `margin`; whether
/// it reaches.
#[inline(always)]
pub fn shadow_ray_to(origin: Vec3, wi: Vec3, target: Vec3, finite: bool, margin: f32) -> (Ray, bool) {
    let e = target - origin;
    let len = e.length();
    let rcp = 1.0 / len;
    let dir = e * rcp;
    let tmax = shadow_tmax_at(len, margin);
    let reach = rcp.is_finite() & (rcp > 0.0) & (tmax > 0.0);
    if finite {
        (Ray { origin, dir, tmin: 0.0, tmax }, reach)
    } else {
        (Ray { origin, dir: wi, tmin: 0.0, tmax: f32::INFINITY }, true)
    }
}

/// The shadow ray of light sample `l` at the diffuse point `s` and its weight: `inv` is the
/// BSDF over the sample count `ns`, `mis` weighs it against the cosine-sampled continuation
/// (power heuristic), `consistent` is [`super::Vertex::consistent`] of `l.wi`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn diffuse_light_ray(
    s: &ShadingPoint,
    l: &LightPoint,
    inv: Vec3,
    margin: f32,
    ns: u32,
    mis: bool,
    consistent: bool,
) -> LightRay {
    let w = if mis { power_heuristic(ns as f32 * l.pdf, l.wi.dot(s.ns).max(0.0) * FRAC_1_PI) } else { 1.0 };
    let cos = l.wi.dot(s.ns);
    let origin = offset_origin(s.p, s.p_error, s.ng, l.wi);
    let (ray, reach) = shadow_ray_to(origin, l.wi, l.target, l.finite, margin);
    let valid = l.valid & (cos > 0.0) & (w > 0.0) & consistent & reach;
    LightRay { ray, weight: inv * l.weight * (cos * w), valid }
}

/// The shadow ray of light sample `l` at the glossy point `s` and its weight, the BSDF's
/// value `f` and density `pdf_b` toward `local` (`l.wi` in the shading frame) given, weighed
/// by MIS against the BSDF's sample (the light strategy counted `ns` times).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn glossy_light_ray(
    s: &ShadingPoint,
    l: &LightPoint,
    local: Vec3,
    f: Vec3,
    pdf_b: f32,
    margin: f32,
    ns: u32,
    consistent: bool,
) -> LightRay {
    let w = power_heuristic(ns as f32 * l.pdf, pdf_b);
    let origin = offset_origin(s.p, s.p_error, s.ng, l.wi);
    let (ray, reach) = shadow_ray_to(origin, l.wi, l.target, l.finite, margin);
    let valid = l.valid & (f != Vec3::ZERO) & (w > 0.0) & consistent & reach;
    LightRay { ray, weight: f * l.weight * (local.z * w / ns as f32), valid }
}

/// What a BSDF sample from a point with shading normal `n` and density `pdf_b` finds along
/// `dir` at infinity (light `sky`), weighed by the power heuristic against that light's `ns`
/// samples; the map's radiance and density toward `dir` given as in
/// [`Sky::radiance_with`]. As `Transport::arrival` sums it over the lights, of which this is
/// the only one a ray that escaped finds when no area light is in its way.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn found_at_infinity(
    sky: Sky,
    ns: f32,
    n: Vec3,
    pdf_b: f32,
    dir: Vec3,
    mapped: Vec3,
    mapped_pdf: f32,
    has_map: bool,
) -> Vec3 {
    let le = sky.radiance_with(dir, mapped, has_map);
    let pdf_l = sky.pdf_with(n, dir, mapped_pdf, has_map);
    Vec3::ZERO + le * power_heuristic(pdf_b, ns * pdf_l)
}
