use super::Scene;
use crate::geometry::error_bound::{sphere_error, triangle_error};
use crate::geometry::{Hit, Ray};
use glam::{Vec2, Vec3};

/// What shading needs to know about a hit point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub position: Vec3,
    /// Per-component bound on how far `position` is from the exact surface (rounding of its
    /// reconstruction); rays leaving the point are offset by it.
    pub p_error: Vec3,
    /// Unit normal of the true surface (triangle plane or sphere), not flipped.
    pub geometric_normal: Vec3,
    /// Unit normal used for shading (interpolated vertex normals where the mesh has them).
    pub shading_normal: Vec3,
    pub uv: Vec2,
    /// The interpolated vertex colour (white where the mesh has none).
    pub color: Vec3,
    pub material: u32,
}

impl Scene {
    /// Reconstructs the surface point of `hit` on `ray`.
    pub fn surface_point(&self, ray: &Ray, hit: &Hit) -> SurfacePoint {
        self.surface_point_with(ray, hit, true)
    }

    /// Whether `ray` hits the front of `hit`'s surface: the side a triangle's winding (or a
    /// sphere's outward normal) points to, the side a one-sided emitter lights. The same rule
    /// as shading's orientation of the geometric normal.
    pub fn front_face(&self, ray: &Ray, hit: &Hit) -> bool {
        let prim = hit.prim as usize;
        let n = if prim < self.mesh.triangles.len() {
            let [a, b, c] = self.mesh.corners(prim);
            (b - a).cross(c - a)
        } else {
            ray.at(hit.t) - self.spheres[prim - self.mesh.triangles.len()].center
        };
        n.dot(ray.dir) <= 0.0
    }

    /// The uv of triangle `prim` at barycentrics (`u`, `v`): the mesh's uvs interpolated, or
    /// (`u`, `v`) itself where the mesh has none.
    #[inline(always)]
    pub fn triangle_uv(&self, prim: usize, u: f32, v: f32) -> Vec2 {
        match &self.mesh.uvs {
            Some(t) => {
                let [ia, ib, ic] = self.mesh.triangles[prim];
                (1.0 - u - v) * t[ia as usize] + u * t[ib as usize] + v * t[ic as usize]
            }
            None => Vec2::new(u, v),
        }
    }

    /// [`surface_point`](Self::surface_point); a sphere point's `uv` (an `atan2` and an `acos`)
    /// only when `uv` is asked for (zero otherwise: untextured shading never reads it).
    #[inline(always)]
    pub fn surface_point_with(&self, ray: &Ray, hit: &Hit, uv: bool) -> SurfacePoint {
        let ntri = self.mesh.triangles.len();
        let prim = hit.prim as usize;
        if prim < ntri {
            let [ia, ib, ic] = self.mesh.triangles[prim];
            let [a, b, c] = self.mesh.corners(prim);
            let (u, v) = (hit.u, hit.v);
            let w = 1.0 - u - v;
            let (position, p_error, geometric_normal) = triangle_point(a, b, c, u, v);
            let shading_normal = match &self.mesh.normals {
                Some(n) => {
                    interpolated_normal([n[ia as usize], n[ib as usize], n[ic as usize]], u, v, geometric_normal)
                }
                None => geometric_normal,
            };
            let uv = self.triangle_uv(prim, u, v);
            let color = match &self.mesh.colors {
                Some(c) => w * c[ia as usize] + u * c[ib as usize] + v * c[ic as usize],
                None => Vec3::ONE,
            };
            SurfacePoint {
                position,
                p_error,
                geometric_normal,
                shading_normal,
                uv,
                color,
                material: self.mesh.material_ids[prim],
            }
        } else {
            let s = &self.spheres[prim - ntri];
            let (position, p_error, n) = sphere_point(s.center, s.radius, ray.at(hit.t));
            let uv = if uv {
                Vec2::new(
                    0.5 + n.z.atan2(n.x) / std::f32::consts::TAU,
                    n.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI,
                )
            } else {
                Vec2::ZERO
            };
            SurfacePoint {
                position,
                p_error,
                geometric_normal: n,
                shading_normal: n,
                uv,
                color: Vec3::ONE,
                material: s.material,
            }
        }
    }
}

/// `v` normalised, or `fallback` when it has no direction (what `try_normalize` does,
/// written with selects so a loop over lanes vectorises).
#[inline(always)]
pub fn normalize_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let rcp = 1.0 / v.length();
    if rcp.is_finite() && rcp > 0.0 { v * rcp } else { fallback }
}

/// The point of triangle (a, b, c) at barycentrics (u, v), its error bound and the unit
/// normal of the triangle's plane. Interpolating the corners is more accurate than o + t d
/// far from the origin.
#[inline(always)]
pub fn triangle_point(a: Vec3, b: Vec3, c: Vec3, u: f32, v: f32) -> (Vec3, Vec3, Vec3) {
    let w = 1.0 - u - v;
    let position = w * a + u * b + v * c;
    (position, triangle_error(a, b, c, u, v), normalize_or((b - a).cross(c - a), Vec3::Y))
}

/// The corner normals `n` interpolated at (u, v) and normalised (`fallback` if degenerate).
#[inline(always)]
pub fn interpolated_normal(n: [Vec3; 3], u: f32, v: f32, fallback: Vec3) -> Vec3 {
    let w = 1.0 - u - v;
    normalize_or(w * n[0] + u * n[1] + v * n[2], fallback)
}

/// The point of a sphere nearest to `p` (a hit point on it): projected onto the sphere so
/// it is as exact as the radius allows, with its error bound and the outward unit normal.
#[inline(always)]
pub fn sphere_point(center: Vec3, radius: f32, p: Vec3) -> (Vec3, Vec3, Vec3) {
    let n = normalize_or(p - center, Vec3::Y);
    let local = n * radius;
    (center + local, sphere_error(center, local), n)
}
