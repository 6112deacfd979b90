//! Stage 3: at every hit, emission, the direct-light rays and the continuation ray.

use super::Features;
use super::Lanes;
use super::queues::{PathQueue, ShadowEntry, ShadowQueue};
use crate::integrator::Transport;
use crate::sampling::Sampler;
use glam::Vec3;

/// Shades every path against its hit: adds emission (and the environment) seen by camera
/// rays, appends the path's shadow rays (throughput applied), and replaces the path's ray by
/// its continuation (`alive`, after Russian roulette) or ends it. Parts whose effect `F`
/// leaves out are not compiled in.
///
/// The paths are first sorted by what shades them ([`Kinds`], pbrt-v4's queues after
/// intersection): the Lambertian hits are shaded in lanes by [`super::lanes`] where the
/// render's [`Lanes`] has a lane width, the rest (escaped paths, other materials) one at a
/// time. Each path's shadow rays stay in the order it made them, so its radiance is the same
/// bits whatever the grouping.
pub fn shade<F: Features>(t: &Transport, lanes: Lanes, q: &mut PathQueue, shadow: &mut ShadowQueue, kinds: &mut Kinds) {
    if lanes.shade.is_none() {
        return shade_scalar::<F>(t, q, shadow);
    }
    shadow.clear();
    kinds.sort::<F>(t, q);
    for &i in &kinds.one_at_a_time {
        shade_path::<F>(t, q, i as usize, shadow);
    }
    super::lanes::shade_diffuse::<F>(lanes, t, q, &kinds.diffuse, shadow);
}

/// A wave's paths by what shades them, as index lists into the path queue.
#[derive(Default)]
pub struct Kinds {
    /// Paths whose hit has a Lambertian material: the lane kernel's.
    pub diffuse: Vec<u32>,
    /// Escaped paths and hits on every other material: one path at a time.
    pub one_at_a_time: Vec<u32>,
}

impl Kinds {
    fn sort<F: Features>(&mut self, t: &Transport, q: &PathQueue) {
        self.diffuse.clear();
        self.one_at_a_time.clear();
        for (i, hit) in q.hit.iter().enumerate() {
            let lane = match hit {
                None => false,
                Some(h) => !F::NON_DIFFUSE || t.lambertian[t.material_of(h.prim)],
            };
            if lane { &mut self.diffuse } else { &mut self.one_at_a_time }.push(i as u32);
        }
    }
}

/// [`shade`] one path at a time (any features; the reference for the lane kernel).
pub fn shade_scalar<F: Features>(t: &Transport, q: &mut PathQueue, shadow: &mut ShadowQueue) {
    shadow.clear();
    for i in 0..q.len() {
        shade_path::<F>(t, q, i, shadow);
    }
}

/// Shades path `i` (see [`shade`]).
#[inline]
pub fn shade_path<F: Features>(t: &Transport, q: &mut PathQueue, i: usize, shadow: &mut ShadowQueue) {
    let sees_emission = t.counts_emission();
    {
        let depth = q.depth[i];
        q.alive[i] = false;
        let Some(hit) = q.hit[i] else {
            if F::ENVIRONMENT && depth == 0 && sees_emission {
                q.radiance[i] += q.throughput[i] * t.lights.background_toward(q.ray[i].dir);
            }
            if (F::NON_DIFFUSE || t.mis) && depth > 0 {
                q.radiance[i] += q.throughput[i] * t.arrival(q.bounce[i], &q.ray[i], None, Vec3::ZERO, depth);
            }
            return;
        };
        let v = t.vertex(&q.ray[i], &hit);
        if F::NON_DIFFUSE && t.layers.volumes {
            q.throughput[i] *= t.layers.absorbed(&v, hit.t);
        }
        if F::EMISSION && depth == 0 && sees_emission {
            q.radiance[i] += v.emission;
        }
        if (F::NON_DIFFUSE || t.mis) && depth > 0 {
            q.radiance[i] += q.throughput[i] * t.arrival(q.bounce[i], &q.ray[i], Some(&hit), v.emission, depth);
        }
        if !F::DIRECT && !F::INDIRECT {
            return;
        }
        let rng = t.vertex_sampler(q.key[i], depth);
        if F::NON_DIFFUSE {
            let sh = t.shading(&v, q.ray[i].dir);
            if F::DIRECT && t.counts_direct(depth) {
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
            return;
        }
        if F::DIRECT && t.counts_direct(depth) {
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
        match t.roulette(depth, rng, q.throughput[i]) {
            Some(f) => q.throughput[i] *= f,
            None => q.alive[i] = false,
        }
    }
}
