use super::{Intersector, TraceCounters, sphere, triangle};
use crate::ray::{Hit, Ray};
use crate::scene::{Scene, Sphere};
use glam::Vec3;

/// Tests every primitive for every ray: the `--no-bvh` reference and timing baseline.
pub struct BruteForce {
    tris: Vec<[Vec3; 3]>,
    spheres: Vec<Sphere>,
}

impl BruteForce {
    pub fn new(scene: &Scene) -> Self {
        let tris = (0..scene.mesh.triangle_count()).map(|i| scene.mesh.corners(i)).collect();
        BruteForce { tris, spheres: scene.spheres.clone() }
    }
}

impl Intersector for BruteForce {
    fn closest_hit(&self, ray: &Ray, counters: &mut TraceCounters) -> Option<Hit> {
        counters.rays += 1;
        counters.prim_tests += (self.tris.len() + self.spheres.len()) as u64;
        let mut r = *ray;
        let mut best = None;
        for (i, [a, b, c]) in self.tris.iter().enumerate() {
            if let Some((t, u, v)) = triangle::intersect(&r, *a, *b, *c) {
                r.tmax = t;
                best = Some(Hit { t, prim: i as u32, u, v });
            }
        }
        let base = self.tris.len() as u32;
        for (i, s) in self.spheres.iter().enumerate() {
            if let Some(t) = sphere::intersect(&r, s.center, s.radius) {
                r.tmax = t;
                best = Some(Hit { t, prim: base + i as u32, u: 0.0, v: 0.0 });
            }
        }
        best
    }

    fn any_hit(&self, ray: &Ray, counters: &mut TraceCounters) -> bool {
        counters.rays += 1;
        for (i, [a, b, c]) in self.tris.iter().enumerate() {
            if triangle::intersect(ray, *a, *b, *c).is_some() {
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
