//! The material models as the leaving kernel ([`super::leave`]) shades them: each one's
//! value, density and sample written without branches, its parameters as numbers (the kernel
//! keeps them one array per parameter), and the rules by which its vertex takes light samples
//! and goes on. Lambert is one more model: the course's area-light samples, its MIS against
//! the cosine-sampled continuation where the rules call for it, and weights computed in the
//! order the one-path code computes them, so its rays are the same bits; the BSDF models
//! (glTF metallic-roughness and specular-glossiness, the layered glTF model, MTL PBR and
//! Phong, the rough conductor, mirror, glass) share the defaults: MIS by the power heuristic
//! against the BSDF's own sample, as [`Transport::direct_light_shaded`] computes it.
//!
//! What is per lane and irregular stays with the caller, one lane at a time: the model's
//! parameters at the vertex ([`Transport::model_at`], the layered model's sheen table) and
//! the library calls a sample needs ([`LaneModel::sample_calls`]: sine, cosine, logarithm).

use crate::bsdf::{BsdfSample, Dielectric, Distribution, Glossy, Lambert, Layered, Microfacet, Mirror, Pbr};
use crate::bsdf::{power_heuristic, to_local};
use crate::geometry::offset::offset_origin;
use crate::integrator::area::{LightRay, ShadingPoint, mis_weighted, triangle_ray};
use crate::integrator::light_ray::{LightPoint, diffuse_light_ray, glossy_light_ray, shadow_ray_to};
use crate::integrator::{Bounce, Transport, Vertex};
use crate::lights::{Emitter, area_to_solid_angle_lanes};
use crate::sampling::{Frame, warp};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Most numbers a model's parameters take (the layered glTF model's).
pub const PARAMS: usize = 24;

/// One lane's vertex as a model's functions read it, rebuilt from the group's arrays inside
/// each lane loop (the shape that vectorises).
pub struct Lane<M> {
    pub p: Vec3,
    pub p_error: Vec3,
    pub ng: Vec3,
    pub ns: Vec3,
    pub frame: Frame,
    /// Toward where the path came from, in the shading frame.
    pub wo: Vec3,
    pub model: M,
    pub bumped: bool,
}

impl<M> Lane<M> {
    /// [`Vertex::consistent`] for this lane.
    #[inline(always)]
    pub fn consistent(&self, wi: Vec3) -> bool {
        crate::integrator::consistent(self.bumped, self.ng, self.ns, wi)
    }

    #[inline(always)]
    pub fn point(&self) -> ShadingPoint {
        ShadingPoint { p: self.p, p_error: self.p_error, ng: self.ng, ns: self.ns }
    }
}

/// A model the leaving kernel shades. The defaults are the BSDF models' (light samples and
/// the continuation weighed against each other by the power heuristic); Lambert overrides
/// what the course and the diffuse rules say differently.
pub trait LaneModel: Copy {
    const NONE: Self;
    /// Delta lobes only (mirror, smooth glass): no light samples, and the continuation's
    /// light is not weighed against them ([`Bounce::DELTA`]).
    const DELTA: bool;
    /// How many of the [`PARAMS`] numbers the model uses (the kernel copies no more).
    const USED: usize = PARAMS;
    /// The continuation reads the lobe-choice number ([`crate::integrator::DIM_LOBE`]).
    const LOBE: bool = true;
    /// Area lights are sampled by the course's rule ([`crate::integrator::area::area_ray`]),
    /// weighted by [`area_weight`](Self::area_weight), not as any other light.
    const AREA_RAYS: bool = false;

    /// The model is made from the material alone ([`at_material`](Self::at_material)), so a
    /// kernel that reconstructs points in lanes builds no vertex for it.
    const FROM_MATERIAL: bool = false;

    fn params(&self) -> [f32; PARAMS];
    fn from_params(p: &[f32; PARAMS]) -> Self;

    /// The model of material `m` where it needs no more ([`Self::FROM_MATERIAL`]).
    #[inline(always)]
    fn at_material(_t: &Transport, _m: usize) -> Self {
        Self::NONE
    }

    /// The model at vertex `v` where the vertex alone makes it (without
    /// [`Transport::model_at`]).
    #[inline(always)]
    fn at_vertex(_v: &Vertex) -> Option<Self> {
        None
    }

    /// The model at a vertex for a ray arriving along `dir`: itself but for the layered
    /// model, which depends on that side.
    #[inline(always)]
    fn seen(self, _t: &Transport, _v: &Vertex, _dir: Vec3) -> Self {
        self
    }

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

    /// Whether the vertex takes light samples where the rules count direct light.
    #[inline(always)]
    fn takes_light(&self) -> bool {
        true
    }

