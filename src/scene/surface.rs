use super::Scene;
use super::error_bound::{sphere_error, triangle_error};
use crate::ray::{Hit, Ray};
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
    pub material: u32,
}

impl Scene {
    /// Reconstructs the surface point of `hit` on `ray`.
    pub fn surface_point(&self, ray: &Ray, hit: &Hit) -> SurfacePoint {
        self.surface_point_with(ray, hit, true)
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
            // Interpolating the corners is more accurate than o + t d far from the origin.
            let position = w * a + u * b + v * c;
            let p_error = triangle_error(a, b, c, u, v);
            let geometric_normal = (b - a).cross(c - a).try_normalize().unwrap_or(Vec3::Y);
            let shading_normal = match &self.mesh.normals {
                Some(n) => (w * n[ia as usize] + u * n[ib as usize] + v * n[ic as usize])
                    .try_normalize()
                    .unwrap_or(geometric_normal),
                None => geometric_normal,
            };
            let uv = match &self.mesh.uvs {
                Some(t) => w * t[ia as usize] + u * t[ib as usize] + v * t[ic as usize],
                None => Vec2::new(u, v),
            };
            SurfacePoint {
                position,
                p_error,
                geometric_normal,
                shading_normal,
                uv,
                material: self.mesh.material_ids[prim],
            }
        } else {
            let s = &self.spheres[prim - ntri];
            let p = ray.at(hit.t);
            let n = (p - s.center).try_normalize().unwrap_or(Vec3::Y);
            // Project onto the sphere so the point is as exact as the radius allows.
            let local = n * s.radius;
            let position = s.center + local;
            let p_error = sphere_error(s.center, local);
            let uv = if uv {
                Vec2::new(
                    0.5 + n.z.atan2(n.x) / std::f32::consts::TAU,
                    n.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI,
                )
            } else {
                Vec2::ZERO
            };
            SurfacePoint { position, p_error, geometric_normal: n, shading_normal: n, uv, material: s.material }
        }
    }
}
