//! Stage 3: at every hit, emission, the direct-light rays and the continuation ray.

use super::CHUNK;
use super::generate::Wave;
use super::queues::{HitQueue, PathChunk, PathQueue, ShadowQueue};
use crate::integrator::Transport;
use crate::ray::{Hit, Ray};
use glam::Vec3;
use rayon::prelude::*;

/// Shades every path against its hit: adds emission seen by camera rays, writes each
/// path's block of shadow rays (throughput applied), and replaces the path's ray by its
/// continuation (`alive = 1`) or ends it (`alive = 0`).
pub fn shade(t: &Transport, wave: &Wave, paths: &mut PathQueue, hits: &HitQueue, shadow: &mut ShadowQueue) {
    let n = paths.len;
    let per = t.direct_per_vertex as usize;
    shadow.ensure(n * per);
    shadow.len = n * per;
    let path_chunks = paths.chunks(n, CHUNK);
    let sizes: Vec<usize> = path_chunks.iter().map(|c| c.slot.len() * per).collect();
    let shadow_chunks = shadow.split_sizes(&sizes);
    path_chunks.into_par_iter().zip(shadow_chunks).for_each(|(p, s)| {
        for k in 0..p.slot.len() {
            let i = p.start + k;
            let ray = chunk_ray(&p, k);
            let depth = p.depth[k];
            let throughput = Vec3::new(p.tr[k], p.tg[k], p.tb[k]);
            let mut l = Vec3::new(p.lr[k], p.lg[k], p.lb[k]);
            let block = k * per..(k + 1) * per;
            for j in block.clone() {
                s.tmax[j] = -1.0;
            }
            p.alive[k] = 0;
            let prim = hits.prim[i];
            if prim == u32::MAX {
                if depth == 0 && t.counts_emission() {
                    l += throughput * t.lights.background;
                }
            } else {
                let hit = Hit { t: hits.t[i], prim, u: hits.u[i], v: hits.v[i] };
                let v = t.vertex(&ray, &hit);
                if depth == 0 && t.counts_emission() {
                    l += v.emission;
                }
                let (pixel, sample) = wave.pixel_sample(p.slot[k]);
                let rng = t.sampler(pixel, sample, depth);
                if t.counts_direct(depth) {
                    let mut j = block.start;
                    t.direct_rays(&v, rng, |d| {
                        let w = d.weight * throughput;
                        (s.ox[j], s.oy[j], s.oz[j]) = (d.ray.origin.x, d.ray.origin.y, d.ray.origin.z);
                        (s.dx[j], s.dy[j], s.dz[j]) = (d.ray.dir.x, d.ray.dir.y, d.ray.dir.z);
                        s.tmax[j] = d.ray.tmax;
                        (s.wr[j], s.wg[j], s.wb[j]) = (w.x, w.y, w.z);
                        j += 1;
                    });
                }
                if let Some((next, w)) = t.scatter(&v, depth, rng) {
                    let tp = throughput * w;
                    (p.ox[k], p.oy[k], p.oz[k]) = (next.origin.x, next.origin.y, next.origin.z);
                    (p.dx[k], p.dy[k], p.dz[k]) = (next.dir.x, next.dir.y, next.dir.z);
                    (p.tmin[k], p.tmax[k]) = (next.tmin, next.tmax);
                    (p.tr[k], p.tg[k], p.tb[k]) = (tp.x, tp.y, tp.z);
                    p.depth[k] = depth + 1;
                    p.alive[k] = 1;
                }
            }
            (p.lr[k], p.lg[k], p.lb[k]) = (l.x, l.y, l.z);
        }
    });
}

#[inline]
fn chunk_ray(p: &PathChunk, k: usize) -> Ray {
    Ray {
        origin: Vec3::new(p.ox[k], p.oy[k], p.oz[k]),
        dir: Vec3::new(p.dx[k], p.dy[k], p.dz[k]),
        tmin: p.tmin[k],
        tmax: p.tmax[k],
    }
}
