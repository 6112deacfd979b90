use glam::Vec3;

/// Relative size of the offset that lifts a ray origin off its surface: a few thousand ulps
/// of the point's largest coordinate, far above the rounding error of a reconstructed hit
/// point (pbrt bounds it by ~gamma(7) |p|), far below any feature size of the scenes.
const REL_OFFSET: f32 = 1.0 / (1u32 << 18) as f32;

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
