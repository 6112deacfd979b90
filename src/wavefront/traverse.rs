//! Stage 2: the closest hit of every ray in the path queue.

use super::CHUNK;
use super::queues::{HitQueue, PathQueue};
use crate::accel::{Intersector, TraceCounters};
use crate::ray::{Hit, Ray};
use glam::Vec3;
use rayon::prelude::*;

/// The ray of entry `i` of the path queue.
#[inline]
pub fn path_ray(q: &PathQueue, i: usize) -> Ray {
    Ray {
        origin: Vec3::new(q.ox[i], q.oy[i], q.oz[i]),
        dir: Vec3::new(q.dx[i], q.dy[i], q.dz[i]),
        tmin: q.tmin[i],
        tmax: q.tmax[i],
    }
}

/// Traces the path queue in chunks through `Intersector::closest_hits`, writing the hit queue.
pub fn traverse(accel: &dyn Intersector, paths: &PathQueue, hits: &mut HitQueue) -> TraceCounters {
    let n = paths.len;
    hits.ensure(n);
    hits.len = n;
    hits.chunks(n, CHUNK)
        .into_par_iter()
        .map(|c| {
            let mut counters = TraceCounters::default();
            let m = c.t.len();
            let mut rays = [Ray::new(Vec3::ZERO, Vec3::ZERO); CHUNK];
            let mut found: [Option<Hit>; CHUNK] = [None; CHUNK];
            for (k, r) in rays.iter_mut().enumerate().take(m) {
                *r = path_ray(paths, c.start + k);
            }
            accel.closest_hits(&rays[..m], &mut found[..m], &mut counters);
            for (k, h) in found.iter().enumerate().take(m) {
                match h {
                    Some(h) => (c.t[k], c.prim[k], c.u[k], c.v[k]) = (h.t, h.prim, h.u, h.v),
                    None => (c.t[k], c.prim[k]) = (f32::INFINITY, u32::MAX),
                }
            }
            counters
        })
        .reduce(TraceCounters::default, |mut a, b| {
            a.add(&b);
            a
        })
}
