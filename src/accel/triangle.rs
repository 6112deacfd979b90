//! Ray–triangle intersection.
use crate::ray::Ray;
use glam::Vec3;

/// Möller–Trumbore test; returns (t, u, v) with t in [tmin, tmax].
/// Placeholder until the watertight test lands with the BVH.
#[inline]
pub fn intersect(ray: &Ray, p0: Vec3, p1: Vec3, p2: Vec3) -> Option<(f32, f32, f32)> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pv = ray.dir.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tv = ray.origin - p0;
    let u = tv.dot(pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = tv.cross(e1);
    let v = ray.dir.dot(qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(qv) * inv;
    (t >= ray.tmin && t <= ray.tmax).then_some((t, u, v))
}
