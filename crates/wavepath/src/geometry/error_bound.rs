//! Conservative bounds on the rounding error of reconstructed surface points (pbrt-v3 3.9):
//! what ray offsets need to step off a surface without stepping over anything else.

use glam::Vec3;

/// Unit roundoff of f32 (half an ulp of 1): one correctly rounded operation has relative
/// error at most this.
pub const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// Higham's bound on the relative error of `n` chained roundings, (1 ± eps)^n - 1 <= gamma(n).
#[inline]
pub const fn gamma(n: u32) -> f32 {
    let ne = n as f32 * MACHINE_EPSILON;
    ne / (1.0 - ne)
}

/// Error bound of the triangle point `w a + u b + v c` with `w = 1 - u - v`, all rounded as f32
/// (the way [`Scene::surface_point`](super::Scene::surface_point) reconstructs it): pbrt's
/// gamma(7) bound on the weighted sum, the rounding of `w` itself (the weights no longer sum
/// to exactly one, which moves the point by that error times `|a|`). The triangle test's own
/// error in `t` needs no margin here: it rejects hits within its pbrt-style bound
/// (`src/accel/triangle.rs`), so an origin strictly off its plane never finds it again.
#[inline]
pub fn triangle_error(a: Vec3, b: Vec3, c: Vec3, u: f32, v: f32) -> Vec3 {
    let w = 1.0 - u - v;
    gamma(7) * ((w * a).abs() + (u * b).abs() + (v * c).abs()) + gamma(2) * (1.0 + u.abs() + v.abs()) * a.abs()
}

/// Error bound of `center + radius * normalize(q - center)` (a point re-projected onto a
/// sphere): the local vector's length is radius times a chain of about seven roundings
/// (dot product, square root, reciprocal, two products), its direction does not matter (any
/// direction gives a point on the sphere), and adding the centre rounds once more.
#[inline]
pub fn sphere_error(center: Vec3, local: Vec3) -> Vec3 {
    gamma(8) * local.abs() + gamma(1) * center.abs()
}

/// The margin on the far end of the ray's range (its `tmax`, or the closest hit so far) in
/// box tests and stack pops. A hit on a box's boundary (a ray through a shared vertex or
/// edge, or ending on a surface) has a `t` that rounds independently of the box's entry
/// distance, by a few ulps each way; without a margin the leaf holding the tied triangle with
/// the lower id could be culled or not depending on the order leaves are visited in, so the
/// ISAs (different visiting orders) would report different triangles. 2^-16 relative is ~100
/// ulps: it covers the rounding of both for coordinates of the order of the distances and
/// costs nothing measurable (a node entering within it beyond the closest hit is rare).
pub const TIE_SCALE: f32 = 1.0 + 1.0 / 65536.0;
