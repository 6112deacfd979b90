use super::cutout::Cutouts;
use super::triangle::{ShearedRay, intersect_sheared};
use super::{Intersector, TraceCounters, sphere};
use crate::geometry::{Hit, Ray};
use crate::scene::{Scene, Sphere};
use glam::Vec3;

/// Tests every primitive for every ray: the `--no-bvh` reference and timing baseline.
///
/// Uses the same watertight triangle test and the same rule for exact ties (the smaller
/// primitive id wins) and the same alpha test as the BVH, so both return identical hits.
pub struct BruteForce {
    tris: Vec<[Vec3; 3]>,
    spheres: Vec<Sphere>,
    cutouts: Option<Cutouts>,
}

impl BruteForce {
    pub fn new(scene: &Scene) -> Self {
        let tris = (0..scene.mesh.triangle_count()).map(|i| scene.mesh.corners(i)).collect();
        BruteForce { tris, spheres: scene.spheres.clone(), cutouts: Cutouts::of(scene) }
    }
}

fn valid(ray: &Ray) -> bool {
    !(ray.tmin.is_nan() || ray.tmax.is_nan() || ray.tmin > ray.tmax)
}

impl BruteForce {
    /// Whether a hit on triangle `i` at barycentrics (`u`, `v`) counts (its alpha test).
    fn keeps(&self, i: usize, u: f32, v: f32, ray: &Ray) -> bool {
        self.cutouts.as_ref().is_none_or(|c| c.keeps(i as u32, u, v, ray))
    }
}

impl Intersector for BruteForce {
    fn closest_hit(&self, ray: &Ray, counters: &mut TraceCounters) -> Option<Hit> {
        counters.rays += 1;
        counters.prim_tests += (self.tris.len() + self.spheres.len()) as u64;
        let sr = ShearedRay::new(ray).filter(|_| valid(ray))?;
        let mut best: Option<Hit> = None;
        for (i, [a, b, c]) in self.tris.iter().enumerate() {
            let tmax = best.map_or(ray.tmax, |h| h.t);
            // Ascending ids: on an exact tie the earlier (smaller) id is kept.
            if let Some((t, u, v)) = intersect_sheared(&sr, ray.tmin, tmax, *a, *b, *c)
                && best.is_none_or(|h| t < h.t)
                && self.keeps(i, u, v, ray)
            {
                best = Some(Hit { t, prim: i as u32, u, v });
            }
        }
        let base = self.tris.len() as u32;
        for (i, s) in self.spheres.iter().enumerate() {
            let r = Ray { tmax: best.map_or(ray.tmax, |h| h.t), ..*ray };
            if let Some(t) = sphere::intersect(&r, s.center, s.radius)
                && best.is_none_or(|h| t < h.t)
            {
                best = Some(Hit { t, prim: base + i as u32, u: 0.0, v: 0.0 });
            }
        }
        best
    }

    fn any_hit(&self, ray: &Ray, counters: &mut TraceCounters) -> bool {
        counters.rays += 1;
        let Some(sr) = ShearedRay::new(ray).filter(|_| valid(ray)) else { return false };
        for (i, [a, b, c]) in self.tris.iter().enumerate() {
            if let Some((_, u, v)) = intersect_sheared(&sr, ray.tmin, ray.tmax, *a, *b, *c)
                && self.keeps(i, u, v, ray)
            {
                counters.prim_tests += i as u64 + 1;
                return true;
            }
        }
        counters.prim_tests += self.tris.len() as u64;
        for (i, s) in self.spheres.iter().enumerate() {
            if sphere::intersect(ray, s.center, s.radius).is_some() {
                counters.prim_tests += i as u64 + 1;
                return true;
            }
        }
        counters.prim_tests += self.spheres.len() as u64;
        false
    }

    fn name(&self) -> String {
        "brute force".into()
    }
}