    /// Whether light samples at `depth` are weighed by MIS (a delta light's density is then
    /// infinite).
    #[inline(always)]
    fn light_mis(_t: &Transport, _depth: u32) -> bool {
        true
    }

    /// Whether the light the continuation from `depth` finds is weighed against the light
    /// samples: a glossy one's is not under hemisphere sampling (`Transport::scatter_shaded`);
    /// a delta one's always is.
    #[inline(always)]
    fn continuation_mis(t: &Transport, _depth: u32) -> bool {
        Self::DELTA || !t.rules.hemisphere
    }

    /// Whether the vertex at `depth` sends a continuation: to go on, or to collect the light
    /// its MIS counts.
    #[inline(always)]
    fn continues(&self, t: &Transport, depth: u32) -> bool {
        t.rules.continues(depth) || (Self::continuation_mis(t, depth) && t.rules.counts_direct(depth))
    }

    /// The shadow ray and weight of light sample `lp` (`ns` samples a vertex, the light's
    /// shadow `margin`).
    #[inline(always)]
    fn light_ray(l: &Lane<Self>, lp: &LightPoint, margin: f32, ns: u32, _mis: bool) -> LightRay {
        let local = to_local(&l.frame, lp.wi);
        let (f, pdf_b) = l.model.eval_pdf(l.wo, local);
        glossy_light_ray(&l.point(), lp, local, f, pdf_b, margin, ns, l.consistent(lp.wi))
    }

    /// The shadow ray and weight toward `point` of emissive triangle `tri`, which emits `le`
    /// toward it, as `EmissiveTriangles::sample_pdf` and [`Transport::direct_light_shaded`]
    /// compute it.
    #[inline(always)]
    fn triangle_ray(
        l: &Lane<Self>,
        tri: &Emitter,
        point: Vec3,
        le: Vec3,
        margin: f32,
        ns: u32,
        _mis: bool,
    ) -> LightRay {
        let (wi, inv_pdf, ok) = area_to_solid_angle_lanes(l.p, point, tri.n, tri.inv_density, tri.one_sided);
        let pdf_l = 1.0 / inv_pdf;
        let local = to_local(&l.frame, wi);
        let (f, pdf_b) = l.model.eval_pdf(l.wo, local);
        let w = power_heuristic(ns as f32 * pdf_l, pdf_b);
        let origin = offset_origin(l.p, l.p_error, l.ng, wi);
        // `LightSampler::shadow_ray` toward the sampled point.
        let (ray, reach) = shadow_ray_to(origin, wi, point, true, margin);
        // An unpicked lane keeps an invalid triangle.
        let valid = tri.valid & ok & (f != Vec3::ZERO) & (w > 0.0) & l.consistent(wi) & reach;
        LightRay { ray, weight: f * (le * inv_pdf) * (local.z * w / ns as f32), valid }
    }

    /// An area light's factor for the model's samples of it (`ns` a vertex, its `radiance`),
    /// made once per light ([`Self::AREA_RAYS`] models only).
    #[inline(always)]
    fn area_scale(&self, _radiance: Vec3, _ns: u32) -> Vec3 {
        Vec3::ZERO
    }

    /// An area light's sample weight from the light's [`area_scale`](Self::area_scale) and
    /// the sample's geometric factor `g`.
    #[inline(always)]
    fn area_weight(_scale: Vec3, _g: f32, _ns: u32, _mis: bool) -> Vec3 {
        Vec3::ZERO
    }

    /// A hemisphere probe's weight toward `local` (one of `n` per vertex), and whether it
    /// can carry light.
    #[inline(always)]
    fn probe(l: &Lane<Self>, local: Vec3, n: u32) -> (Vec3, bool) {
        let (f, _) = l.model.eval_pdf(l.wo, local);
        (f * (local.z / (warp::UNIFORM_HEMISPHERE_PDF * n as f32)), f != Vec3::ZERO)
    }

    /// The continuation `s`'s solid-angle density and the reverse's (of the arriving
    /// direction, sampled from `s.wi`), as path+light weighs caustics by them.
    #[inline(always)]
    fn densities(l: &Lane<Self>, s: &BsdfSample) -> (f32, f32) {
        (s.pdf, l.model.eval_pdf(s.wi, l.wo).1)
    }

    /// What the light the continuation `s` (along `wi`, world) finds means.
    #[inline(always)]
    fn bounce(l: &Lane<Self>, s: &BsdfSample, _wi: Vec3, mis: bool) -> Bounce {
        if Self::DELTA || s.delta {
            Bounce::DELTA
        } else if mis {
            Bounce { n: l.ns, pdf: s.pdf }
        } else {
            Bounce::DIFFUSE
        }
    }
}

