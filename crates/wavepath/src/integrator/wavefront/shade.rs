//! Stage 3: at every hit, emission, the direct-light rays and the continuation ray.

use super::Features;
use super::queues::{PathQueue, ShadowEntry, ShadowQueue};
use crate::cpu::Avx2;
use crate::integrator::Transport;
use crate::sampling::Sampler;
use glam::Vec3;

/// Shades every path against its hit: adds emission (and the environment) seen by camera
/// rays, appends the path's shadow rays (throughput applied), and replaces the path's ray by
/// its continuation (`alive`, after Russian roulette) or ends it. Parts whose effect `F` leaves out are not compiled in.
/// `lanes`: the token of the eight-path kernel when this render uses it (`super::Lanes`).
pub fn shade<F: Features>(t: &Transport, lanes: Option<Avx2>, q: &mut PathQueue, shadow: &mut ShadowQueue) {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx) = lanes {
        super::lanes::shade_lanes::<F>(avx, t, q, shadow);
        return;
    }
    let _ = lanes;
    shade_scalar::<F>(t, q, shadow);
}

/// [`shade`] one path at a time (any features; the reference for the lane kernel).
pub fn shade_scalar<F: Features>(t: &Transport, q: &mut PathQueue, shadow: &mut ShadowQueue) {
    shadow.clear();
    let sees_emission = t.rules.counts_emission();
    for i in 0..q.len() {
        let depth = q.depth[i];
        q.alive[i] = false;
        let Some(hit) = q.hit[i] else {
            if F::ENVIRONMENT && depth == 0 && sees_emission {
                q.radiance[i] += q.throughput[i] * t.lights.set.background_toward(q.ray[i].dir);
            }
            if (F::NON_DIFFUSE || t.rules.mis) && depth > 0 {
                q.radiance[i] += q.throughput[i] * t.arrival(q.bounce[i], &q.ray[i], None, Vec3::ZERO, depth);
            }
            continue;
        };
        let v = t.vertex(&q.ray[i], &hit);
        if F::NON_DIFFUSE && t.materials.layers.volumes {
            q.throughput[i] *= t.materials.layers.absorbed(&v, hit.t);
        }
        if F::EMISSION && depth == 0 && sees_emission {
            q.radiance[i] += v.emission;
        }
        if (F::NON_DIFFUSE || t.rules.mis) && depth > 0 {
            q.radiance[i] += q.throughput[i] * t.arrival(q.bounce[i], &q.ray[i], Some(&hit), v.emission, depth);
        }
        if !F::DIRECT && !F::INDIRECT {
            continue;
        }
        let rng = t.streams.vertex_sampler(q.key[i], depth);
        if F::NON_DIFFUSE {
            let sh = t.shading(&v, q.ray[i].dir);
            if F::DIRECT && t.rules.counts_direct(depth) {
                let tp = q.throughput[i];
                t.direct_rays_shaded(&v, &sh, depth, rng, |d| {
                    shadow.push(ShadowEntry { ray: d.ray, weight: d.weight * tp, owner: i as u32 })
                });
            }
            if F::INDIRECT
                && let Some((next, w, bounce)) = t.scatter_shaded(&v, &sh, depth, rng)
            {
                q.ray[i] = next;
                q.throughput[i] *= w;
                q.depth[i] = depth + 1;
                q.alive[i] = true;
                q.bounce[i] = bounce;
                roulette::<F>(t, q, i, depth, rng);
            }
            continue;
        }
        if F::DIRECT && t.rules.counts_direct(depth) {
            let tp = q.throughput[i];
            t.direct_rays(&v, depth, rng, |d| {
                shadow.push(ShadowEntry { ray: d.ray, weight: d.weight * tp, owner: i as u32 })
            });
        }
        if F::INDIRECT
            && let Some((next, w, bounce)) = t.scatter(&v, depth, rng)
        {
            q.ray[i] = next;
            q.throughput[i] *= w;
            q.depth[i] = depth + 1;
            q.alive[i] = true;
            q.bounce[i] = bounce;
            roulette::<F>(t, q, i, depth, rng);
        }
    }
}

/// Russian roulette for path `i`'s new continuation, here where the vertex's stream is at
/// hand (the bounce stage would have to derive it again), applied after the BSDF weight as
/// [`Transport::continuation`] does; the shadow rays already took the throughput before it.
#[inline(always)]
pub(super) fn roulette<F: Features>(t: &Transport, q: &mut PathQueue, i: usize, depth: u32, rng: Sampler) {
    if F::ROULETTE {
        match t.rules.roulette(depth, rng, q.throughput[i]) {
            Some(f) => q.throughput[i] *= f,
            None => q.alive[i] = false,
        }
    }
}
