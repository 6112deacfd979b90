//! Stage 5: gathers each path's shadow results into its radiance, plays Russian roulette,
//! and packs the surviving paths densely into the next queue; finished paths hand their
//! radiance to their sample slot.

use super::CHUNK;
use super::generate::Wave;
use super::queues::{PathQueue, ShadowQueue};
use crate::integrator::Transport;
use glam::Vec3;
use rayon::prelude::*;

/// Returns the number of surviving paths (now in `next`, whose `len` is set).
pub fn compact(
    t: &Transport,
    wave: &Wave,
    paths: &mut PathQueue,
    next: &mut PathQueue,
    shadow: &ShadowQueue,
    slot_radiance: &mut [Vec3],
) -> usize {
    let n = paths.len;
    let per = t.direct_per_vertex as usize;
    // Gather shadow results and decide who continues, per chunk.
    let counts: Vec<usize> = paths
        .chunks(n, CHUNK)
        .into_par_iter()
        .map(|p| {
            let mut alive = 0;
            for k in 0..p.slot.len() {
                let i = p.start + k;
                let mut l = Vec3::new(p.lr[k], p.lg[k], p.lb[k]);
                for j in i * per..(i + 1) * per {
                    if shadow.tmax[j] >= 0.0 {
                        l += Vec3::new(shadow.wr[j], shadow.wg[j], shadow.wb[j]);
                    }
                }
                (p.lr[k], p.lg[k], p.lb[k]) = (l.x, l.y, l.z);
                if p.alive[k] != 0 {
                    // The continuation was sampled at the vertex one level up.
                    let depth = p.depth[k] - 1;
                    let (pixel, sample) = wave.pixel_sample(p.slot[k]);
                    match t.roulette(depth, t.sampler(pixel, sample, depth)) {
                        Some(f) => {
                            (p.tr[k], p.tg[k], p.tb[k]) = (p.tr[k] * f, p.tg[k] * f, p.tb[k] * f);
                            alive += 1;
                        }
                        None => p.alive[k] = 0,
                    }
                }
            }
            alive
        })
        .collect();
    // Finished paths deliver their radiance (each slot has one path, so order is irrelevant).
    for i in 0..n {
        if paths.alive[i] == 0 {
            slot_radiance[paths.slot[i] as usize] = Vec3::new(paths.lr[i], paths.lg[i], paths.lb[i]);
        }
    }
    // Pack survivors: chunk c of `paths` writes piece c of `next`.
    let total: usize = counts.iter().sum();
    next.ensure(total);
    next.len = total;
    let src: &PathQueue = paths;
    next.split_sizes(&counts).into_par_iter().enumerate().for_each(|(c, out)| {
        let mut o = 0;
        for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
            if src.alive[i] == 0 {
                continue;
            }
            out.ox[o] = src.ox[i];
            out.oy[o] = src.oy[i];
            out.oz[o] = src.oz[i];
            out.dx[o] = src.dx[i];
            out.dy[o] = src.dy[i];
            out.dz[o] = src.dz[i];
            out.tmin[o] = src.tmin[i];
            out.tmax[o] = src.tmax[i];
            out.slot[o] = src.slot[i];
            out.tr[o] = src.tr[i];
            out.tg[o] = src.tg[i];
            out.tb[o] = src.tb[i];
            out.lr[o] = src.lr[i];
            out.lg[o] = src.lg[i];
            out.lb[o] = src.lb[i];
            out.depth[o] = src.depth[i];
            out.alive[o] = 0;
            o += 1;
        }
    });
    total
}
