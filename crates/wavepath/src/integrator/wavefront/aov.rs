//! The output variables' stage (only in renders that keep first-hit AOVs): after each
//! traverse, every path whose camera sample has not yet recorded its first hit records it, by
//! the rule of [`crate::film::AovSample`]'s module: depth and position at the camera ray's
//! hit, albedo and normal at the first hit that is not a delta surface, the background seen
//! by a ray that escapes. A path goes on through a mirror or glass along its own
//! continuation, so the record needs no ray of its own.
//!
//! Where shade reconstructs a group's points in lanes (`aov_hits_in_lanes` in the frame loop), the hits are recorded
//! there, from those points (`lanes::hits`' gather, [`AovRecords::record_hit`]); this stage
//! then records only escaped rays. Otherwise it records every hit from its whole vertex, the
//! same numbers: the lanes' points are `Transport::vertex`'s, field for field.

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

impl AovRecords {
    /// Whether slot `slot` still waits for its first non-delta hit.
    #[inline(always)]
    pub fn pending(&self, slot: usize) -> bool {
        self.pending[slot]
    }

    /// Slot `slot`'s path, at `depth`, hit the point `p` (shading normal `ns`) at distance
    /// `t` along a ray of direction `dir`; `albedo` is the model's estimate there, `None` for a
    /// delta surface (the slot then waits for the next hit).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn record_hit(&mut self, slot: usize, depth: u32, t: f32, dir: Vec3, p: Vec3, ns: Vec3, albedo: Option<Vec3>) {
        let s = &mut self.samples[slot];
        if depth == 0 {
            s.hit = true;
            s.position = p;
            s.depth = t * dir.length();
        }
        if let Some(albedo) = albedo {
            s.albedo = albedo;
            s.normal = ns;
            self.pending[slot] = false;
        }
    }
}

/// Records the first hits the paths of `q` have just found (their `hit`, written by traverse);
/// with `hits_in_lanes` (shade records the hits) only the escaped rays.
pub fn record(t: &Transport, q: &PathQueue, r: &mut AovRecords, hits_in_lanes: bool) {
    for i in 0..q.len() {
        let slot = q.slot[i] as usize;
        if !r.pending[slot] || (hits_in_lanes && q.hit[i].is_some()) {
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
        let albedo = t.model_at(&v).albedo_estimate();
        r.record_hit(slot, q.depth[i], hit.t, ray.dir, v.p, v.ns, albedo);
    }
}
