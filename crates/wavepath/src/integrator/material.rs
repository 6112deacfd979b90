//! Shading of materials that are not Lambertian (mirror, glass, rough conductors) for the
//! recursive reference (the wavefront's lane kernels reach the same bits through the models'
//! `LaneModel` form), used only when the scene has such a material.
//!
//! Light is counted exactly once per path:
//! - Lambertian vertices: light sampling and the cosine-sampled ray, weighted by the power
//!   heuristic where the scene calls for MIS
//!   ([`Rules::diffuse_mis`](super::rules::Rules::diffuse_mis)); light sampling alone
//!   elsewhere and with `--no-mis`.
//! - Glossy vertices: light sampling and BSDF sampling, each weighted by the power
//!   heuristic against the other (the light strategy counted `-l` times), so a small bright
//!   light in a rough metal converges without fireflies. The BSDF-sampled ray counts what
//!   light sampling can find: area lights it reaches, emissive triangles (when they stand
//!   in for area lights) and light from infinity.
//! - Delta vertices (mirror, glass): no light sampling; the ray they send on counts the
//!   emission of the surface it hits, as a camera ray does, or the light from infinity.
//!
//! Either kind of arrival is direct light of the vertex that sampled the ray, so it counts
//! when that vertex's direct light would, and a vertex at the last depth still sends a ray
//! (which only collects this light).

use super::light_ray::{LightPoint, glossy_light_ray};
use super::{DIM_DIRECT, DIM_LOBE, DirectRay, Transport, Vertex, offset_origin};
use crate::bsdf::{Glossy, Kind, Lambert, Model, Pbr, power_heuristic, to_local};
use crate::geometry::{Hit, Ray};
use crate::lights::{SampledLight, Seen};
use crate::sampling::{Frame, Numbers, warp};
use crate::scene::Bsdf;
use glam::Vec3;

/// What the vertex that sampled a path's ray means for the light that ray finds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounce {
    /// Shading normal of that vertex (the infinite light's sampling density depends on it).
    pub n: Vec3,
    /// Solid-angle density of the BSDF sample: 0 for Lambertian vertices (nothing is
    /// counted), infinite after a delta bounce (emission counts fully).
    pub pdf: f32,
}

impl Bounce {
    pub const DIFFUSE: Bounce = Bounce { n: Vec3::ZERO, pdf: 0.0 };
    pub const DELTA: Bounce = Bounce { n: Vec3::ZERO, pdf: f32::INFINITY };
}

impl Default for Bounce {
    fn default() -> Self {
        Bounce::DIFFUSE
    }
}

/// A vertex's scattering model in its local frame.
#[derive(Clone, Copy, Debug)]
pub struct ShadingFrame {
    pub frame: Frame,
    /// Direction toward where the path came from, local.
    pub wo: Vec3,
    pub model: Model,
    pub kind: Kind,
}

