//! Stage 4: the shadow queue. Light-sampling rays are any-hit tests (an unoccluded ray adds
//! its contribution to its path); hemisphere probes are closest-hit rays whose contribution
//! is multiplied by the emission they see.

use super::queues::ShadowQueue;
use crate::accel::{Intersector, TraceCounters};
use crate::integrator::Transport;
use glam::Vec3;

/// Resolves the shadow queue into the paths' radiance (in queue order, so each path adds
/// its contributions in the order shading made them).
pub fn shadow(
    t: &Transport,
    accel: &dyn Intersector,
    q: &ShadowQueue,
    occluded: &mut Vec<bool>,
    radiance: &mut [Vec3],
    c: &mut TraceCounters,
) {
    if t.rules.hemisphere {
        for ((ray, &owner), &weight) in q.ray().iter().zip(q.owner()).zip(q.weight()) {
            let hit = accel.closest_hit(ray, c);
            radiance[owner as usize] += weight * t.probe_radiance(ray, hit.as_ref());
        }
    } else {
        // Not cleared first: the intersector writes every entry.
        occluded.resize(q.len(), false);
        accel.any_hits_packets(q.ray(), occluded, c);
        for ((&occ, &owner), &weight) in occluded.iter().zip(q.owner()).zip(q.weight()) {
            if !occ {
                radiance[owner as usize] += weight;
            }
        }
    }
}
