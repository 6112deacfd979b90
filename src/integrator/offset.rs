//! Where a ray that leaves a surface starts and where a ray toward a light point stops,
//! from per-point floating-point error bounds (pbrt-v3 3.9, pbrt-v4 6.8).
//!
//! A reconstructed hit point `p` is within `p_error` (per component) of a point on the true
//! surface. Moving `p` along the geometric normal by `dot(|n|, p_error)` puts the whole error
//! box on one side of the surface's tangent plane, and rounding each component of the moved
//! point away from the surface keeps the rounding of that move from undoing it. The offset is
//! thus as small as the point's own error allows: no fixed fraction of |p| that is too small
//! for large triangles and too large for small features far from the origin.

use crate::ray::Ray;
use glam::Vec3;

/// Absolute offset added to every error bound before it is used. Bounds are relative to
/// the magnitudes that enter a computation, so a point computed exactly (a vertex at the
/// origin, a sphere centred there) gets a zero bound, and a ray starting exactly on its plane
/// leaves the triangle test nothing but the sign of a rounded zero. 2^-100 (~8e-31) is far
/// above f32's smallest normal (so it survives a multiplication by a unit normal component)
/// and far below any feature size a scene can express next to a non-zero coordinate.
const ERROR_FLOOR: f32 = 7.888_609e-31;

/// The origin of a ray that leaves the surface point `p` (error bound `p_error`, geometric
/// normal `ng`, any orientation) in direction `dir`: on the side of the surface `dir` points
/// to, outside `p`'s error box, so the ray cannot find its own surface again.
#[inline(always)]
pub fn offset_origin(p: Vec3, p_error: Vec3, ng: Vec3, dir: Vec3) -> Vec3 {
    let d = ng.abs().dot(p_error) + ERROR_FLOOR;
    let offset = if ng.dot(dir) < 0.0 { -d * ng } else { d * ng };
    let po = p + offset;
    // `p + offset` rounds to nearest, which may move it back toward the surface by half an
    // ulp; rounding away from it instead keeps the full offset.
    Vec3::new(away(po.x, offset.x), away(po.y, offset.y), away(po.z, offset.z))
}

/// `x` moved one ulp toward the sign of `o` (unchanged when `o` is zero).
#[inline(always)]
fn away(x: f32, o: f32) -> f32 {
    if o > 0.0 {
        x.next_up()
    } else if o < 0.0 {
        x.next_down()
    } else {
        x
    }
}

/// Relative shortening of a shadow ray: its unit direction and length are each a few
/// roundings (~1e-7 relative) away from the exact segment, so its end can drift past the
/// light point by that much of the distance; 1e-5 is 100x that, and a blocker closer to the
/// light than 1e-5 of the distance is not resolvable from the shading point anyway (the
/// CS184 scenes put emissive quads exactly on their area lights).
const SHADOW_SHORTEN: f32 = 1e-5;

/// The `tmax` of a unit-direction shadow ray from `origin` toward the light point `target`
/// (error bound `target_error`): it stops before the light's own surface, so the surface
/// the light point lies on does not occlude it.
#[inline]
pub fn shadow_tmax(origin: Vec3, target: Vec3, target_error: Vec3) -> f32 {
    let d = (target - origin).length();
    // Twice the error box's diagonal: the target may lie that far in front of the surface it
    // was sampled on, and the surface's own hit point as far again.
    d * (1.0 - SHADOW_SHORTEN) - 2.0 * (target_error.length() + ERROR_FLOOR)
}

/// The shadow ray from `origin` (already offset) along `dir`, or, for a light point
/// `target` (with its error bound), aimed from `origin` itself at the target: a direction
/// computed from the surface point before the offset runs parallel to the true segment,
/// `offset / cos` too far, and can reach the light's surface before its `tmax`. `None`
/// when the origin is already at the light.
#[inline]
pub fn shadow_ray(origin: Vec3, dir: Vec3, target: Option<(Vec3, Vec3)>) -> Option<Ray> {
    let Some((q, q_error)) = target else {
        return Some(Ray { origin, dir, tmin: 0.0, tmax: f32::INFINITY });
    };
    let dir = (q - origin).try_normalize()?;
    let tmax = shadow_tmax(origin, q, q_error);
    (tmax > 0.0).then_some(Ray { origin, dir, tmin: 0.0, tmax })
}
