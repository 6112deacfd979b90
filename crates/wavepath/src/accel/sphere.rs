//! Ray–sphere intersection in the numerically stable form.
use crate::geometry::Ray;
use glam::Vec3;

/// Nearest root of |o + t d - c|^2 = r^2 inside [tmin, tmax].
///
/// Uses the Hearn–Baker / Ray Tracing Gems (ch. 7) form: the discriminant is computed from
/// the distance of the centre to the ray's line, which does not cancel catastrophically for
/// small spheres far away, and the second root comes from the product of roots.
#[inline]
pub fn intersect(ray: &Ray, center: Vec3, radius: f32) -> Option<f32> {
    let a = ray.dir.length_squared();
    if a == 0.0 || !a.is_finite() {
        return None;
    }
    let f = ray.origin - center;
    let b = -f.dot(ray.dir);
    // |f + (b/a) d|^2 is the squared distance of the centre from the line.
    let l = f + (b / a) * ray.dir;
    let disc = a * (radius * radius - l.length_squared());
    if disc < 0.0 {
        return None;
    }
    let c = f.length_squared() - radius * radius;
    let q = b + b.signum() * disc.sqrt();
    let (mut t0, mut t1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q / a) };
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    if t0 >= ray.tmin && t0 <= ray.tmax {
        Some(t0)
    } else if t1 >= ray.tmin && t1 <= ray.tmax {
        Some(t1)
    } else {
        None
    }
}
