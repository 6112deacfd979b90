//! The models whose sample is written without branches (`LaneModel`: glTF metallic-roughness
//! and specular-glossiness, the layered glTF model, MTL PBR and Phong, the rough conductor,
//! mirror, glass) leaving their vertices eight or sixteen at a time: the shading frames, the
//! light samples of every light (emissive triangles, the light from infinity, point, spot and
//! directional lights) or hemisphere sampling's probes, the BSDF's value and density at each,
//! the MIS weights, the shadow rays, and the continuation's sample with its value, density
//! and ray, all in fixed loops over the lanes that the compiler vectorises. What is per lane
//! and irregular stays one lane at a time: the material's parameters at the vertex
//! ([`Transport::model_at`], the layered model's sheen table), which emissive triangle a
//! sample picks and what it emits, an environment map's or a point light's sample, the
//! library calls a sample needs (the sine and cosine of an angle, Beckmann's logarithm),
//! Russian roulette. Mirror and glass take no light samples: theirs is the continuation alone.
//!
//! The per-sample functions are the ones the one-path code calls (`eval_pdf`, `sample_at`,
//! the light sample's geometry, `offset_origin`), written without branches, so the rays and
//! weights are those of [`super::one_path::leave`], bit for bit.

#![allow(clippy::needless_range_loop)]

use super::lanes::{Emitters, LightPoints, Points, Rays, get, put};
use super::one_path;
use super::queues::{PathQueue, ShadowQueue, ShadowSlots};
use crate::bsdf::{BsdfSample, Dielectric, Distribution, Glossy, Layered, Microfacet, Mirror, Pbr};
use crate::bsdf::{power_heuristic, to_local};
use crate::geometry::Ray;
use crate::geometry::offset::{offset_origin, shadow_tmax_at};
use crate::integrator::Bounce;
use crate::integrator::area::ShadingPoint;
use crate::integrator::light_ray::{LightPoint, glossy_light_ray};
use crate::integrator::{DIM_DIRECT, Transport, Vertex};
use crate::lights::{EmissiveTriangles, SampledLight, area_to_solid_angle_lanes};
use crate::sampling::numbers::{Drawn, Numbers};
use crate::sampling::{Frame, Sampler, warp};
use glam::Vec3;

/// Most numbers a model's parameters take (the layered glTF model's).
const PARAMS: usize = 24;

/// A model this kernel shades: its value and density and its sample without branches, and
/// its parameters as numbers (the kernel keeps them one array per parameter).
pub(super) trait LaneModel: Copy {
    const NONE: Self;
    /// Delta lobes only (mirror, smooth glass): no light samples, and the continuation's
    /// light is not weighed against them ([`Bounce::DELTA`]).
    const DELTA: bool;
    fn params(&self) -> [f32; PARAMS];
    fn from_params(p: &[f32; PARAMS]) -> Self;
    /// The value and density toward `wi`; by default those of delta lobes (zero).
    #[inline(always)]
    fn eval_pdf(&self, _wo: Vec3, _wi: Vec3) -> (Vec3, f32) {
        (Vec3::ZERO, 0.0)
    }
    /// The library calls (sine, cosine, logarithm) [`sample_at`](Self::sample_at) needs for
    /// the numbers `u`: made one lane at a time, as they do not vectorise. By default none.
    #[inline(always)]
    fn sample_calls(&self, _u: [f32; 3]) -> [f32; 3] {
        [0.0; 3]
    }
    fn sample_at(&self, wo: Vec3, u: [f32; 3], calls: [f32; 3]) -> (BsdfSample, bool);
}

/// A model's `N` parameters, the rest of the kernel's `PARAMS` zero.
#[inline(always)]
fn pad<const N: usize>(p: [f32; N]) -> [f32; PARAMS] {
    std::array::from_fn(|k| if k < N { p[k] } else { 0.0 })
}

/// The sine and cosine of the visible-normal sample's disk angle, `2 pi u[1]`.
#[inline(always)]
fn disk_angle(u: [f32; 3]) -> [f32; 3] {
    let (sin, cos) = (std::f32::consts::TAU * u[1]).sin_cos();
    [sin, cos, 0.0]
}

impl LaneModel for Pbr {
    const NONE: Self = Pbr { diffuse: Vec3::ZERO, f0: Vec3::ZERO, diffuse_f0: Vec3::ZERO, alpha: 0.0 };
    const DELTA: bool = false;

