use super::{LightSample, area_to_solid_angle};
use crate::geometry::error_bound::gamma;
use crate::sampling::warp;
use crate::scene::Scene;
use glam::Vec3;

/// All emissive triangles of a mesh as one light, a triangle chosen in proportion to its
/// area. Emission is two-sided, as the reference's emission BSDF is.
#[derive(Clone, Debug)]
pub struct EmissiveTriangles {
    /// Corner 0 and the two edges from it.
    corners: Vec<[Vec3; 3]>,
    emission: Vec<Vec3>,
    /// Running sum of areas (the last entry is the total).
    cdf: Vec<f32>,
    /// Largest error bound of a sampled point over all triangles (see
    /// [`point_error`](Self::point_error)).
    max_error: Vec3,
}

impl EmissiveTriangles {
    pub fn new(scene: &Scene) -> Option<Self> {
        let mut corners = Vec::new();
        let mut emission = Vec::new();
        let mut cdf = Vec::new();
        let mut total = 0.0f32;
        let mut max_error = Vec3::ZERO;
        for (i, &m) in scene.mesh.material_ids.iter().enumerate() {
            let mat = &scene.materials[m as usize];
            if !mat.is_emissive() {
                continue;
            }
            let [a, b, c] = scene.mesh.corners(i);
            let area = 0.5 * (b - a).cross(c - a).length();
            if area > 0.0 && area.is_finite() {
                total += area;
                let (e1, e2) = (b - a, c - a);
                // a + bu e1 + bv e2 with bu, bv in [0, 1]: two products and two sums, plus
                // the rounding of the edges themselves (up to eps |e|, scaled by bu, bv <= 1).
                max_error = max_error.max(gamma(4) * (a.abs() + e1.abs() + e2.abs()));
                corners.push([a, e1, e2]);
                emission.push(mat.emission);
                cdf.push(total);
            }
        }
        (total > 0.0).then_some(EmissiveTriangles { corners, emission, cdf, max_error })
    }

    /// Per-component bound on the distance of any sampled point from its triangle: one
    /// bound for all triangles (the largest), since a light sample does not say which
    /// triangle it came from; it only shortens shadow rays by a few ulps of the largest
    /// emitter's coordinates.
    pub fn point_error(&self) -> Vec3 {
        self.max_error
    }

    pub fn total_area(&self) -> f32 {
        *self.cdf.last().unwrap_or(&0.0)
    }

    pub fn len(&self) -> usize {
        self.corners.len()
    }

    pub fn is_empty(&self) -> bool {
        self.corners.is_empty()
    }

    #[inline]
    pub fn sample(&self, p: Vec3, u: [f32; 3]) -> Option<LightSample> {
        self.sample_pdf(p, u).map(|(ls, _)| ls)
    }

    /// [`sample`](Self::sample) and the solid-angle density of the drawn direction.
    #[inline]
    pub fn sample_pdf(&self, p: Vec3, u: [f32; 3]) -> Option<(LightSample, f32)> {
        let total = self.total_area();
        let x = u[2] * total;
        let i = self.cdf.partition_point(|&c| c <= x).min(self.cdf.len() - 1);
        let [a, e1, e2] = self.corners[i];
        let (bu, bv) = warp::uniform_triangle(u[0], u[1]);
        let q = a + bu * e1 + bv * e2;
        let n = e1.cross(e2).try_normalize()?;
        // Area density 1/total; emission is two-sided.
        let (wi, inv_pdf) = area_to_solid_angle(p, q, n, total, false)?;
        Some((LightSample { wi, target: Some(q), weight: self.emission[i] * inv_pdf }, 1.0 / inv_pdf))
    }
}
