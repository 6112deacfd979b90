//! Leaving a vertex, written once for every model ([`LaneModel`], Lambert included) and
//! every lane count: the light samples of every light (area lights, emissive triangles, the
//! light from infinity, point, spot and directional lights) or hemisphere sampling's probes,
//! the model's value and density at each, the MIS weights and shadow rays, then the
//! continuation's sample, ray and weight, all in fixed loops over the lanes that the compiler
//! vectorises; Russian roulette and the path's update through [`one_path::go_on`], the one
//! continuation of every kernel. What is per lane and irregular stays one lane at a time:
//! which emissive triangle a sample picks and what it emits, an environment map's or a point
//! light's sample, a model's library calls.
//!
//! The per-sample functions are the ones the one-path code calls (`area_ray`,
//! `triangle_ray`, `diffuse_light_ray`, `glossy_light_ray`, `eval_pdf`, `sample_at`,
//! `offset_origin`), so each lane's rays and weights are those of [`one_path::leave`], bit
//! for bit, whatever the lane count.

#![allow(clippy::needless_range_loop)]

use super::model::{Lane, LaneModel, PARAMS};
use super::numbers::LaneNumbers;
use super::soa::{Emitters, LightPoints, Points, Rays, area_rays, get, put, unused_half};
use crate::bsdf::to_local;
use crate::geometry::Ray;
use crate::geometry::offset::offset_origin;
use crate::integrator::bidir::caustics::CausticTerms;
use crate::integrator::light_ray::LightPoint;
use crate::integrator::wavefront::one_path;
use crate::integrator::wavefront::queues::{PathQueue, ShadowQueue, ShadowSlots};
use crate::integrator::{DIM_DIRECT, DIM_LOBE, DIM_ROULETTE, Transport, Vertex};
use crate::lights::{EmissiveTriangles, Emitter, SampledLight};
use crate::sampling::{Frame, warp};
use glam::Vec3;

/// Up to `L` vertices of one model leaving together (lanes `0..n`), one array per component.
pub struct Group<M, const L: usize> {
    pub n: usize,
    /// Path index of each lane.
    pub path: [usize; L],
    pub depth: [u32; L],
    /// The lane takes light samples / sends a continuation (the model's rules at its depth,
    /// the render's features).
    pub direct: [bool; L],
    pub cont: [bool; L],
    pub model: [M; L],
    /// The shading points: filled by [`push`](Self::push), or in lanes by the caller.
    pub pts: Points<L>,
    /// The direction each path arrived along.
    dir: [[f32; L]; 3],
    params: [[f32; L]; PARAMS],
    bumped: [bool; L],
}

impl<M: LaneModel, const L: usize> Group<M, L> {
    pub fn new() -> Self {
        Group {
            n: 0,
            path: [0; L],
            depth: [0; L],
            direct: [false; L],
            cont: [false; L],
            model: [M::NONE; L],
            pts: Points::default(),
            dir: [[0.0; L]; 3],
            params: [[0.0; L]; PARAMS],
            bumped: [false; L],
        }
    }

    /// Empties the group.
    #[inline(always)]
    pub fn clear(&mut self) {
        self.n = 0;
        self.direct = [false; L];
        self.cont = [false; L];
    }

    /// Adds path `i` with model `m`, its shading point left to the caller (lane `n`, not
    /// relief-mapped); the lane's index.
    #[inline(always)]
    pub fn push_path(&mut self, t: &Transport, q: &PathQueue, i: usize, m: M) -> usize {
        let j = self.n;
        (self.path[j], self.depth[j]) = (i, q.depth[i]);
        self.set_model(t, j, m);
        put(&mut self.dir, j, q.ray[i].dir);
        self.bumped[j] = false;
        self.n += 1;
        j
    }

    /// Sets lane `j`'s model (and what its rules say the lane sends).
    #[inline(always)]
    pub fn set_model(&mut self, t: &Transport, j: usize, m: M) {
        let depth = self.depth[j];
        self.model[j] = m;
        self.direct[j] = t.rules.features.direct && !M::DELTA && t.rules.counts_direct(depth) && m.takes_light();
        self.cont[j] = t.rules.features.indirect && m.continues(t, depth);
        let p = m.params();
        for k in 0..M::USED {
            self.params[k][j] = p[k];
        }
    }

