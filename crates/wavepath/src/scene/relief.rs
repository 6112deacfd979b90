//! Surface relief read from images: tangent-space normal maps (glTF `normalTexture`, MTL
//! `norm`) and height maps (MTL `bump`/`map_Bump`). Either only tilts the shading normal;
//! the geometry, and so the hit points, stay the mesh's.

use super::Scene;
use super::surface::normalize_or;
use super::texture::Texture;
use crate::geometry::Hit;
use glam::{Vec2, Vec3};

/// What a relief image holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Relief {
    /// A tangent-space normal, (r, g, b) in [0, 1] mapping to [-1, 1]; x and y scaled by
    /// `scale` (glTF `normalTexture.scale`).
    Normal { scale: f32 },
    /// A height in the red channel (0..1, linear) times `bm` (MTL `-bm`), in world units:
    /// the surface is displaced along its normal by `bm h(u, v)` (pbrt's bump mapping) and
    /// the shading normal is the displaced surface's.
    Height { bm: f32 },
}

/// A relief image and how to read it. The texture's image holds linear values.
#[derive(Clone, Debug, PartialEq)]
pub struct ReliefMap {
    pub texture: Texture,
    pub relief: Relief,
}

/// The tangents at a triangle point: the mesh's per-vertex ones (xyz interpolated, w the
/// bitangent's handedness: glTF TANGENT or MikkTSpace), or the triangle's uv
/// parametrisation (dp/du, dp/dv).
enum Tangents {
    Mesh { t: Vec3, sign: f32 },
    Uv { dpdu: Vec3, dpdv: Vec3 },
}

impl Scene {
    /// The shading normal of `hit` on triangle `hit.prim` with its material's relief map
    /// applied (`ns` when the material has none, the triangle has no usable uvs or the
    /// image is missing). Not yet turned toward the ray: the caller orients it.
    #[inline(never)]
    pub fn relief_normal(&self, hit: &Hit, ns: Vec3, uv: Vec2, material: u32) -> Vec3 {
        let prim = hit.prim as usize;
        if prim >= self.mesh.triangles.len() || self.mesh.uvs.is_none() {
            return ns;
        }
        let Some(map) = self.materials.get(material as usize).and_then(|m| m.relief.as_ref()) else { return ns };
        let mesh_tangents = matches!(map.relief, Relief::Normal { .. });
        let Some(t) = self.tangents_at(prim, hit.u, hit.v, mesh_tangents) else { return ns };
        map.apply(&t, ns, uv).unwrap_or(ns)
    }

    /// `mesh_tangents`: use the mesh's tangents where it has them (normal maps are baked
    /// against them); height maps need the parametrisation's own scale.
    fn tangents_at(&self, prim: usize, u: f32, v: f32, mesh_tangents: bool) -> Option<Tangents> {
        let [ia, ib, ic] = self.mesh.triangles[prim].map(|i| i as usize);
        if let Some(tan) = self.mesh.tangents.as_ref().filter(|_| mesh_tangents) {
            let w = 1.0 - u - v;
            let t = w * tan[ia] + u * tan[ib] + v * tan[ic];
            let sign = if tan[ia].w < 0.0 { -1.0 } else { 1.0 };
            let t = t.truncate();
            if t.length_squared() > 0.0 && t.is_finite() {
                return Some(Tangents::Mesh { t, sign });
            }
        }
        let uvs = self.mesh.uvs.as_ref()?;
        let [a, b, c] = self.mesh.corners(prim);
        let (ta, tb, tc) = (uvs[ia], uvs[ib], uvs[ic]);
        let (d1, d2) = (tb - ta, tc - ta);
        let (e1, e2) = (b - a, c - a);
        let det = d1.x * d2.y - d1.y * d2.x;
        let inv = 1.0 / det;
        if !inv.is_finite() {
            return None;
        }
        let dpdu = (e1 * d2.y - e2 * d1.y) * inv;
        let dpdv = (e2 * d1.x - e1 * d2.x) * inv;
        (dpdu.is_finite() && dpdv.is_finite()).then_some(Tangents::Uv { dpdu, dpdv })
    }
}

impl ReliefMap {
    fn apply(&self, t: &Tangents, ns: Vec3, uv: Vec2) -> Option<Vec3> {
        match self.relief {
            Relief::Normal { scale } => {
                let c = self.texture.albedo(uv)?;
                let m = Vec3::new((2.0 * c.x - 1.0) * scale, (2.0 * c.y - 1.0) * scale, 2.0 * c.z - 1.0);
                let (t0, side) = match *t {
                    Tangents::Mesh { t, sign } => (t, Err(sign)),
                    // The texel's +y is up in the image: +v for OBJ (v up), -v for glTF.
                    Tangents::Uv { dpdu, dpdv } => (dpdu, Ok(if self.texture.flip_v { dpdv } else { -dpdv })),
                };
                // Gram-Schmidt: the tangent perpendicular to the interpolated normal; the
                // bitangent n x t with the file's handedness, or on dp/dv's side.
                let tangent = (t0 - ns * ns.dot(t0)).try_normalize()?;
                let b = ns.cross(tangent);
                let bitangent = match side {
                    Err(sign) => b * sign,
                    Ok(dpdv) if b.dot(dpdv) < 0.0 => -b,
                    Ok(_) => b,
                };
                Some(normalize_or(tangent * m.x + bitangent * m.y + ns * m.z, ns))
            }
            Relief::Height { bm } => {
                let img = self.texture.image.as_deref()?;
                let Tangents::Uv { dpdu, dpdv } = *t else { return None };
                // Central differences half a texel either side.
                let (du, dv) = (0.5 / img.width as f32, 0.5 / img.height as f32);
                let h = |d: Vec2| self.texture.albedo(uv + d).map(|c| c.x * bm);
                let dhdu = (h(Vec2::new(du, 0.0))? - h(Vec2::new(-du, 0.0))?) / (2.0 * du);
                let dhdv = (h(Vec2::new(0.0, dv))? - h(Vec2::new(0.0, -dv))?) / (2.0 * dv);
                // The displaced surface p + h n has tangents dp/du + dh/du n (pbrt's bump
                // mapping, the normal's own change neglected) and its normal their cross
                // product, on the side of the unperturbed one.
                let n = (dpdu + dhdu * ns).cross(dpdv + dhdv * ns);
                let n = normalize_or(n, ns);
                Some(if n.dot(ns) < 0.0 { -n } else { n })
            }
        }
    }
}

/// The normal `ns` (a relief map's, turned toward `wo`'s side like `ng`) bent toward the
/// geometric normal `ng` just enough that the mirror direction of `wo` about it lies above
/// the geometric surface: a strongly tilted map would otherwise face away from the viewer
/// and shade black, or send reflections into the surface. `wo` is the unit direction toward
/// the viewer, with `wo . ng > 0`. Unchanged where it is already valid, so a gentle map
/// keeps its exact normal.
#[inline(never)]
pub fn keep_visible(ns: Vec3, ng: Vec3, wo: Vec3) -> Vec3 {
    const MARGIN: f32 = 0.01;
    let valid = |n: Vec3| {
        let c = wo.dot(n);
        c > 0.0 && (2.0 * c * n - wo).dot(ng) >= MARGIN.min(wo.dot(ng))
    };
    if valid(ns) {
        return ns;
    }
    // Bisection on the blend toward ng (at which the reflection is wo's own mirror image).
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    for _ in 0..12 {
        let mid = 0.5 * (lo + hi);
        if valid(normalize_or(ns.lerp(ng, mid), ng)) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    normalize_or(ns.lerp(ng, hi), ng)
}
