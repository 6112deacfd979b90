//! What every kernel, one path or lanes, does per path: arrival ([`arrive`], [`arrive_at_hit`]:
//! emission seen, the light its ray found, the vertex) and the end of leaving a vertex
//! ([`go_on`]: the continuation and Russian roulette). Leaving itself (light samples, MIS,
//! the continuation's sample) is the lane kernels' `lanes::leave`, which the one-path code
//! runs at one lane.

use super::queues::PathQueue;
use crate::geometry::{Hit, Ray};
use crate::integrator::{Bounce, Transport, Vertex};
use glam::{Vec2, Vec3};

/// Path `i` arrives: `alive` cleared, emission and the light its ray found added; the vertex
/// to leave from, `None` when the path ends here (escaped, or nothing is sent on).
#[inline(always)]
pub fn arrive(t: &Transport, q: &mut PathQueue, i: usize) -> Option<Vertex> {
    arrive_as::<true>(t, q, i).map(|a| a.vertex)
}

/// What a path that goes on from its hit leaves for the lanes: its material and the emission
/// seen, and (from [`arrive_as`] with `WHOLE`) its vertex.
pub struct Arrival {
    pub material: usize,
    pub emission: Vec3,
    pub vertex: Vertex,
}

/// [`arrive`]; without `WHOLE` the vertex is left out ([`NO_VERTEX`]) and the
/// hit's material and emission are found without it, for kernels that reconstruct a group's
/// vertices in lanes (surfaces with no textures, colours, relief or volumes:
/// `lanes::soa::whole_vertices` false; the emission is then the vertex's).
#[inline(always)]
pub fn arrive_as<const WHOLE: bool>(t: &Transport, q: &mut PathQueue, i: usize) -> Option<Arrival> {
    let sees_emission = t.rules.counts_emission();
    let depth = q.depth[i];
    q.alive[i] = false;
    let Some(hit) = q.hit[i] else {
        if t.rules.features.environment && depth == 0 && sees_emission {
            q.radiance[i] += q.throughput[i] * t.lights.set.background_toward(q.ray[i].dir);
        }
        if (t.rules.features.non_diffuse || t.rules.mis) && depth > 0 {
            q.radiance[i] += q.throughput[i] * t.arrival(q.bounce[i], &q.ray[i], None, Vec3::ZERO, depth);
        }
        return None;
    };
    Some(arrive_at_hit::<WHOLE>(t, q, i, hit)).filter(|_| t.rules.features.direct || t.rules.features.indirect)
}

/// [`arrive_as`] for a path whose ray hit `hit`: the one arrival step of every kernel at a
/// hit, returned whether or not the path goes on.
#[inline(always)]
pub fn arrive_at_hit<const WHOLE: bool>(t: &Transport, q: &mut PathQueue, i: usize, hit: Hit) -> Arrival {
    let depth = q.depth[i];
    q.alive[i] = false;
    let (material, emission, vertex) = if WHOLE {
        let v = t.vertex(&q.ray[i], &hit);
        if t.rules.features.non_diffuse && t.materials.layers.volumes {
            q.throughput[i] *= t.materials.layers.absorbed(&v, hit.t);
        }
        (v.material as usize, v.emission, v)
    } else {
        let m = t.materials.material_of(hit.prim);
        (m, emission_of(t, m, &q.ray[i], &hit), NO_VERTEX)
    };
    // Most hits find no light: nothing is added (adding the zero cost the camera rays' hits
    // a stalled reload of the emission each).
    if t.rules.features.emission && depth == 0 && t.rules.counts_emission() && emission != Vec3::ZERO {
        q.radiance[i] += emission;
    }
    if (t.rules.features.non_diffuse || t.rules.mis) && depth > 0 {
        let mut found = t.arrival_at_hit(q.bounce[i], &q.ray[i], &hit, emission, depth);
        if found != Vec3::ZERO {
            if let Some(c) = &t.caustics
                && q.bounce[i].pdf == f32::INFINITY
            {
                // Emission after a delta vertex: a caustic light tracing also draws.
                found *= c.hit_weight(&t.lights.set, hit.prim, q.ray[i].dir, q.pl[i]);
            }
            q.radiance[i] += q.throughput[i] * found;
        }
    }
    Arrival { material, emission, vertex }
}

/// Path `i` goes on from its vertex of `depth` along `ray`, its throughput times `weight`,
/// and plays Russian roulette with the number `u` gives (asked for only where roulette is
/// played): the one continuation every kernel, one path or lanes, ends a vertex with.
/// Roulette is played here, where the vertex's numbers are at hand (the bounce stage would
/// have to derive them again), after the BSDF weight as [`Transport::continuation`] does; the
/// shadow rays already took the throughput before it.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn go_on(
    t: &Transport,
    q: &mut PathQueue,
    i: usize,
    depth: u32,
    ray: Ray,
    weight: Vec3,
    bounce: Bounce,
    u: impl FnOnce() -> f32,
) {
    q.ray[i] = ray;
    q.throughput[i] *= weight;
    q.depth[i] = depth + 1;
    q.alive[i] = true;
    q.bounce[i] = bounce;
    if t.rules.features.roulette && t.rules.plays_roulette(depth) {
        match t.rules.roulette_with(u(), q.throughput[i]) {
            Some(f) => q.throughput[i] *= f,
            None => q.alive[i] = false,
        }
    }
}

/// A vertex with nothing in it, for lanes a group leaves empty.
pub const NO_VERTEX: Vertex = Vertex {
    p: Vec3::ZERO,
    p_error: Vec3::ZERO,
    ng: Vec3::Z,
    ns: Vec3::Z,
    albedo: Vec3::ZERO,
    emission: Vec3::ZERO,
    metal_rough: Vec2::ZERO,
    material: 0,
    front: true,
    uv: Vec2::ZERO,
    bumped: false,
};

/// The emission of a hit on material `m` seen from `ray` (as `Transport::vertex` computes it
/// where the material has no emission texture).
#[inline(always)]
pub fn emission_of(t: &Transport, m: usize, ray: &Ray, hit: &Hit) -> Vec3 {
    let e = t.materials.emission[m];
    if e == Vec3::ZERO || t.materials.two_sided_emission[m] {
        e
    } else {
        // One-sided emitters are rare: the whole vertex says which side was hit.
        t.vertex(ray, hit).emission
    }
}
