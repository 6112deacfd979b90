//! The queues of one wave, structure of arrays: one `Vec` per field, grown once and then
//! reused by every wave a worker thread runs (cleared, never freed), so the steady state
//! allocates nothing. Rays are kept whole (`Ray`) because that is what the intersector's
//! batch interface consumes.

use crate::geometry::Ray;
use crate::integrator::Bounce;
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
///
/// The arrays keep the largest length any bounce needed (entries past [`len`](Self::len)
/// are stale): a writer gets room with [`open`](Self::open) without filling it first, and
/// one capacity check per batch instead of three per ray.
#[derive(Clone, Debug, Default)]
pub struct ShadowQueue {
    ray: Vec<Ray>,
    /// Contribution if unoccluded (throughput applied); a probe's is multiplied by the
    /// emission it sees.
    weight: Vec<Vec3>,
    /// Index of the path (in the path queue) the contribution goes to.
    owner: Vec<u32>,
    len: usize,
}

impl ShadowQueue {
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn clear(&mut self) {
        self.len = 0;
    }

    pub fn ray(&self) -> &[Ray] {
        &self.ray[..self.len]
    }

    pub fn weight(&self) -> &[Vec3] {
        &self.weight[..self.len]
    }

    pub fn owner(&self) -> &[u32] {
        &self.owner[..self.len]
    }

    #[inline]
    pub fn push(&mut self, ray: Ray, weight: Vec3, owner: u32) {
        let (r, w, o) = self.open(1);
        (r[0], w[0], o[0]) = (ray, weight, owner);
        self.commit(1);
    }

    /// Room for `extra` entries after the current ones (stale contents), for a writer that
    /// fills them in order and then [`commit`](Self::commit)s how many it wrote: it can store
    /// every candidate and move on past the valid ones only, with no branch per ray.
    #[inline]
    pub fn open(&mut self, extra: usize) -> (&mut [Ray], &mut [Vec3], &mut [u32]) {
        let (start, end) = (self.len, self.len + extra);
        if self.ray.len() < end {
            self.grow(end);
        }
        (&mut self.ray[start..end], &mut self.weight[start..end], &mut self.owner[start..end])
    }

    /// The first `n` entries after the current ones (written after [`open`](Self::open))
    /// join the queue.
    #[inline]
    pub fn commit(&mut self, n: usize) {
        self.len += n;
        debug_assert!(self.len <= self.ray.len());
    }

    #[cold]
    fn grow(&mut self, end: usize) {
        // At least doubled, so a queue filled by single pushes grows in amortised O(1).
        let end = end.max(2 * self.ray.len());
        let zero = Ray { origin: Vec3::ZERO, dir: Vec3::ZERO, tmin: 0.0, tmax: 0.0 };
        self.ray.resize(end, zero);
        self.weight.resize(end, Vec3::ZERO);
        self.owner.resize(end, 0);
    }
}