    #[inline(always)]
    fn params(&self) -> [f32; PARAMS] {
        let (d, f, g) = (self.diffuse, self.f0, self.diffuse_f0);
        pad([d.x, d.y, d.z, f.x, f.y, f.z, g.x, g.y, g.z, self.alpha])
    }

    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        Pbr {
            diffuse: Vec3::new(p[0], p[1], p[2]),
            f0: Vec3::new(p[3], p[4], p[5]),
            diffuse_f0: Vec3::new(p[6], p[7], p[8]),
            alpha: p[9],
        }
    }

    #[inline(always)]
    fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        Pbr::eval_pdf(self, wo, wi)
    }

    #[inline(always)]
    fn sample_calls(&self, u: [f32; 3]) -> [f32; 3] {
        disk_angle(u)
    }

    #[inline(always)]
    fn sample_at(&self, wo: Vec3, u: [f32; 3], [sin, cos, _]: [f32; 3]) -> (BsdfSample, bool) {
        Pbr::sample_at(self, wo, u, (sin, cos))
    }
}

impl LaneModel for Glossy {
    const NONE: Self = Glossy { diffuse: Vec3::ZERO, specular: Vec3::ZERO, alpha: 0.0 };
    const DELTA: bool = false;

    #[inline(always)]
    fn params(&self) -> [f32; PARAMS] {
        let (d, s) = (self.diffuse, self.specular);
        pad([d.x, d.y, d.z, s.x, s.y, s.z, self.alpha])
    }

    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        Glossy { diffuse: Vec3::new(p[0], p[1], p[2]), specular: Vec3::new(p[3], p[4], p[5]), alpha: p[6] }
    }

    #[inline(always)]
    fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        Glossy::eval_pdf(self, wo, wi)
    }

    #[inline(always)]
    fn sample_calls(&self, u: [f32; 3]) -> [f32; 3] {
        disk_angle(u)
    }

    #[inline(always)]
    fn sample_at(&self, wo: Vec3, u: [f32; 3], [sin, cos, _]: [f32; 3]) -> (BsdfSample, bool) {
        Glossy::sample_at(self, wo, u, (sin, cos))
    }
}

/// The rough conductor (CS184's microfacet BSDF): Beckmann's D through the branch-free
/// `exp`, the half vector's azimuth and logarithm made one lane at a time.
impl LaneModel for Microfacet {
    const NONE: Self = Microfacet { alpha: 0.0, eta: Vec3::ZERO, k: Vec3::ZERO, distribution: Distribution::Beckmann };
    const DELTA: bool = false;

    #[inline(always)]
    fn params(&self) -> [f32; PARAMS] {
        let (e, k) = (self.eta, self.k);
        let ggx = (self.distribution == Distribution::Ggx) as u32 as f32;
        pad([e.x, e.y, e.z, k.x, k.y, k.z, self.alpha, ggx])
    }

    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        let distribution = if p[7] != 0.0 { Distribution::Ggx } else { Distribution::Beckmann };
        Microfacet { eta: Vec3::new(p[0], p[1], p[2]), k: Vec3::new(p[3], p[4], p[5]), alpha: p[6], distribution }
    }

    #[inline(always)]
    fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        Microfacet::eval_pdf(self, wo, wi)
    }

    #[inline(always)]
    fn sample_calls(&self, u: [f32; 3]) -> [f32; 3] {
        Microfacet::sample_calls(self, [u[0], u[1]])
    }

    #[inline(always)]
    fn sample_at(&self, wo: Vec3, u: [f32; 3], calls: [f32; 3]) -> (BsdfSample, bool) {
        Microfacet::sample_at(self, wo, [u[0], u[1]], calls)
    }
}

impl LaneModel for Mirror {
    const NONE: Self = Mirror { reflectance: Vec3::ZERO };
    const DELTA: bool = true;

    #[inline(always)]
    fn params(&self) -> [f32; PARAMS] {
        let r = self.reflectance;
        pad([r.x, r.y, r.z])
    }

    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        Mirror { reflectance: Vec3::new(p[0], p[1], p[2]) }
    }

    #[inline(always)]
    fn sample_at(&self, wo: Vec3, _: [f32; 3], _: [f32; 3]) -> (BsdfSample, bool) {
        Mirror::sample_at(self, wo)
    }
}