    /// Adds path `i` at vertex `v` with model `m`.
    #[inline(always)]
    pub fn push(&mut self, t: &Transport, q: &PathQueue, i: usize, v: &Vertex, m: M) {
        let j = self.push_path(t, q, i, m);
        self.pts.set(j, &v.shading_point());
        self.bumped[j] = v.bumped;
    }

    /// Whether any lane sends a ray.
    #[inline(always)]
    pub fn sends(&self) -> bool {
        self.direct.iter().chain(&self.cont).any(|&b| b)
    }

    /// Drops the rays of `r` that leave a relief-mapped lane on the other side of its
    /// geometric surface ([`Vertex::consistent`] of the ray's direction); none is where no
    /// lane is relief-mapped.
    #[inline(always)]
    fn keep_consistent(&self, r: &mut Rays<L>) {
        if self.bumped.iter().any(|&b| b) {
            for j in 0..L {
                r.valid[j] &= self.lane(j).consistent(r.ray(j).dir);
            }
        }
    }

    /// Lane `j` with its frame and outgoing direction ([`Transport::shading`]'s operations).
    #[inline(always)]
    fn lane(&self, j: usize) -> Lane<M> {
        let sp = self.pts.get(j);
        let frame = Frame::new(sp.ns);
        let wo = to_local(&frame, -get(&self.dir, j));
        let a = &self.params;
        let model = M::from_params(&std::array::from_fn(|k| if k < M::USED { a[k][j] } else { 0.0 }));
        Lane { p: sp.p, p_error: sp.p_error, ng: sp.ng, ns: sp.ns, frame, wo, model, bumped: self.bumped[j] }
    }
}

/// Leaves the vertices of `g` as [`one_path::leave`] does, with the numbers `rng`: shadow
/// rays (throughput applied) and continuations after Russian roulette. `pending` is scratch
/// for a light's samples.
#[inline(always)]
pub fn leave<M: LaneModel, N: LaneNumbers<L>, const L: usize>(
    t: &Transport,
    q: &mut PathQueue,
    g: &Group<M, L>,
    rng: N,
    pending: &mut Vec<Rays<L>>,
    shadow: &mut ShadowQueue,
) {
    if t.rules.features.direct && !M::DELTA && g.direct.iter().any(|&d| d) {
        let gs = Samples { t, q: &*q, g, rng };
        if t.rules.hemisphere {
            hemisphere_probes(gs, pending, shadow);
        } else {
            direct_light(gs, pending, shadow);
        }
    }
    if t.rules.features.indirect && g.cont.iter().any(|&c| c) {
        continuation(t, q, g, rng);
    }
}

/// What a group's direct-light functions read: the transport, the paths, the group and its
/// numbers.
struct Samples<'a, 's, M, N, const L: usize> {
    t: &'a Transport<'s>,
    q: &'a PathQueue,
    g: &'a Group<M, L>,
    rng: N,
}

// By hand: a derive would ask `M: Copy` of the references' target.
impl<M, N: Copy, const L: usize> Clone for Samples<'_, '_, M, N, L> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<M, N: Copy, const L: usize> Copy for Samples<'_, '_, M, N, L> {}