impl Transport<'_> {
    /// The model of `v`'s material (a Lambertian one takes the vertex's albedo) for a ray
    /// arriving along `dir`.
    #[inline]
    pub fn shading(&self, v: &Vertex, dir: Vec3) -> ShadingFrame {
        let frame = Frame::new(v.ns);
        let wo = to_local(&frame, -dir);
        let model = match self.model_at(v) {
            Model::Layered(_) => Model::Layered(self.materials.layers.at(self, v, wo.z)),
            m => m,
        };
        ShadingFrame { frame, wo, kind: model.kind(), model }
    }

    /// The model of `v`'s material at the vertex, but for the layered glTF model, which also
    /// depends on the direction the ray arrives from ([`shading`](Self::shading) finishes it).
    #[inline]
    pub fn model_at(&self, v: &Vertex) -> Model {
        // By reference: the models that vary over the surface are rebuilt from a few numbers,
        // and only a dielectric's or a layered model's side changes the model (`oriented`).
        match &self.materials.models[v.material as usize] {
            Model::Lambert(_) => Model::Lambert(Lambert { albedo: v.albedo }),
            // The base colour (textures, vertex colours) and metalness vary over the surface.
            &Model::Pbr(p) => Model::Pbr(match self.scene.materials[v.material as usize].bsdf {
                Bsdf::MetallicRoughness { .. } => Pbr::metallic_roughness(v.albedo, v.metal_rough.x, v.metal_rough.y),
                Bsdf::SpecularGlossiness { specular, glossiness, .. } => {
                    match self.materials.textures.specular_glossiness(v.material as usize, v.uv) {
                        Some((s, g)) => Pbr::specular_glossiness(v.albedo, s, g),
                        None => Pbr::specular_glossiness(v.albedo, specular, glossiness),
                    }
                }
                _ => p,
            }),
            // The diffuse colour varies (map_Kd, vertex colours); the scaling that keeps
            // Kd + Ks <= 1 applies to it where it is looked up.
            &Model::Glossy(g) => match self.scene.materials[v.material as usize].bsdf {
                Bsdf::Phong { specular, shininess, .. } => Model::Glossy(Glossy::phong(v.albedo, specular, shininess)),
                _ => Model::Glossy(g),
            },
            m => m.oriented(v.front),
        }
    }

    /// [`direct_rays`](Self::direct_rays) for any material: none for delta materials,
    /// light samples weighted by MIS (or hemisphere probes) for glossy ones.
    #[inline]
    pub fn direct_rays_shaded(
        &self,
        v: &Vertex,
        sh: &ShadingFrame,
        depth: u32,
        rng: impl Numbers,
        mut out: impl FnMut(DirectRay),
    ) {
        match sh.kind {
            Kind::Diffuse => return self.direct_rays(v, depth, rng, out),
            Kind::Delta => return,
            Kind::Glossy => {}
        }
        let mut rng = rng.at(DIM_DIRECT);
        if self.rules.hemisphere {
            let n = self.rules.direct_per_vertex;
            for _ in 0..n {
                let (a, b) = rng.next_2d();
                let local = warp::uniform_hemisphere(a, b);
                let f = sh.model.eval(sh.wo, local);
                if f == Vec3::ZERO {
                    continue;
                }
                let wi = sh.frame.to_world(local);
                if !v.consistent(wi) {
                    continue;
                }
                let ray =
                    Ray { origin: offset_origin(v.p, v.p_error, v.ng, wi), dir: wi, tmin: 0.0, tmax: f32::INFINITY };
                out(DirectRay { ray, weight: f * (local.z / (warp::UNIFORM_HEMISPHERE_PDF * n as f32)) });
            }
            return;
        }
        for i in 0..self.lights.set.lights.len() {
            self.direct_light_shaded(v, sh, i, &mut rng, &mut out);
        }
    }

    /// The light samples of the glossy vertex `v` toward light `i`, drawn from `rng` at its
    /// current dimension: one light's part of [`direct_rays_shaded`](Self::direct_rays_shaded),
    /// through the per-sample function the glossy lane kernel runs on its lanes
    /// ([`glossy_light_ray`]).
    #[inline]
    pub fn direct_light_shaded(
        &self,
        v: &Vertex,
        sh: &ShadingFrame,
        i: usize,
        rng: &mut impl Numbers,
        out: &mut impl FnMut(DirectRay),
    ) {
        let light = &self.lights.set.lights[i];
        let ns = self.lights.set.samples_for(i, self.rules.light_samples);
        let (sp, margin) = (v.shading_point(), self.lights.shadow_margins[i]);
        for _ in 0..ns {
            let u = super::light_numbers(rng, light);
            let Some(s) = light.sample_pdf(v.p, v.ns, u) else { continue };
            let l = LightPoint::of(Some(s));
            let local = to_local(&sh.frame, l.wi);
            let (f, pdf_b) = sh.model.eval_pdf(sh.wo, local);
            let r = glossy_light_ray(&sp, &l, local, f, pdf_b, margin, ns, v.consistent(l.wi));
            if r.valid {
                out(DirectRay { ray: r.ray, weight: r.weight });
            }
        }
    }

    /// [`scatter`](Self::scatter) for any material, with what the sampled ray's arrival
    /// means ([`Bounce`]).
    #[inline]
    pub fn scatter_shaded(
        &self,
        v: &Vertex,
        sh: &ShadingFrame,
        depth: u32,
        rng: impl Numbers,
    ) -> Option<(Ray, Vec3, Bounce)> {
        let mis = match sh.kind {
            Kind::Diffuse => return self.scatter(v, depth, rng),
            Kind::Glossy => !self.rules.hemisphere,
            Kind::Delta => true,
        };
        if !(self.rules.continues(depth) || (mis && self.rules.counts_direct(depth))) {
            return None;
        }
        let (a, b) = rng.at(0).next_2d();
        let c = rng.at(DIM_LOBE).next_f32();
        let s = sh.model.sample(sh.wo, [a, b, c])?;
        if s.weight == Vec3::ZERO {
            return None;
        }
        let wi = sh.frame.to_world(s.wi);
        if !v.consistent(wi) {
            return None;
        }
        let bounce = if s.delta {
            Bounce::DELTA
        } else if mis {
            Bounce { n: v.ns, pdf: s.pdf }
        } else {
            Bounce::DIFFUSE
        };
        let origin = offset_origin(v.p, v.p_error, v.ng, wi);
        Some((Ray { origin, dir: wi, tmin: 0.0, tmax: f32::INFINITY }, s.weight, bounce))
    }

    /// [`scatter_shaded`](Self::scatter_shaded) followed by [`roulette`](super::rules::Rules::roulette),
    /// for a path whose throughput before this vertex is `throughput`.
    #[inline]
    pub fn continuation_shaded(
        &self,
        v: &Vertex,
        sh: &ShadingFrame,
        depth: u32,
        rng: impl Numbers,
        throughput: Vec3,
    ) -> Option<(Ray, Vec3, Bounce)> {
        let (ray, w, b) = self.scatter_shaded(v, sh, depth, rng)?;
        let k = self.rules.roulette(depth, rng, throughput * w)?;
        Some((ray, w * k, b))
    }

    /// [`Transport::arrival`] at a hit: nothing, without a call, where the surface does not
    /// emit and no area light can be in the way (most hits of most scenes; the out-of-line
    /// call cost the diffuse lane kernel 2-4% of its time).
    #[inline(always)]
    pub fn arrival_at_hit(&self, prev: Bounce, ray: &Ray, hit: &Hit, emission: Vec3, depth: u32) -> Vec3 {
        if emission == Vec3::ZERO && !self.lights.area_arrivals {
            return Vec3::ZERO;
        }
        self.arrival(prev, ray, Some(hit), emission, depth)
    }

    /// Light a path's ray (sampled at a vertex described by `prev`) finds at the vertex of
    /// `depth` it reaches (`hit`, whose surface emits `emission`) or, `hit` = `None`, at
    /// infinity; throughput not applied.
    #[inline]
    pub fn arrival(&self, prev: Bounce, ray: &Ray, hit: Option<&Hit>, emission: Vec3, depth: u32) -> Vec3 {
        if prev.pdf == 0.0 || !(self.rules.accumulate || depth == self.rules.max_depth) {
            return Vec3::ZERO;
        }
        if prev.pdf == f32::INFINITY {
            return match hit {
                Some(_) => emission,
                None => self.lights.set.infinite.radiance(ray.dir),
            };
        }
        if hit.is_none() && !self.lights.area_arrivals {
            // Only the light from infinity is found there.
            let inf = &self.lights.set.infinite;
            let (mapped, mapped_pdf) = inf.map.as_ref().map_or((Vec3::ZERO, 0.0), |m| m.lookup(ray.dir));
            return self.infinity_mis(prev, ray.dir, mapped, mapped_pdf, inf.map.is_some());
        }
        if hit.is_some() && emission == Vec3::ZERO && !self.lights.area_arrivals {
            // Only an area light (not geometry) is found on the way to a surface that does
            // not emit.
            return Vec3::ZERO;
        }
        let seen = match hit {
            None => Seen::Miss,
            Some(h) => Seen::Hit { t: h.t, emitter: self.emitter(h, emission) },
        };
        let mut l = Vec3::ZERO;
        for (i, light) in self.lights.set.lights.iter().enumerate() {
            if let Some((le, pdf_l)) = light.radiance_pdf(ray.origin, prev.n, ray.dir, seen) {
                let ns = self.lights.set.samples_for(i, self.rules.light_samples) as f32;
                l += le * power_heuristic(prev.pdf, ns * pdf_l);
            }
        }
        l
    }

    /// The light from infinity a BSDF-sampled ray (`prev`, neither diffuse nor delta) finds
    /// along `dir` when no area light is in the way, weighed by MIS against the light's own
    /// samples; the map's radiance and density toward `dir` looked up by the caller (read
    /// only when `has_map`). Branch-free: the lane kernel for escaped paths calls it on every
    /// lane.
    #[inline(always)]
    pub fn infinity_mis(&self, prev: Bounce, dir: Vec3, mapped: Vec3, mapped_pdf: f32, has_map: bool) -> Vec3 {
        let Some(i) = self.lights.infinite else { return Vec3::ZERO };
        let SampledLight::Infinite(inf) = &self.lights.set.lights[i] else { return Vec3::ZERO };
        let ns = self.lights.set.samples_for(i, self.rules.light_samples) as f32;
        super::light_ray::found_at_infinity(inf.sky(), ns, prev.n, prev.pdf, dir, mapped, mapped_pdf, has_map)
    }

    /// An emissive triangle's emission, geometric normal and index.
    #[inline]
    fn emitter(&self, h: &Hit, emission: Vec3) -> Option<(Vec3, Vec3, u32)> {
        if emission == Vec3::ZERO || h.prim as usize >= self.scene.mesh.triangles.len() {
            return None;
        }
        let [a, b, c] = self.scene.mesh.corners(h.prim as usize);
        Some((emission, (b - a).cross(c - a).try_normalize()?, h.prim))
    }
}
