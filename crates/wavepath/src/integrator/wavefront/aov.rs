//! The output variables' stage (only in renders that keep first-hit AOVs): after each
//! traverse, every path whose camera sample has not yet recorded its first hit records it, by
//! the rule of [`crate::film::AovSample`]'s module: depth and position at the camera ray's
//! hit, albedo and normal at the first hit that is not a delta surface, the background seen
//! by a ray that escapes. A path goes on through a mirror or glass along its own
//! continuation, so the record needs no ray of its own.

use super::queues::PathQueue;
use crate::film::AovSample;
use crate::integrator::Transport;
use glam::Vec3;

/// Each sample slot's record of one wave and whether it still waits for its first
/// non-delta hit.
#[derive(Default)]
pub struct AovRecords {
    pub samples: Vec<AovSample>,
    pending: Vec<bool>,
}

impl AovRecords {
    /// Empty records for a wave of `n` samples.
    pub fn start(&mut self, n: usize) {
        self.samples.clear();
        self.samples.resize(n, AovSample::default());
        self.pending.clear();
        self.pending.resize(n, true);
    }
}

/// Records the first hits the paths of `q` have just found (their `hit`, written by traverse).
pub fn record(t: &Transport, q: &PathQueue, r: &mut AovRecords) {
    for i in 0..q.len() {
        let slot = q.slot[i] as usize;
        if !r.pending[slot] {
            continue;
        }
        let (ray, s) = (&q.ray[i], &mut r.samples[slot]);
        let Some(hit) = q.hit[i] else {
            let seen = if t.rules.features.environment { t.lights.set.background_toward(ray.dir) } else { Vec3::ZERO };
            s.albedo = if seen.is_finite() { seen.clamp(Vec3::ZERO, Vec3::ONE) } else { Vec3::ZERO };
            r.pending[slot] = false;
            continue;
        };
        let v = t.vertex(ray, &hit);
        if q.depth[i] == 0 {
            s.hit = true;
            s.position = v.p;
            s.depth = hit.t * ray.dir.length();
        }
        if let Some(albedo) = t.model_at(&v).albedo_estimate() {
            s.albedo = albedo;
            s.normal = v.ns;
            r.pending[slot] = false;
        }
    }
}
