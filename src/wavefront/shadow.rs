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
    if t.hemisphere {
        for j in 0..q.len() {
            let hit = accel.closest_hit(&q.ray[j], c);
            radiance[q.owner[j] as usize] += q.weight[j] * t.probe_radiance(&q.ray[j], hit.as_ref());
        }
    } else {
        occluded.clear();
        occluded.resize(q.len(), false);
        accel.any_hits_packets(&q.ray, occluded, c);
        for j in 0..q.len() {
            if !occluded[j] {
                radiance[q.owner[j] as usize] += q.weight[j];
            }
        }
    }
}