/// The Lambertian model as `Transport::direct_rays` and `Transport::scatter` shade it: the
/// course's area-light samples, MIS where [`Rules::diffuse_mis`](crate::integrator::rules::Rules::diffuse_mis)
/// says, the continuation cosine-weighted with the albedo as its weight.
impl LaneModel for Lambert {
    const NONE: Self = Lambert { albedo: Vec3::ZERO };
    const DELTA: bool = false;
    const USED: usize = 3;
    const LOBE: bool = false;
    const AREA_RAYS: bool = true;
    const FROM_MATERIAL: bool = true;

    #[inline(always)]
    fn params(&self) -> [f32; PARAMS] {
        let a = self.albedo;
        pad([a.x, a.y, a.z])
    }

    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        Lambert { albedo: Vec3::new(p[0], p[1], p[2]) }
    }

    #[inline(always)]
    fn at_material(t: &Transport, m: usize) -> Self {
        Lambert { albedo: t.materials.albedo[m] }
    }

    /// The vertex's albedo (textures, colours), as `Transport::model_at` makes it.
    #[inline(always)]
    fn at_vertex(v: &Vertex) -> Option<Self> {
        Some(Lambert { albedo: v.albedo })
    }

    #[inline(always)]
    fn sample_at(&self, _wo: Vec3, u: [f32; 3], _: [f32; 3]) -> (BsdfSample, bool) {
        let wi = warp::cosine_hemisphere(u[0], u[1]);
        (BsdfSample { wi, weight: self.albedo, pdf: 0.0, delta: false }, true)
    }

    #[inline(always)]
    fn takes_light(&self) -> bool {
        self.albedo * FRAC_1_PI != Vec3::ZERO
    }

    #[inline(always)]
    fn light_mis(t: &Transport, depth: u32) -> bool {
        t.rules.diffuse_mis(depth)
    }

    #[inline(always)]
    fn continuation_mis(t: &Transport, depth: u32) -> bool {
        t.rules.diffuse_mis(depth)
    }

    #[inline(always)]
    fn continues(&self, t: &Transport, depth: u32) -> bool {
        t.rules.diffuse_continues(depth) && self.albedo != Vec3::ZERO
    }

    #[inline(always)]
    fn light_ray(l: &Lane<Self>, lp: &LightPoint, margin: f32, ns: u32, mis: bool) -> LightRay {
        let inv = l.model.albedo * FRAC_1_PI / ns as f32;
        diffuse_light_ray(&l.point(), lp, inv, margin, ns, mis, l.consistent(lp.wi))
    }

    #[inline(always)]
    fn triangle_ray(l: &Lane<Self>, tri: &Emitter, point: Vec3, le: Vec3, margin: f32, ns: u32, mis: bool) -> LightRay {
        let inv = l.model.albedo * FRAC_1_PI / ns as f32;
        let mut r = triangle_ray(&l.point(), tri, point, le, inv, margin, ns, mis);
        r.valid &= l.consistent(r.ray.dir);
        r
    }

    #[inline(always)]
    fn area_scale(&self, radiance: Vec3, ns: u32) -> Vec3 {
        self.albedo * FRAC_1_PI / ns as f32 * radiance
    }

    #[inline(always)]
    fn area_weight(scale: Vec3, g: f32, ns: u32, mis: bool) -> Vec3 {
        scale * mis_weighted(g, ns, mis)
    }

    #[inline(always)]
    fn probe(l: &Lane<Self>, local: Vec3, n: u32) -> (Vec3, bool) {
        (l.model.albedo * FRAC_1_PI / (warp::UNIFORM_HEMISPHERE_PDF * n as f32) * local.z, true)
    }

    #[inline(always)]
    fn densities(l: &Lane<Self>, s: &BsdfSample) -> (f32, f32) {
        // Cosine-weighted both ways (the lane's sample leaves its density out).
        (s.wi.z.abs() * FRAC_1_PI, l.wo.z.abs() * FRAC_1_PI)
    }

    #[inline(always)]
    fn bounce(l: &Lane<Self>, _s: &BsdfSample, wi: Vec3, mis: bool) -> Bounce {
        // `Transport::diffuse_bounce`.
        if mis { Bounce { n: l.ns, pdf: wi.dot(l.ns).max(0.0) * FRAC_1_PI } } else { Bounce::DIFFUSE }
    }
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
    const USED: usize = 10;

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
    const USED: usize = 7;

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
    const USED: usize = 8;
    const LOBE: bool = false;

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
    const USED: usize = 3;
    const LOBE: bool = false;

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
    const USED: usize = 8;

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

    /// Seen from the direction the path arrives along (`Transport::shading`).
    #[inline(always)]
    fn seen(self, t: &Transport, v: &Vertex, dir: Vec3) -> Self {
        let cos_o = to_local(&Frame::new(v.ns), -dir).z;
        t.materials.layers.at(t, v, cos_o)
    }

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