/// Smooth glass, oriented to the side the path arrives on ([`Transport::model_at`]).
impl LaneModel for Dielectric {
    const NONE: Self = Dielectric { reflectance: Vec3::ZERO, transmittance: Vec3::ZERO, eta: 0.0, reflect: false };
    const DELTA: bool = true;

    #[inline(always)]
    fn params(&self) -> [f32; PARAMS] {
        let (r, t) = (self.reflectance, self.transmittance);
        pad([r.x, r.y, r.z, t.x, t.y, t.z, self.eta, self.reflect as u32 as f32])
    }

    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        Dielectric {
            reflectance: Vec3::new(p[0], p[1], p[2]),
            transmittance: Vec3::new(p[3], p[4], p[5]),
            eta: p[6],
            reflect: p[7] != 0.0,
        }
    }

    #[inline(always)]
    fn sample_at(&self, wo: Vec3, u: [f32; 3], _: [f32; 3]) -> (BsdfSample, bool) {
        Dielectric::sample_at(self, wo, u[2])
    }
}

/// The glTF model with its extensions' layers (clearcoat, sheen, transmission), seen from
/// the lane's direction ([`LayerData::at`](crate::integrator::layers::LayerData::at)): its
/// delta transmission lobe mixed with the continuous ones, so the sample says per lane
/// whether it is a delta one.
impl LaneModel for Layered {
    const NONE: Self = Layered {
        diffuse: Vec3::ZERO,
        transmit: Vec3::ZERO,
        f0: Vec3::ZERO,
        f90: 0.0,
        dielectric_f0: Vec3::ZERO,
        specular_weight: 0.0,
        alpha: 0.0,
        eta: 1.0,
        thin: true,
        clearcoat: 0.0,
        coat_alpha: 0.0,
        sheen: Vec3::ZERO,
        sheen_alpha: 1.0,
        sheen_scaling: 1.0,
    };
    const DELTA: bool = false;

    #[inline(always)]
    fn params(&self) -> [f32; PARAMS] {
        let (d, t, f, g, s) = (self.diffuse, self.transmit, self.f0, self.dielectric_f0, self.sheen);
        [
            d.x,
            d.y,
            d.z,
            t.x,
            t.y,
            t.z,
            f.x,
            f.y,
            f.z,
            self.f90,
            g.x,
            g.y,
            g.z,
            self.specular_weight,
            self.alpha,
            self.eta,
            self.thin as u32 as f32,
            self.clearcoat,
            self.coat_alpha,
            s.x,
            s.y,
            s.z,
            self.sheen_alpha,
            self.sheen_scaling,
        ]
    }

    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        Layered {
            diffuse: Vec3::new(p[0], p[1], p[2]),
            transmit: Vec3::new(p[3], p[4], p[5]),
            f0: Vec3::new(p[6], p[7], p[8]),
            f90: p[9],
            dielectric_f0: Vec3::new(p[10], p[11], p[12]),
            specular_weight: p[13],
            alpha: p[14],
            eta: p[15],
            thin: p[16] != 0.0,
            clearcoat: p[17],
            coat_alpha: p[18],
            sheen: Vec3::new(p[19], p[20], p[21]),
            sheen_alpha: p[22],
            sheen_scaling: p[23],
        }
    }

    #[inline(always)]
    fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        Layered::eval_pdf(self, wo, wi)
    }

    #[inline(always)]
    fn sample_calls(&self, u: [f32; 3]) -> [f32; 3] {
        disk_angle(u)
    }

    #[inline(always)]
    fn sample_at(&self, wo: Vec3, u: [f32; 3], [sin, cos, _]: [f32; 3]) -> (BsdfSample, bool) {
        Layered::sample_at(self, wo, u, (sin, cos))
    }
}

/// A group's vertices of one model (lanes `0..n`), gathered by the shaded kinds' kernel.
pub(super) struct ModelGroup<M, const L: usize> {
    pub n: usize,
    /// Path index of each lane.
    pub path: [usize; L],
    /// The lane's place in the shaded group (its row of the numbers drawn ahead).
    pub row: [usize; L],
    pub vertex: [Vertex; L],
    pub model: [M; L],
}

impl<M: LaneModel, const L: usize> ModelGroup<M, L> {
    pub fn new() -> Self {
        ModelGroup { n: 0, path: [0; L], row: [0; L], vertex: [one_path::NO_VERTEX; L], model: [M::NONE; L] }
    }

