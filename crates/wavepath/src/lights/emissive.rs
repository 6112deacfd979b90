use super::{LightSample, area_to_solid_angle};
use crate::geometry::error_bound::gamma;
use crate::geometry::illuminance;
use crate::sampling::warp;
use crate::scene::Scene;
use crate::scene::texture::{Texture, Wrap, wrap_index};
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// All emissive triangles of a mesh as one light, a triangle chosen in proportion to its
/// power (area x mean emitted illuminance) and a point uniformly on it, so a dim emitter
/// takes few samples and a bright one many. A triangle emits from both faces or from its
/// front only, as its material says (a two-sided emitter has twice the power). A triangle under an emission texture emits factor x texel at each
/// point: its mean is estimated from a grid of lookups, floored at a tenth of its brightest
/// texel so that no point that emits has zero density (the estimator stays unbiased
/// whatever the estimate); one whose texels are all black over its uv footprint emits
/// nothing anywhere and is left out.
#[derive(Clone, Debug)]
pub struct EmissiveTriangles {
    /// What a sample of each triangle reads, in one place.
    triangles: Vec<Emitter>,
    emission: Vec<Vec3>,
    /// For a textured triangle: its material's emission texture and its corners' uvs.
    textured: Vec<Option<(u32, [Vec2; 3])>>,
    /// Per material, the decoded emission texture (when the mesh has uvs).
    textures: Vec<Option<Texture>>,
    /// Running sum of powers (the last entry is the total).
    cdf: Vec<f32>,
    /// Per triangle, the density of sampled points per unit area: power / (area x total).
    density: Vec<f32>,
    /// Per triangle, its index in the mesh (ascending).
    prims: Vec<u32>,
    /// Largest error bound of a sampled point over all triangles (see
    /// [`point_error`](Self::point_error)).
    max_error: Vec3,
}

impl EmissiveTriangles {
    pub fn new(scene: &Scene) -> Option<Self> {
        let textures: Vec<Option<Texture>> = scene
            .materials
            .iter()
            .map(|m| m.emission_texture.clone().filter(|t| t.image.is_some() && scene.mesh.uvs.is_some()))
            .collect();
        let mut textured = Vec::new();
        let mut corners = Vec::new();
        let mut emission = Vec::new();
        let mut one_sided = Vec::new();
        let mut cdf = Vec::new();
        let mut powers = Vec::new();
        let mut prims = Vec::new();
        let mut total = 0.0f32;
        let mut max_error = Vec3::ZERO;
        for (i, m) in scene.mesh.material_ids.iter().enumerate() {
            let mat = &scene.materials[m as usize];
            if !mat.is_emissive() {
                continue;
            }
            let [a, b, c] = scene.mesh.corners(i);
            let area = 0.5 * (b - a).cross(c - a).length();
            let tex = textures[m as usize].as_ref().zip(scene.mesh.uvs.as_ref()).map(|(t, uvs)| {
                let [ia, ib, ic] = scene.mesh.triangles[i];
                (t, [uvs[ia as usize], uvs[ib as usize], uvs[ic as usize]])
            });
            let brightness = match tex {
                Some((t, uv)) => {
                    let brightest = illuminance(t.factor * brightest_texel(t, uv));
                    if brightest <= 0.0 {
                        continue;
                    }
                    mean_illuminance(t, uv).max(0.1 * brightest)
                }
                None => illuminance(mat.emission),
            };
            let brightness = if mat.two_sided_emission { 2.0 * brightness } else { brightness };
            let power = area * brightness;
            if area > 0.0 && power > 0.0 && power.is_finite() {
                total += power;
                let (e1, e2) = (b - a, c - a);
                // a + bu e1 + bv e2 with bu, bv in [0, 1]: two products and two sums, plus
                // the rounding of the edges themselves (up to eps |e|, scaled by bu, bv <= 1).
                max_error = max_error.max(gamma(4) * (a.abs() + e1.abs() + e2.abs()));
                corners.push([a, e1, e2]);
                emission.push(mat.emission);
                one_sided.push(!mat.two_sided_emission);
                textured.push(tex.map(|(_, uv)| (m, uv)));
                cdf.push(total);
                powers.push(brightness);
                prims.push(i as u32);
            }
        }
        let density: Vec<f32> = powers.iter().map(|&b| b / total).collect();
        let triangles = corners
            .iter()
            .zip(&density)
            .zip(&one_sided)
            .map(|((&[a, e1, e2], &d), &one_sided)| {
                let n = e1.cross(e2).try_normalize();
                Emitter { a, e1, e2, n: n.unwrap_or(Vec3::Z), valid: n.is_some(), inv_density: 1.0 / d, one_sided }
            })
            .collect();
        (total > 0.0).then_some(EmissiveTriangles {
            triangles,
            emission,
            textured,
            textures,
            cdf,
            density,
            prims,
            max_error,
        })
    }