/// The shadow rays of the group, light by light: each light's rays sample-major
/// (lane-parallel), pushed path-major, so the rays of one point sit together in the queue,
/// where the shadow stage traces them as one packet, and each path still adds its own in the
/// order the one-path code makes them.
#[inline(always)]
fn direct_light<M: LaneModel, N: LaneNumbers<L>, const L: usize>(
    gs: Samples<'_, '_, M, N, L>,
    pending: &mut Vec<Rays<L>>,
    shadow: &mut ShadowQueue,
) {
    let Samples { t, q, g, .. } = gs;
    let mut mis = [false; L];
    for j in 0..L {
        mis[j] = M::light_mis(t, g.depth[j]);
    }
    let mut dim = DIM_DIRECT;
    for (li, light) in t.lights.set.lights.iter().enumerate() {
        let ns = t.lights.set.samples_for(li, t.rules.light_samples);
        if pending.len() < ns as usize {
            pending.resize_with(ns as usize, Rays::default);
        }
        let samples = pending.iter_mut().take(ns as usize);
        // Into a local first: a loop writing through the queue's buffer is left scalar (its
        // stores might alias what it reads, for all the compiler knows).
        match (light, &t.lights.area_lights[li]) {
            (SampledLight::Emissive(e), _) => {
                for p in samples {
                    let mut out = Rays::<L>::default();
                    emissive_samples(gs, e, li, ns, dim, &mis, &mut out);
                    *p = out;
                    dim += 2;
                }
            }
            (SampledLight::Area { radiance, .. }, Some(al)) if M::AREA_RAYS => {
                let mut scale = [[0.0; L]; 3];
                for j in 0..L {
                    put(&mut scale, j, g.model[j].area_scale(*radiance, ns));
                }
                for p in samples {
                    let (ua, ub) = gs.rng.pair(dim);
                    let (ua, ub) = (unused_half(ua, &g.direct), unused_half(ub, &g.direct));
                    let mut out = Rays::<L>::default();
                    area_rays(&g.pts, al, &ua, &ub, &mut out);
                    for j in 0..L {
                        out.set_weight(j, M::area_weight(get(&scale, j), out.g[j], ns, mis[j]));
                    }
                    g.keep_consistent(&mut out);
                    *p = out;
                    dim += 1;
                }
            }
            _ => {
                for p in samples {
                    let mut out = Rays::<L>::default();
                    light_samples(gs, light, li, ns, dim, &mis, &mut out);
                    *p = out;
                    dim += 1;
                }
            }
        }
        push_samples(q, g, &pending[..ns as usize], shadow);
    }
}

/// One sample of light `li` (`light`: the light from infinity, point, spot and directional
/// lights, an area light a model samples as any light; `ns` samples a vertex) for every lane,
/// from the pair at dimension `dim`: the light from infinity (with or without a map) and the
/// delta lights sampled in all lanes at once, any other light one lane at a time
/// (`SampledLight::sample_pdf`); then the model's shadow rays and weights of all lanes
/// ([`LaneModel::light_ray`]).
#[inline(always)]
fn light_samples<M: LaneModel, N: LaneNumbers<L>, const L: usize>(
    gs: Samples<'_, '_, M, N, L>,
    light: &SampledLight,
    li: usize,
    ns: u32,
    dim: u32,
    mis: &[bool; L],
    out: &mut Rays<L>,
) {
    let Samples { t, g, rng, .. } = gs;
    // A delta light's samples are the same for each of its samples and read no numbers.
    let delta = LightPoints::delta(light, &g.pts.p, mis, &g.direct);
    let ls = match (light, delta) {
        (_, Some(ls)) => ls,
        (SampledLight::Infinite(inf), None) => {
            let (ua, ub) = rng.pair(dim);
            match inf.map.as_deref() {
                None => LightPoints::sky(inf.sky(), &g.pts.ns, &ua, &ub, &g.direct),
                Some(map) => LightPoints::environment(inf, map, &g.pts.ns, &ua, &ub, mis, &g.direct),
            }
        }
        _ => {
            let (ua, ub) = rng.pair(dim);
            let mut ls = LightPoints::<L>::default();
            for j in 0..g.n {
                if g.direct[j] {
                    let (s, u) = (g.pts.get(j), [ua[j], ub[j], 0.0]);
                    ls.set(
                        j,
                        &LightPoint::of(if mis[j] {
                            light.sample_pdf(s.p, s.ns, u)
                        } else {
                            light.sample(s.p, s.ns, u).map(|l| (l, 0.0))
                        }),
                    );
                }
            }
            ls
        }
    };
    let margin = t.lights.shadow_margins[li];
    for j in 0..L {
        let r = M::light_ray(&g.lane(j), &ls.get(j), margin, ns, mis[j]);
        out.set_light_ray(j, &r);
    }
}

