//! Stage 5 (the bounce stage, only when paths continue): the surviving paths (shade has
//! already played Russian roulette) are packed in place at the front of the queue; finished
//! paths hand their radiance to their sample slot. A path whose ray leaves its last vertex
//! and can find no light ([`Transport::traces`]) finishes here, untraced.

use super::queues::PathQueue;
use crate::integrator::Transport;
use glam::Vec3;

pub fn compact(t: &Transport, q: &mut PathQueue, slot_radiance: &mut [Vec3]) {
    let mut o = 0;
    for i in 0..q.len() {
        if q.alive[i] && t.traces(&q.ray[i], q.depth[i]) {
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
