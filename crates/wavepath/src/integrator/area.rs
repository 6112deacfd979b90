//! The per-sample math of direct light from an area light or an emissive triangle (and of
//! the continuation ray),
//! written once, branch-free, for both the one-vertex-at-a-time code and the wavefront's
//! lane kernel: the lane kernel calls these same functions on each of 8 lanes in a
//! fixed-size loop that the compiler vectorises, so both give the same bits.

use crate::bsdf::power_heuristic;
use crate::geometry::Ray;
use crate::geometry::offset::{offset_origin, shadow_tmax_at};
use crate::lights::{Emitter, area_to_solid_angle_lanes};
use crate::sampling::{Frame, warp};
use glam::Vec3;

/// What the shading point of a vertex contributes to its shadow rays.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint {
    pub p: Vec3,
    pub p_error: Vec3,
    pub ng: Vec3,
    pub ns: Vec3,
}

/// An area light as its samples need it.
#[derive(Clone, Copy, Debug)]
pub struct AreaLight {
    pub position: Vec3,
    pub normal: Vec3,
    pub dim_x: Vec3,
    pub dim_y: Vec3,
    pub area: f32,
    /// [`shadow_margin`](crate::geometry::offset::shadow_margin) of the light's points.
    pub margin: f32,
}

/// A shadow ray toward a light point and its geometric factor
/// `cos_surface * cos_light * area / dist^2` (the light's radiance, the BSDF and the sample
/// count not applied); `valid` false when the sample contributes nothing (the light faces
/// away, the point is below the surface, or the points coincide).
#[derive(Clone, Copy, Debug)]
pub struct AreaRay {
    pub ray: Ray,
    pub g: f32,
    pub valid: bool,
}

/// The shadow ray from `s` toward the point of `l` at `(a, b)` in [0, 1)^2. The geometric
/// factor is taken at the shading point itself (an offset origin can be a sizeable fraction
/// of the distance far from the origin of the scene's coordinates) and needs no square
/// root: `cos_s cos_l / dist^2 = (d.ns)(-d.nl) / dist^4`. The ray is aimed from the offset
/// origin (one square root and one division for its direction and its length).
#[inline(always)]
pub fn area_ray(s: &ShadingPoint, l: &AreaLight, a: f32, b: f32) -> AreaRay {
    let q = l.position + (a - 0.5) * l.dim_x + (b - 0.5) * l.dim_y;
    let d = q - s.p;
    let dist2 = d.dot(d);
    let inv_d2 = 1.0 / dist2;
    let cos_l = -d.dot(l.normal);
    let cos = d.dot(s.ns);
    let g = l.area * (cos_l * inv_d2) * (cos * inv_d2);
    // The offset only needs the side `q` is on.
    let origin = offset_origin(s.p, s.p_error, s.ng, d);
    let e = q - origin;
    let len = e.dot(e).sqrt();
    let dir = e * (1.0 / len);
    let tmax = shadow_tmax_at(len, l.margin);
    // Distinct finite points, the one-sided light faces the point, the point faces the light.
    let valid = (dist2 > 0.0) & (dist2 < f32::INFINITY) & (cos_l > 0.0) & (cos > 0.0) & (tmax > 0.0);
    AreaRay { ray: Ray { origin, dir, tmin: 0.0, tmax }, g, valid }
}

/// An area-light sample's geometric factor `g`, times its MIS weight against the vertex's
/// cosine-sampled continuation when `mis` (power heuristic, the light strategy counted `ns`
/// times). The light's solid-angle density is `cos_s / g` and the BSDF's `cos_s / pi`, so the
/// cosines cancel: `w = 1 / (1 + (g / (pi ns))^2)`. One function for the scalar and the lane
/// kernels, so that both compute the same bits.
#[inline(always)]
pub fn mis_weighted(g: f32, ns: u32, mis: bool) -> f32 {
    if !mis {
        return g;
    }
    let r = g * (std::f32::consts::FRAC_1_PI / ns as f32);
    g / (1.0 + r * r)
}

/// The cosine-weighted continuation ray about `s.ns` from `(a, b)` in [0, 1)^2.
#[inline(always)]
pub fn cosine_ray(s: &ShadingPoint, a: f32, b: f32) -> Ray {
    let wi = Frame::new(s.ns).to_world(warp::cosine_hemisphere(a, b));
    let origin = offset_origin(s.p, s.p_error, s.ng, wi);
    Ray { origin, dir: wi, tmin: 0.0, tmax: f32::INFINITY }
}

/// A light sample's shadow ray and its weight (radiance over density, times the BSDF over the
/// sample count, the cosine at the shading point and the MIS weight).
#[derive(Clone, Copy, Debug)]
pub struct LightRay {
    pub ray: Ray,
    pub weight: Vec3,
    pub valid: bool,
}

/// The shadow ray from `s` toward the point `q` of emissive triangle `tri`, which emits `le`
/// toward it, weighted by MIS against the cosine-sampled continuation when `mis` (the light
/// strategy counted `ns` times); `margin` is the light's shadow margin, `inv` the BSDF over
/// the sample count. Exactly the operations of the one-vertex code's sample of an emissive
/// light (`Transport::direct_light`), without branches.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn triangle_ray(
    s: &ShadingPoint,
    tri: &Emitter,
    q: Vec3,
    le: Vec3,
    inv: Vec3,
    margin: f32,
    ns: u32,
    mis: bool,
) -> LightRay {
    let (wi, inv_pdf, ok) = area_to_solid_angle_lanes(s.p, q, tri.n, tri.inv_density, tri.one_sided);
    let pdf_l = 1.0 / inv_pdf;
    let w =
        if mis { power_heuristic(ns as f32 * pdf_l, wi.dot(s.ns).max(0.0) * std::f32::consts::FRAC_1_PI) } else { 1.0 };
    let cos = wi.dot(s.ns);
    let origin = offset_origin(s.p, s.p_error, s.ng, wi);
    let e = q - origin;
    let len = e.length();
    let rcp = 1.0 / len;
    let dir = e * rcp;
    let tmax = shadow_tmax_at(len, margin);
    let valid = ok & tri.valid & (cos > 0.0) & (w > 0.0) & rcp.is_finite() & (rcp > 0.0) & (tmax > 0.0);
    LightRay { ray: Ray { origin, dir, tmin: 0.0, tmax }, weight: inv * (le * inv_pdf) * (cos * w), valid }
}