/// One sample of emissive-triangle light `li` (`e`, `ns` samples a vertex) for every lane,
/// from dimension `dim` (the pair) and `dim + 1` (the triangle's pick): the picks first
/// (independent searches), then each picked triangle's fields into lanes, then the points of
/// all lanes at once (picking, reading and sampling one lane at a time made each lane wait on
/// its own chain of loads), then the model's shadow rays and weights
/// ([`LaneModel::triangle_ray`]).
#[inline(always)]
fn emissive_samples<M: LaneModel, N: LaneNumbers<L>, const L: usize>(
    gs: Samples<'_, '_, M, N, L>,
    e: &EmissiveTriangles,
    li: usize,
    ns: u32,
    dim: u32,
    mis: &[bool; L],
    out: &mut Rays<L>,
) {
    let Samples { t, g, rng, .. } = gs;
    let (ua, ub) = rng.pair(dim);
    let uc = rng.one(dim + 1);
    let mut picked = [usize::MAX; L];
    for j in 0..g.n {
        if g.direct[j] {
            picked[j] = e.pick(uc[j]).unwrap_or(usize::MAX);
        }
    }
    let mut tri = Emitters::<L>::default();
    let mut corners = [[[0.0; L]; 3]; 3];
    for j in 0..g.n {
        if picked[j] != usize::MAX {
            let t = e.triangle(picked[j]);
            tri.set(j, t);
            put(&mut corners[0], j, t.a);
            put(&mut corners[1], j, t.e1);
            put(&mut corners[2], j, t.e2);
        }
    }
    let mut point = [[0.0; L]; 3];
    let (mut bu, mut bv) = ([0.0; L], [0.0; L]);
    for j in 0..L {
        (bu[j], bv[j]) = warp::uniform_triangle(ua[j], ub[j]);
        let [a, e1, e2] = [get(&corners[0], j), get(&corners[1], j), get(&corners[2], j)];
        put(&mut point, j, Emitter::point_at(a, e1, e2, bu[j], bv[j]));
    }
    let mut le = [[0.0; L]; 3];
    for j in 0..g.n {
        if picked[j] != usize::MAX {
            put(&mut le, j, e.emitted(picked[j], bu[j], bv[j]));
        }
    }
    let margin = t.lights.shadow_margins[li];
    for j in 0..L {
        let r = M::triangle_ray(&g.lane(j), &tri.get(j), get(&point, j), get(&le, j), margin, ns, mis[j]);
        out.set_light_ray(j, &r);
    }
}

/// Hemisphere sampling's direct light (`Transport::direct_rays` under `-H`): uniform probes
/// of the lanes that take direct light, weighted by the model ([`LaneModel::probe`]), each
/// path's in its order; the sine and cosine of each probe's azimuth one lane at a time.
#[inline(always)]
fn hemisphere_probes<M: LaneModel, N: LaneNumbers<L>, const L: usize>(
    gs: Samples<'_, '_, M, N, L>,
    pending: &mut Vec<Rays<L>>,
    shadow: &mut ShadowQueue,
) {
    let Samples { t, q, g, rng } = gs;
    let n = t.rules.direct_per_vertex;
    if pending.len() < n as usize {
        pending.resize_with(n as usize, Rays::default);
    }
    for (k, p) in pending.iter_mut().take(n as usize).enumerate() {
        let (z, b) = rng.pair(DIM_DIRECT + k as u32);
        let (mut sin, mut cos) = ([0.0f32; L], [1.0f32; L]);
        for j in 0..g.n {
            if g.direct[j] {
                (sin[j], cos[j]) = (std::f32::consts::TAU * b[j]).sin_cos();
            }
        }
        let z = unused_half(z, &g.direct);
        // Into a local first (see `direct_light`).
        let mut out = Rays::<L>::default();
        for j in 0..L {
            let l = g.lane(j);
            let local = warp::uniform_hemisphere_at(z[j], (sin[j], cos[j]));
            let (w, ok) = M::probe(&l, local, n);
            let wi = l.frame.to_world(local);
            let origin = offset_origin(l.p, l.p_error, l.ng, wi);
            out.set(j, &Ray { origin, dir: wi, tmin: 0.0, tmax: f32::INFINITY });
            out.set_weight(j, w);
            out.valid[j] = g.direct[j] & ok & l.consistent(wi);
        }
        *p = out;
    }
    push_samples(q, g, &pending[..n as usize], shadow);
}