    /// Adds path `path` (row `row` of the group's numbers) at vertex `v` with model `m`;
    /// true (the path is taken).
    #[inline(always)]
    pub fn push(&mut self, path: usize, row: usize, v: &Vertex, m: M) -> bool {
        let k = self.n;
        (self.path[k], self.row[k], self.vertex[k], self.model[k]) = (path, row, *v, m);
        self.n += 1;
        true
    }
}

/// What the lane-parallel loops read of a group: the shading points, the direction each ray
/// arrived along, and the model's parameters, one array per component.
struct Soa<const L: usize> {
    pts: Points<L>,
    dir: [[f32; L]; 3],
    params: [[f32; L]; PARAMS],
    bumped: [bool; L],
}

/// One lane's state, rebuilt from the arrays inside each loop (the shape that vectorises).
struct Lane<M> {
    p: Vec3,
    p_error: Vec3,
    ng: Vec3,
    ns: Vec3,
    frame: Frame,
    wo: Vec3,
    model: M,
    bumped: bool,
}

impl<M> Lane<M> {
    /// [`Vertex::consistent`] for this lane.
    #[inline(always)]
    fn consistent(&self, wi: Vec3) -> bool {
        !self.bumped || (wi.dot(self.ng) > 0.0) == (wi.dot(self.ns) > 0.0)
    }
}

impl<const L: usize> Soa<L> {
    fn new() -> Self {
        Soa { pts: Points::default(), dir: [[0.0; L]; 3], params: [[0.0; L]; PARAMS], bumped: [false; L] }
    }

    #[inline(always)]
    fn set<M: LaneModel>(&mut self, j: usize, v: &Vertex, dir: Vec3, m: &M) {
        self.pts.set(j, &v.shading_point());
        put(&mut self.dir, j, dir);
        for (a, x) in self.params.iter_mut().zip(m.params()) {
            a[j] = x;
        }
        self.bumped[j] = v.bumped;
    }

    /// Lane `j` with its frame and outgoing direction ([`Transport::shading`]'s operations).
    #[inline(always)]
    fn lane<M: LaneModel>(&self, j: usize) -> Lane<M> {
        let sp = self.pts.get(j);
        let frame = Frame::new(sp.ns);
        let wo = to_local(&frame, -get(&self.dir, j));
        let a = &self.params;
        let model = M::from_params(&std::array::from_fn(|k| a[k][j]));
        Lane { p: sp.p, p_error: sp.p_error, ng: sp.ng, ns: sp.ns, frame, wo, model, bumped: self.bumped[j] }
    }
}

/// Whether the shaded kinds' kernel may leave glossy vertices (not delta ones) here: every
/// number the vertex reads drawn ahead (light samples or hemisphere probes).
#[inline(always)]
pub(super) fn takes(t: &Transport) -> bool {
    t.shaded_numbers.complete
}

/// Leaves the vertices of `g` as [`one_path::leave`] does: shadow rays (throughput applied)
/// and continuations after Russian roulette. `table` holds the numbers drawn for the shaded
/// group (`dims` per lane, rows by [`ModelGroup::row`]), `rng` its streams; `pending` is
/// scratch for a light's samples.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn leave<M: LaneModel, const L: usize>(
    t: &Transport,
    q: &mut PathQueue,
    g: &ModelGroup<M, L>,
    table: &[[f32; 2]],
    dims: usize,
    rng: &[Sampler],
    pending: &mut Vec<Rays<L>>,
    shadow: &mut ShadowQueue,
) {
    let mut soa = Soa::<L>::new();
    let mut depth = [0u32; L];
    for j in 0..g.n {
        let i = g.path[j];
        soa.set(j, &g.vertex[j], q.ray[i].dir, &g.model[j]);
        depth[j] = q.depth[i];
    }
    let numbers = |j: usize, dim: u32| {
        let r = g.row[j];
        Drawn { stream: rng[r], table: &table[r * dims..(r + 1) * dims], one_d: &t.shaded_numbers.one_d, dim }
    };
    if t.rules.features.direct && !M::DELTA {
        let mut direct = [false; L];
        for j in 0..g.n {
            direct[j] = t.rules.counts_direct(depth[j]);
        }
        if direct.iter().any(|&d| d) {
            let gs = GroupSamples { t, q: &*q, g, soa: &soa, direct: &direct, table, dims };
            if t.rules.hemisphere {
                hemisphere_probes(gs, pending, shadow);
            } else {
                direct_light(gs, pending, shadow);
            }
        }
    }
    if t.rules.features.indirect {
        continuation::<M, L>(t, q, g, &soa, &depth, table, dims, &numbers);
    }
}

