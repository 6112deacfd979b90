//! The queues of one wave, structure of arrays: one `Vec` per field, grown once and then
//! reused by every wave a worker thread runs (cleared, never freed), so the steady state
//! allocates nothing. Rays are kept whole (`Ray`) because that is what the intersector's
//! batch interface consumes.

use crate::integrator::Bounce;
use crate::ray::Ray;
use glam::Vec3;

/// Paths in flight: the ray each traces next and the path's state.
#[derive(Clone, Debug, Default)]
pub struct PathQueue {
    pub ray: Vec<Ray>,
    /// Key of the path's random streams ([`crate::sampling::Sampler::path_key`]): with
    /// `depth` this is the path's whole RNG state.
    pub key: Vec<u64>,
    /// The path's sample slot in the wave (pixel = wave pixel `slot / batch`).
    pub slot: Vec<u32>,
    /// Product of BSDF weights so far.
    pub throughput: Vec<Vec3>,
    /// Radiance gathered so far.
    pub radiance: Vec<Vec3>,
    /// Depth of the vertex this ray will hit (0: camera ray).
    pub depth: Vec<u32>,
    /// Set by shade: the path has a continuation ray (before Russian roulette).
    pub alive: Vec<bool>,
    /// What the vertex that sampled `ray` means for the light the ray finds (read only by
    /// kernels with non-diffuse materials).
    pub bounce: Vec<Bounce>,
}

impl PathQueue {
    pub fn len(&self) -> usize {
        self.ray.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ray.is_empty()
    }

    pub fn clear(&mut self) {
        self.truncate(0);
    }

    /// Gives the `n` camera rays (and keys) already in `ray` and `key` a fresh path state:
    /// slots 0..n in order, unit throughput, no radiance, depth 0.
    pub fn start_camera_paths(&mut self, n: usize) {
        debug_assert!(self.ray.len() == n && self.key.len() == n);
        self.slot.clear();
        self.slot.extend(0..n as u32);
        for (v, x) in [(&mut self.throughput, Vec3::ONE), (&mut self.radiance, Vec3::ZERO)] {
            v.clear();
            v.resize(n, x);
        }
        self.depth.clear();
        self.depth.resize(n, 0);
        self.alive.clear();
        self.alive.resize(n, false);
        self.bounce.clear();
        self.bounce.resize(n, Bounce::DELTA);
    }

    pub fn truncate(&mut self, n: usize) {
        self.ray.truncate(n);
        self.key.truncate(n);
        self.slot.truncate(n);
        self.throughput.truncate(n);
        self.radiance.truncate(n);
        self.depth.truncate(n);
        self.alive.truncate(n);
        self.bounce.truncate(n);
    }

    /// A new path at its camera ray.
    #[inline]
    pub fn push_camera(&mut self, ray: Ray, key: u64, slot: u32) {
        self.ray.push(ray);
        self.key.push(key);
        self.slot.push(slot);
        self.throughput.push(Vec3::ONE);
        self.radiance.push(Vec3::ZERO);
        self.depth.push(0);
        self.alive.push(false);
        self.bounce.push(Bounce::DELTA);
    }

    /// Copies entry `from` over entry `to` (compaction, `to < from`).
    #[inline]
    pub fn move_entry(&mut self, from: usize, to: usize) {
        self.ray[to] = self.ray[from];
        self.key[to] = self.key[from];
        self.slot[to] = self.slot[from];
        self.throughput[to] = self.throughput[from];
        self.radiance[to] = self.radiance[from];
        self.depth[to] = self.depth[from];
        // `alive` is not copied: shade sets it for every path before reading it.
        self.bounce[to] = self.bounce[from];
    }
}

/// Shadow rays (or hemisphere probes) of one bounce, in the order shading wrote them.
#[derive(Clone, Debug, Default)]
pub struct ShadowQueue {
    pub ray: Vec<Ray>,
    /// Contribution if unoccluded (throughput applied); a probe's is multiplied by the
    /// emission it sees.
    pub weight: Vec<Vec3>,
    /// Index of the path (in the path queue) the contribution goes to.
    pub owner: Vec<u32>,
}

impl ShadowQueue {
    pub fn len(&self) -> usize {
        self.ray.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ray.is_empty()
    }

    pub fn clear(&mut self) {
        self.ray.clear();
        self.weight.clear();
        self.owner.clear();
    }

    #[inline]
    pub fn push(&mut self, ray: Ray, weight: Vec3, owner: u32) {
        self.ray.push(ray);
        self.weight.push(weight);
        self.owner.push(owner);
    }
}