/// A light's samples of the group (sample-major, each with its whole weight) into the shadow
/// queue path-major, throughput applied: every candidate is stored and the cursor moves past
/// the valid ones only.
#[inline(always)]
fn push_samples<M, const L: usize>(q: &PathQueue, g: &Group<M, L>, samples: &[Rays<L>], shadow: &mut ShadowQueue) {
    let ShadowSlots { ray: rs, weight: ws, owner: os } = shadow.open(g.n * samples.len());
    let mut w = 0;
    for j in 0..g.n {
        if !g.direct[j] {
            continue;
        }
        let (i, tp) = (g.path[j], q.throughput[g.path[j]]);
        for p in samples {
            rs[w] = p.ray(j);
            ws[w] = p.weight(j) * tp;
            os[w] = i as u32;
            w += p.valid[j] as usize;
        }
    }
    shadow.commit(w);
}

/// The continuations (`Transport::scatter` and `Transport::scatter_shaded`): the model's
/// samples in lanes (its library calls one lane at a time), then each path goes on.
#[inline(always)]
fn continuation<M: LaneModel, N: LaneNumbers<L>, const L: usize>(
    t: &Transport,
    q: &mut PathQueue,
    g: &Group<M, L>,
    rng: N,
) {
    let (ua, ub) = rng.pair(0);
    let (ua, ub) = (unused_half(ua, &g.cont), unused_half(ub, &g.cont));
    let uc = if M::LOBE { rng.one(DIM_LOBE) } else { [0.0; L] };
    let rr = if t.rules.features.roulette { rng.one(DIM_ROULETTE) } else { [0.0; L] };
    // What is one lane at a time first (the model's library calls, the rules at each
    // depth), so that the loop after it vectorises.
    let mut calls = [[0.0f32; L]; 3];
    let mut mis = [false; L];
    for j in 0..g.n {
        put(&mut calls, j, Vec3::from(g.model[j].sample_calls([ua[j], ub[j], uc[j]])));
        mis[j] = M::continuation_mis(t, g.depth[j]);
    }
    let mut rays = Rays::<L>::default();
    let mut weight = [[0.0f32; L]; 3];
    let mut bounce_n = [[0.0f32; L]; 3];
    let mut bounce_pdf = [0.0f32; L];
    let caustics = t.caustics.as_ref();
    // path+light's terms: the cosines at the vertex, the sample's densities both ways.
    let (mut cos_in, mut cos_out, mut pdf, mut pdf_rev, mut delta) =
        ([0.0f32; L], [0.0f32; L], [0.0f32; L], [0.0f32; L], [false; L]);
    for j in 0..L {
        let l = g.lane(j);
        let (s, ok) = l.model.sample_at(l.wo, [ua[j], ub[j], uc[j]], get(&calls, j).to_array());
        let wi = l.frame.to_world(s.wi);
        if caustics.is_some() {
            cos_in[j] = get(&g.dir, j).dot(l.ng).abs();
            cos_out[j] = wi.dot(l.ng).abs();
            delta[j] = M::DELTA || s.delta;
            (pdf[j], pdf_rev[j]) = if delta[j] { (s.pdf, 0.0) } else { M::densities(&l, &s) };
        }
        let origin = offset_origin(l.p, l.p_error, l.ng, wi);
        rays.set(j, &Ray { origin, dir: wi, tmin: 0.0, tmax: f32::INFINITY });
        put(&mut weight, j, s.weight);
        let b = M::bounce(&l, &s, wi, mis[j]);
        put(&mut bounce_n, j, b.n);
        bounce_pdf[j] = b.pdf;
        rays.valid[j] = g.cont[j] & ok & (s.weight != Vec3::ZERO) & l.consistent(wi);
    }
    for j in 0..g.n {
        if !rays.valid[j] {
            continue;
        }
        if let Some(c) = caustics {
            let i = g.path[j];
            q.pl[i] = match q.hit[i] {
                _ if g.depth[j] > 0 => CausticTerms::next(q.pl[i], cos_in[j], cos_out[j], delta[j], pdf[j], pdf_rev[j]),
                Some(h) if !delta[j] => c.first(get(&g.dir, j), h.t, cos_in[j], cos_out[j], pdf[j]),
                _ => 0.0,
            };
        }
        let bounce = crate::integrator::Bounce { n: get(&bounce_n, j), pdf: bounce_pdf[j] };
        one_path::go_on(t, q, g.path[j], g.depth[j], rays.ray(j), get(&weight, j), bounce, || rr[j]);
    }
}