/// What a group's direct-light functions read (light samples of every kind, hemisphere
/// probes): the transport, the paths, the group and its lanes' arrays, which lanes take
/// direct light, and the numbers drawn ahead (`dims` per lane).
struct GroupSamples<'a, 's, M, const L: usize> {
    t: &'a Transport<'s>,
    q: &'a PathQueue,
    g: &'a ModelGroup<M, L>,
    soa: &'a Soa<L>,
    direct: &'a [bool; L],
    table: &'a [[f32; 2]],
    dims: usize,
}

// By hand: a derive would ask `M: Copy` of the references' target.
impl<M, const L: usize> Clone for GroupSamples<'_, '_, M, L> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<M, const L: usize> Copy for GroupSamples<'_, '_, M, L> {}

/// The shadow rays of the lanes in `direct`, light by light, each path's in the order the
/// one-path code makes them ([`Transport::direct_rays_shaded`]).
#[inline(always)]
fn direct_light<M: LaneModel, const L: usize>(
    gs: GroupSamples<'_, '_, M, L>,
    pending: &mut Vec<Rays<L>>,
    shadow: &mut ShadowQueue,
) {
    let GroupSamples { t, q, g, direct, .. } = gs;
    let mut dim = DIM_DIRECT as usize;
    for (li, light) in t.lights.set.lights.iter().enumerate() {
        let ns = t.lights.set.samples_for(li, t.rules.light_samples);
        let per_sample = 1 + light.uses_third_number() as usize;
        if let SampledLight::Emissive(e) = light {
            if pending.len() < ns as usize {
                pending.resize_with(ns as usize, Rays::default);
            }
            for p in pending.iter_mut().take(ns as usize) {
                // Into a local first: a loop writing through the queue's buffer is left
                // scalar (its stores might alias what it reads, for all the compiler knows).
                let mut out = Rays::<L>::default();
                emissive_samples(gs, e, li, ns, dim, &mut out);
                *p = out;
                dim += per_sample;
            }
            push_samples(q, g, direct, &pending[..ns as usize], shadow);
            continue;
        }
        if pending.len() < ns as usize {
            pending.resize_with(ns as usize, Rays::default);
        }
        for p in pending.iter_mut().take(ns as usize) {
            // Into a local first, as above.
            let mut out = Rays::<L>::default();
            light_samples(gs, light, li, ns, dim, &mut out);
            *p = out;
            dim += per_sample;
        }
        push_samples(q, g, direct, &pending[..ns as usize], shadow);
    }
}

/// One sample of light `li` (`light`: the light from infinity, point, spot and directional
/// lights, an area light; `ns` samples a vertex) for every lane, from the pair at dimension
/// `dim`: the light from infinity without a map and the delta lights sampled in all lanes at
/// once, any other light one lane at a time (`SampledLight::sample_pdf`: the map's table, a
/// normalisation); then the BSDF's value and density, the MIS weight and the shadow ray of all lanes, as
/// [`Transport::direct_light_shaded`] computes them ([`glossy_light_ray`]).
#[inline(always)]
fn light_samples<M: LaneModel, const L: usize>(
    gs: GroupSamples<'_, '_, M, L>,
    light: &SampledLight,
    li: usize,
    ns: u32,
    dim: usize,
    out: &mut Rays<L>,
) {
    let GroupSamples { t, g, soa, direct, table, dims, .. } = gs;
    let (mut ua, mut ub) = ([0.5f32; L], [0.5f32; L]);
    for j in 0..g.n {
        [ua[j], ub[j]] = table[g.row[j] * dims + dim];
    }
    let delta = LightPoints::delta(light, &soa.pts.p, &[true; L], direct);
    let ls = match (light, delta) {
        (_, Some(ls)) => ls,
        (SampledLight::Infinite(inf), None) if inf.map.is_none() => {
            LightPoints::sky(inf.sky(), &soa.pts.ns, &ua, &ub, direct)
        }
        _ => {
            let mut ls = LightPoints::<L>::default();
            for j in 0..g.n {
                if direct[j] {
                    let v = &g.vertex[j];
                    ls.set(j, &LightPoint::of(light.sample_pdf(v.p, v.ns, [ua[j], ub[j], 0.0])));
                }
            }
            ls
        }
    };
    let margin = t.lights.shadow_margins[li];
    for j in 0..L {
        let (l, lp) = (soa.lane::<M>(j), ls.get(j));
        let local = to_local(&l.frame, lp.wi);
        let (f, pdf_b) = l.model.eval_pdf(l.wo, local);
        let sp = ShadingPoint { p: l.p, p_error: l.p_error, ng: l.ng, ns: l.ns };
        let r = glossy_light_ray(&sp, &lp, local, f, pdf_b, margin, ns, l.consistent(lp.wi));
        out.set(j, &r.ray);
        out.set_weight(j, r.weight);
        out.valid[j] = r.valid;
    }
}

