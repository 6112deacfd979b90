//! Ray–scene intersection behind one interface, so that the brute-force loop and the BVH
//! are interchangeable for every caller (camera rays, shading, ray files).

mod brute;
pub mod bvh;
pub mod cutout;
pub mod sphere;
pub mod triangle;

pub use brute::BruteForce;
pub use bvh::Bvh;
#[cfg(test)]
pub use bvh::{BvhBuild, BvhOptions, LeafLayout};

use crate::geometry::{Hit, Ray};

/// Work counters for one thread, merged into the render statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceCounters {
    /// Rays traced (closest-hit and any-hit).
    pub rays: u64,
    /// Ray–primitive intersection tests.
    pub prim_tests: u64,
    /// Acceleration-structure nodes visited; a packet's visit counts once (one test for all of
    /// its rays), so coherent rays report fewer nodes per ray than they would alone.
    pub nodes: u64,
}

impl TraceCounters {
    pub fn add(&mut self, o: &TraceCounters) {
        self.rays += o.rays;
        self.prim_tests += o.prim_tests;
        self.nodes += o.nodes;
    }
}

/// Closest-hit and any-hit queries over a fixed scene.
pub trait Intersector: Sync + Send {
    /// The nearest hit with `t` in `[ray.tmin, ray.tmax]`, if any.
    fn closest_hit(&self, ray: &Ray, counters: &mut TraceCounters) -> Option<Hit>;
    /// Whether anything is hit with `t` in `[ray.tmin, ray.tmax]` (shadow rays; may stop early).
    fn any_hit(&self, ray: &Ray, counters: &mut TraceCounters) -> bool;
    /// Short name for logs ("brute force", "bvh8 avx2, sah build", ...).
    fn name(&self) -> String;

    /// Closest hits for a whole queue of rays; accelerators override this to exploit the
    /// batch (ordering, SIMD over rays).
    fn closest_hits(&self, rays: &[Ray], hits: &mut [Option<Hit>], counters: &mut TraceCounters) {
        for (r, h) in rays.iter().zip(hits.iter_mut()) {
            *h = self.closest_hit(r, counters);
        }
    }

    /// Any-hit for a whole queue of shadow rays (`occluded[i]`: ray i hits something).
    fn any_hits(&self, rays: &[Ray], occluded: &mut [bool], counters: &mut TraceCounters) {
        for (r, o) in rays.iter().zip(occluded.iter_mut()) {
            *o = self.any_hit(r, counters);
        }
    }

    /// [`Intersector::any_hits`] for a queue in which the shadow rays of one point (same
    /// origin) sit next to one another: accelerators may trace each such run as a packet.
    /// The results are exactly those of `any_hits`.
    fn any_hits_packets(&self, rays: &[Ray], occluded: &mut [bool], counters: &mut TraceCounters) {
        self.any_hits(rays, occluded, counters)
    }
}

/// How the acceleration structure turned out (zeros for brute force).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct BuildInfo {
    /// How the tree was built (`--bvh-build`: "sah" or "fast"; empty for brute force).
    pub method: &'static str,
    pub build_s: f64,
    pub nodes: usize,
    /// Leaf blocks (each holds at most four primitives).
    pub leaves: usize,
    pub depth: usize,
    pub sah_cost: f64,
    /// Resident bytes of the inner nodes and of the leaf blocks: with the mesh, what a
    /// render keeps in memory.
    pub node_bytes: usize,
    pub leaf_bytes: usize,
}

/// Builds the intersector the settings ask for: the BVH (built and stored as `s.bvh` says, box tests
/// of at most `s.isa`), or brute force for `--no-bvh`.
pub fn build(scene: &crate::scene::Scene, s: &crate::settings::Settings) -> (Box<dyn Intersector>, BuildInfo) {
    if s.accel.use_bvh {
        let bvh = Bvh::build_with(scene, s.accel.bvh).with_isa(s.execution.isa);
        let info = bvh.info();
        return (Box::new(bvh), info);
    }
    let start = std::time::Instant::now();
    let accel = BruteForce::new(scene);
    let info = BuildInfo { build_s: start.elapsed().as_secs_f64(), ..BuildInfo::default() };
    (Box::new(accel), info)
}
