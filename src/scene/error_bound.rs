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

/// Multiple of the unit roundoff, times the triangle's extent seen from the hit point, by
/// which the watertight triangle test (src/accel/triangle.rs) can misplace `t`. That test
/// subtracts the ray origin from the corners, shears them and sums three products of edge
/// functions and depths; pbrt-v3 (3.9.6) bounds the result by `deltaT` ~ 3 (2 gamma(3) +
/// 2 gamma(2) + 4 gamma(5)) maxZ, about 80 eps times the largest corner distance, and rejects
/// hits below it. Our test has no such check, so a ray starting on a triangle can find that
/// triangle at a rounded `t` just above 0; offsetting the origin by this much more puts the
/// exact `t` of its own plane below minus the error. Grazing rays keep the same margin: their
/// plane lies `d / cos` behind them and their error grows as `1 / cos` too.
pub const TRIANGLE_TEST_ULPS: u32 = 96;

/// Error bound of the triangle point `w a + u b + v c` with `w = 1 - u - v`, all rounded as f32
/// (the way [`Scene::surface_point`](super::Scene::surface_point) reconstructs it): pbrt's
/// gamma(7) bound on the weighted sum, the rounding of `w` itself (the weights no longer sum
/// to exactly one, which moves the point by that error times `|a|`), and the triangle test's
/// error in `t` for rays that start at `p` ([`TRIANGLE_TEST_ULPS`]).
#[inline]
pub fn triangle_error(a: Vec3, b: Vec3, c: Vec3, u: f32, v: f32, p: Vec3) -> Vec3 {
    let w = 1.0 - u - v;
    let reconstruction =
        gamma(7) * ((w * a).abs() + (u * b).abs() + (v * c).abs()) + gamma(2) * (1.0 + u.abs() + v.abs()) * a.abs();
    let extent = (a - p).abs().max((b - p).abs()).max((c - p).abs()).max_element();
    reconstruction + Vec3::splat(gamma(TRIANGLE_TEST_ULPS) * extent)
}

/// Error bound of `center + radius * normalize(q - center)` (a point re-projected onto a
/// sphere): the local vector's length is radius times a chain of about seven roundings
/// (dot product, square root, reciprocal, two products), its direction does not matter (any
/// direction gives a point on the sphere), and adding the centre rounds once more.
#[inline]
pub fn sphere_error(center: Vec3, local: Vec3) -> Vec3 {
    gamma(8) * local.abs() + gamma(1) * center.abs()
}