/// Hemisphere sampling's direct light ([`Transport::direct_rays_shaded`] under `-H`): the
/// uniform probes of the lanes in `direct`, BSDF-weighted, each path's in its order; the
/// sine and cosine of each probe's azimuth one lane at a time.
#[inline(always)]
fn hemisphere_probes<M: LaneModel, const L: usize>(
    gs: GroupSamples<'_, '_, M, L>,
    pending: &mut Vec<Rays<L>>,
    shadow: &mut ShadowQueue,
) {
    let GroupSamples { t, q, g, soa, direct, table, dims } = gs;
    let n = t.rules.direct_per_vertex as usize;
    if pending.len() < n {
        pending.resize_with(n, Rays::default);
    }
    let density = warp::UNIFORM_HEMISPHERE_PDF * n as f32;
    for (k, p) in pending.iter_mut().take(n).enumerate() {
        let dim = DIM_DIRECT as usize + k;
        let (mut z, mut sin, mut cos) = ([0.0f32; L], [0.0f32; L], [1.0f32; L]);
        for j in 0..g.n {
            let [a, b] = table[g.row[j] * dims + dim];
            z[j] = a;
            (sin[j], cos[j]) = (std::f32::consts::TAU * b).sin_cos();
        }
        // Into a local first (see `direct_light`).
        let mut out = Rays::<L>::default();
        for j in 0..L {
            let l = soa.lane::<M>(j);
            let local = warp::uniform_hemisphere_at(z[j], (sin[j], cos[j]));
            let (f, _) = l.model.eval_pdf(l.wo, local);
            let wi = l.frame.to_world(local);
            let origin = offset_origin(l.p, l.p_error, l.ng, wi);
            out.set(j, &Ray { origin, dir: wi, tmin: 0.0, tmax: f32::INFINITY });
            out.set_weight(j, f * (local.z / density));
            out.valid[j] = direct[j] & (f != Vec3::ZERO) & l.consistent(wi);
        }
        *p = out;
    }
    push_samples(q, g, direct, &pending[..n], shadow);
}

/// One sample of emissive-triangle light `li` (`e`, `ns` samples a vertex) for every lane,
/// from dimension `dim` (the pair) and `dim + 1` (the triangle's pick): the triangle and its
/// point one lane at a time, the rest lane-parallel, as `EmissiveTriangles::sample_pdf` and
/// [`Transport::direct_light_shaded`] compute it.
#[inline(always)]
fn emissive_samples<M: LaneModel, const L: usize>(
    gs: GroupSamples<'_, '_, M, L>,
    e: &EmissiveTriangles,
    li: usize,
    ns: u32,
    dim: usize,
    out: &mut Rays<L>,
) {
    let GroupSamples { t, g, soa, direct, table, dims, .. } = gs;
    let mut tri = Emitters::<L>::default();
    let mut point = [[0.0; L]; 3];
    let mut le = [[0.0; L]; 3];
    for j in 0..g.n {
        let row = g.row[j] * dims;
        let [ua, ub] = table[row + dim];
        let uc = table[row + dim + 1][0];
        if let (true, Some(i)) = (direct[j], e.pick(uc)) {
            let t = e.triangle(i);
            tri.set(j, t);
            let (qp, bu, bv) = t.point(ua, ub);
            put(&mut point, j, qp);
            put(&mut le, j, e.emitted(i, bu, bv));
        }
    }
    let margin = t.lights.shadow_margins[li];
    for j in 0..L {
        let l = soa.lane::<M>(j);
        let (tri, point, le) = (tri.get(j), get(&point, j), get(&le, j));
        let (wi, inv_pdf, ok) = area_to_solid_angle_lanes(l.p, point, tri.n, tri.inv_density, tri.one_sided);
        let pdf_l = 1.0 / inv_pdf;
        let local = to_local(&l.frame, wi);
        let (f, pdf_b) = l.model.eval_pdf(l.wo, local);
        let w = power_heuristic(ns as f32 * pdf_l, pdf_b);
        let origin = offset_origin(l.p, l.p_error, l.ng, wi);
        // `LightSampler::shadow_ray` toward the sampled point.
        let to = point - origin;
        let len = to.length();
        let rcp = 1.0 / len;
        let tmax = shadow_tmax_at(len, margin);
        out.set(j, &Ray { origin, dir: to * rcp, tmin: 0.0, tmax });
        out.set_weight(j, f * (le * inv_pdf) * (local.z * w / ns as f32));
        // An unpicked lane keeps an invalid triangle.
        out.valid[j] = tri.valid
            & ok
            & (f != Vec3::ZERO)
            & (w > 0.0)
            & l.consistent(wi)
            & rcp.is_finite()
            & (rcp > 0.0)
            & (tmax > 0.0);
    }
}

