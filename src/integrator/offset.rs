use glam::Vec3;

/// Relative size of the offset that lifts a ray origin off its surface: 8 ulps of the
/// point's largest coordinate, above the rounding error of a reconstructed hit point (pbrt
/// bounds it by ~gamma(7) |p| = 4.2e-7 |p|) and of the watertight test's t on large
/// triangles (2^-21 let a 10x10 plane shadow itself: tests/analytic.rs
/// `plane_under_a_point_light`). Larger offsets (2^-18) start shadow rays inside small
/// features far from the origin (0.38 at |p| = 1e5, more than a 0.3 sphere):
/// tests/stability.rs `cornell_box_far_from_the_origin`. A per-hit error bound would remove
/// this trade-off.
const REL_OFFSET: f32 = 1.0 / (1u32 << 20) as f32;

#[inline]
fn scale(p: Vec3) -> f32 {
    p.abs().max_element().max(1.0) * REL_OFFSET
}

/// A ray origin for leaving the surface at `p` (geometric normal `ng`) toward `dir`: moved
/// along the normal to the side `dir` goes, by an amount that grows with |p|, so the ray does
/// not find its own surface again whatever the scene's scale.
#[inline]
pub fn offset_origin(p: Vec3, ng: Vec3, dir: Vec3) -> Vec3 {
    let s = scale(p);
    if ng.dot(dir) >= 0.0 { p + ng * s } else { p - ng * s }
}

/// The `tmax` of a unit-direction shadow ray from `origin` toward the light point `target`:
/// it stops short of the light's surface by that surface's own offset.
#[inline]
pub fn shadow_tmax(origin: Vec3, target: Vec3) -> f32 {
    let d = (target - origin).length();
    d * (1.0 - 1e-5) - 2.0 * scale(target)
}