    /// Per-component bound on the distance of any sampled point from its triangle: one
    /// bound for all triangles (the largest), since a light sample does not say which
    /// triangle it came from; it only shortens shadow rays by a few ulps of the largest
    /// emitter's coordinates.
    pub fn point_error(&self) -> Vec3 {
        self.max_error
    }

    /// The density per unit area with which [`sample_pdf`](Self::sample_pdf) draws points
    /// of mesh triangle `prim` (0 for a triangle it never draws).
    pub fn area_density(&self, prim: u32) -> f32 {
        self.prims.binary_search(&prim).map_or(0.0, |i| self.density[i])
    }

    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    #[inline]
    pub fn sample(&self, p: Vec3, u: [f32; 3]) -> Option<LightSample> {
        self.sample_pdf(p, u).map(|(ls, _)| ls)
    }

    /// [`sample`](Self::sample) and the solid-angle density of the drawn direction.
    #[inline]
    pub fn sample_pdf(&self, p: Vec3, u: [f32; 3]) -> Option<(LightSample, f32)> {
        let i = self.pick(u[2])?;
        let tri = &self.triangles[i];
        let (q, bu, bv) = tri.point(u[0], u[1]);
        if !tri.valid {
            return None;
        }
        let (wi, inv_pdf) = area_to_solid_angle(p, q, tri.n, tri.inv_density, tri.one_sided)?;
        let le = self.emitted(i, bu, bv);
        Some((LightSample { wi, target: Some(q), weight: le * inv_pdf }, 1.0 / inv_pdf))
    }

    /// The triangle a light sample whose third number is `u` draws (in proportion to power).
    #[inline(always)]
    pub fn pick(&self, u: f32) -> Option<usize> {
        let total = *self.cdf.last()?;
        let x = u * total;
        Some(self.cdf.partition_point(|&c| c <= x).min(self.cdf.len() - 1))
    }

    /// Triangle `i` of the light (an index [`pick`](Self::pick) gave).
    #[inline(always)]
    pub fn triangle(&self, i: usize) -> &Emitter {
        &self.triangles[i]
    }

    /// The radiance triangle `i` emits at barycentrics (`bu`, `bv`).
    #[inline(always)]
    pub fn emitted(&self, i: usize, bu: f32, bv: f32) -> Vec3 {
        match self.textured[i] {
            Some((m, [ua, ub, uc])) => {
                let uv = ua + bu * (ub - ua) + bv * (uc - ua);
                self.textures[m as usize].as_ref().and_then(|t| t.albedo(uv)).unwrap_or(self.emission[i])
            }
            None => self.emission[i],
        }
    }
}

impl EmissiveTriangles {
    /// Densities of a light point on mesh triangle `prim` reached
    /// along `-w` (`w` leaves the light): per unit area (the triangle's share of the
    /// light's samples) and, times the cosine-weighted direction's, per area and solid
    /// angle. `None` for a triangle this light does not draw or a side it does not emit.
    pub fn emission_pdfs(&self, prim: u32, w: Vec3) -> Option<(f32, f32)> {
        let i = self.prims.binary_search(&prim).ok()?;
        let tri = &self.triangles[i];
        let c = w.dot(tri.n);
        let cos = if tri.one_sided { c } else { c.abs() };
        if cos <= 0.0 {
            return None;
        }
        let pdf_a = self.density[i];
        let sides = if tri.one_sided { 1.0 } else { 0.5 };
        Some((pdf_a, pdf_a * cos * FRAC_1_PI * sides))
    }

    /// [`emission_pdfs`](Self::emission_pdfs)' second density over the cosine at the light:
    /// the light subpath's density of the direction `-w` converted to the area measure at a
    /// point at unit distance, as the path tracer's side of path+light weighs a hit by it.
    #[inline]
    pub fn emission_pdf_per_cos(&self, prim: u32, w: Vec3) -> Option<f32> {
        let i = self.prims.binary_search(&prim).ok()?;
        let tri = &self.triangles[i];
        let c = w.dot(tri.n);
        if (if tri.one_sided { c } else { c.abs() }) <= 0.0 {
            return None;
        }
        let sides = if tri.one_sided { 1.0 } else { 0.5 };
        Some(self.density[i] * FRAC_1_PI * sides)
    }

