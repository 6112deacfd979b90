//! Stage 4: the shadow queue. Light-sampling rays are any-hit tests (an occluded ray's
//! contribution becomes zero); hemisphere probes are closest-hit rays whose contribution is
//! multiplied by the emission they see.

use super::CHUNK;
use super::queues::ShadowQueue;
use crate::accel::{Intersector, TraceCounters};
use crate::integrator::Transport;
use crate::ray::{Hit, Ray};
use glam::Vec3;
use rayon::prelude::*;

/// Resolves every used entry of the shadow queue; returns the work counters and the number
/// of rays traced.
pub fn shadow(t: &Transport, accel: &dyn Intersector, q: &mut ShadowQueue) -> (TraceCounters, u64) {
    let n = q.len;
    q.chunks(n, CHUNK)
        .into_par_iter()
        .map(|c| {
            let mut counters = TraceCounters::default();
            let mut rays = [Ray::new(Vec3::ZERO, Vec3::ZERO); CHUNK];
            let mut index = [0usize; CHUNK];
            let mut m = 0;
            for k in 0..c.tmax.len() {
                if c.tmax[k] >= 0.0 {
                    rays[m] = Ray {
                        origin: Vec3::new(c.ox[k], c.oy[k], c.oz[k]),
                        dir: Vec3::new(c.dx[k], c.dy[k], c.dz[k]),
                        tmin: 0.0,
                        tmax: c.tmax[k],
                    };
                    index[m] = k;
                    m += 1;
                }
            }
            if t.hemisphere {
                let mut found: [Option<Hit>; CHUNK] = [None; CHUNK];
                accel.closest_hits(&rays[..m], &mut found[..m], &mut counters);
                for j in 0..m {
                    let k = index[j];
                    let e = t.probe_radiance(&rays[j], found[j].as_ref());
                    (c.wr[k], c.wg[k], c.wb[k]) = (c.wr[k] * e.x, c.wg[k] * e.y, c.wb[k] * e.z);
                }
            } else {
                for j in 0..m {
                    if accel.any_hit(&rays[j], &mut counters) {
                        let k = index[j];
                        (c.wr[k], c.wg[k], c.wb[k]) = (0.0, 0.0, 0.0);
                    }
                }
            }
            (counters, m as u64)
        })
        .reduce(
            || (TraceCounters::default(), 0),
            |(mut a, x), (b, y)| {
                a.add(&b);
                (a, x + y)
            },
        )
}
