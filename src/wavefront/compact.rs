//! Stage 5 (the bounce stage, only when paths continue): Russian roulette, then the
//! surviving paths are packed in place at the front of the queue; finished paths hand their
//! radiance to their sample slot.

use super::Features;
use super::queues::PathQueue;
use crate::integrator::Transport;
use glam::Vec3;

pub fn compact<F: Features>(t: &Transport, q: &mut PathQueue, slot_radiance: &mut [Vec3]) {
    let mut o = 0;
    for i in 0..q.len() {
        let mut keep = q.alive[i];
        if F::ROULETTE && keep {
            // The continuation was sampled at the vertex one level up.
            let depth = q.depth[i] - 1;
            match t.roulette(depth, t.vertex_sampler(q.key[i], depth)) {
                Some(f) => q.throughput[i] *= f,
                None => keep = false,
            }
        }
        if keep {
            if o != i {
                q.move_entry(i, o);
            }
            o += 1;
        } else {
            slot_radiance[q.slot[i] as usize] = q.radiance[i];
        }
    }
    q.truncate(o);
}