    /// The light's total power per pi (sum of area x emitted illuminance).
    pub fn total_power(&self) -> f32 {
        self.cdf.last().copied().unwrap_or(0.0)
    }
}

/// One emissive triangle as a light sample reads it (gathered per lane by the lane kernel).
#[derive(Clone, Copy, Debug)]
pub struct Emitter {
    /// Corner 0 and the two edges from it.
    pub a: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
    /// Unit normal (`e1 x e2`); `valid` false when it cannot be normalised.
    pub n: Vec3,
    pub valid: bool,
    /// 1 / the density of sampled points per unit area.
    pub inv_density: f32,
    pub one_sided: bool,
}

impl Emitter {
    /// The point at (`u`, `v`) in [0, 1)^2, uniform over the triangle, and its barycentrics.
    #[inline(always)]
    pub fn point(&self, u: f32, v: f32) -> (Vec3, f32, f32) {
        let (bu, bv) = warp::uniform_triangle(u, v);
        (Self::point_at(self.a, self.e1, self.e2, bu, bv), bu, bv)
    }

    /// The point at barycentrics (`bu`, `bv`) of the triangle with corner `a` and edges `e1`,
    /// `e2` from it (the lane kernels hold the corners of a group's triangles in lanes).
    #[inline(always)]
    pub fn point_at(a: Vec3, e1: Vec3, e2: Vec3, bu: f32, bv: f32) -> Vec3 {
        a + bu * e1 + bv * e2
    }
}

/// Mean illuminance of `t` over the triangle with these uvs, from lookups at the centres of
/// a grid of 64 equal-area cells of the triangle.
fn mean_illuminance(t: &Texture, uv: [Vec2; 3]) -> f32 {
    const N: usize = 8;
    let mut sum = 0.0;
    for i in 0..N {
        for j in 0..N {
            let (bu, bv) = warp::uniform_triangle((i as f32 + 0.5) / N as f32, (j as f32 + 0.5) / N as f32);
            let p = uv[0] + bu * (uv[1] - uv[0]) + bv * (uv[2] - uv[0]);
            sum += t.albedo(p).map_or(0.0, illuminance);
        }
    }
    sum / (N * N) as f32
}

/// The brightest texel a lookup anywhere in the triangle with these uvs can reach: the texels
/// of its uv box as the filter reads them (nearest: the texel containing each point;
/// bilinear: also the next one), wrapped as the sampler wraps; the whole image when the box
/// is larger.
fn brightest_texel(t: &Texture, uv: [Vec2; 3]) -> Vec3 {
    let Some(img) = t.image.as_deref() else { return Vec3::ZERO };
    let (w, h) = (img.width, img.height);
    let v = |p: Vec2| if t.flip_v { 1.0 - p.y } else { p.y };
    let (u0, u1) = (uv.iter().map(|p| p.x).fold(f32::MAX, f32::min), uv.iter().map(|p| p.x).fold(f32::MIN, f32::max));
    let (v0, v1) =
        (uv.iter().map(|&p| v(p)).fold(f32::MAX, f32::min), uv.iter().map(|&p| v(p)).fold(f32::MIN, f32::max));
    let all = || img.texels.iter().fold(Vec3::ZERO, |m, &c| m.max(c));
    if !(u0.is_finite() && u1.is_finite() && v0.is_finite() && v1.is_finite()) {
        return all();
    }
    let (shift, extra) = match t.filter {
        crate::scene::texture::Filter::Nearest => (0.0, 0),
        crate::scene::texture::Filter::Linear => (0.5, 1),
    };
    let span = |a: f32, b: f32, n: usize| {
        ((a * n as f32 - shift).floor() as i64, (b * n as f32 - shift).floor() as i64 + extra)
    };
    // The texel indices a span reaches once wrapped: clamped, or every index when a
    // repeating span is as long as the image.
    let indices = |(a, b): (i64, i64), n: usize, wrap: Wrap| -> Vec<usize> {
        match wrap {
            Wrap::ClampToEdge => (a.clamp(0, n as i64 - 1)..=b.clamp(0, n as i64 - 1)).map(|i| i as usize).collect(),
            _ if b - a + 1 >= n as i64 => (0..n).collect(),
            _ => (a..=b).map(|i| wrap_index(i, n, wrap)).collect(),
        }
    };
    let (xs, ys) = (indices(span(u0, u1, w), w, t.wrap[0]), indices(span(v0, v1, h), h, t.wrap[1]));
    if xs.len() * ys.len() >= w * h {
        return all();
    }
    let mut m = Vec3::ZERO;
    for &y in &ys {
        for &x in &xs {
            m = m.max(img.texels[y * w + x]);
        }
    }
    m
}