/// A light's samples of the group (sample-major) into the shadow queue path-major, throughput
/// applied, so the rays of one point sit together (the shadow stage traces them as a packet).
#[inline(always)]
fn push_samples<M, const L: usize>(
    q: &PathQueue,
    g: &ModelGroup<M, L>,
    direct: &[bool; L],
    samples: &[Rays<L>],
    shadow: &mut ShadowQueue,
) {
    let ShadowSlots { ray: rs, weight: ws, owner: os } = shadow.open(g.n * samples.len());
    let mut w = 0;
    for j in 0..g.n {
        if !direct[j] {
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

/// The continuations ([`Transport::scatter_shaded`] for a glossy or a delta vertex), then Russian roulette one lane at a time.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn continuation<'a, M: LaneModel, const L: usize>(
    t: &Transport,
    q: &mut PathQueue,
    g: &ModelGroup<M, L>,
    soa: &Soa<L>,
    depth: &[u32; L],
    table: &[[f32; 2]],
    dims: usize,
    numbers: &impl Fn(usize, u32) -> Drawn<'a>,
) {
    // Under hemisphere sampling a glossy continuation's light is not weighed against the
    // probes (`Transport::scatter_shaded`); a delta one's always is.
    let mis = M::DELTA || !t.rules.hemisphere;
    let mut cont = [false; L];
    let mut u = [[0.5f32; L]; 3];
    let mut calls = [[0.0f32; L]; 3];
    for j in 0..g.n {
        let d = depth[j];
        cont[j] = t.rules.continues(d) || (mis && t.rules.counts_direct(d));
        let row = g.row[j] * dims;
        let [a, b] = table[row];
        let uj = [a, b, table[row + crate::integrator::DIM_LOBE as usize][0]];
        put(&mut u, j, Vec3::from(uj));
        put(&mut calls, j, Vec3::from(g.model[j].sample_calls(uj)));
    }
    if !cont.iter().any(|&c| c) {
        return;
    }
    let mut rays = Rays::<L>::default();
    let mut pdf = [0.0f32; L];
    let mut delta = [M::DELTA; L];
    let mut weight = [[0.0f32; L]; 3];
    for j in 0..L {
        let l = soa.lane::<M>(j);
        let (s, ok) = l.model.sample_at(l.wo, get(&u, j).to_array(), get(&calls, j).to_array());
        let wi = l.frame.to_world(s.wi);
        let origin = offset_origin(l.p, l.p_error, l.ng, wi);
        rays.set(j, &Ray { origin, dir: wi, tmin: 0.0, tmax: f32::INFINITY });
        put(&mut weight, j, s.weight);
        pdf[j] = s.pdf;
        delta[j] = s.delta;
        rays.valid[j] = cont[j] & ok & (s.weight != Vec3::ZERO) & l.consistent(wi);
    }
    for j in 0..g.n {
        if !rays.valid[j] {
            continue;
        }
        let bounce = if M::DELTA || delta[j] {
            Bounce::DELTA
        } else if mis {
            Bounce { n: g.vertex[j].ns, pdf: pdf[j] }
        } else {
            Bounce::DIFFUSE
        };
        let u = || numbers(j, 0).at(crate::integrator::DIM_ROULETTE).next_f32();
        one_path::go_on(t, q, g.path[j], depth[j], rays.ray(j), get(&weight, j), bounce, u);
    }
}
