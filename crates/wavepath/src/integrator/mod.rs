//! What happens at one path vertex: emission, direct light (light or hemisphere sampling)
//! and the continuation ray, with the seed's semantics.
//!
//! The recursive reference calls the vertex code here one ray at a time; the wavefront
//! integrator's lane kernels (`wavefront::lanes`) leave vertices with the same per-sample
//! functions and the parts here (the vertex, arrivals, the rules), and are tested against
//! this vertex code bit for bit. Each vertex draws its random numbers from its own
//! stream (pixel, sample, depth), at fixed dimensions: 0 continuation direction (two numbers
//! from one hash), 2 Russian roulette, 3.. light or hemisphere samples (one dimension per
//! 2-d sample, plus one for a light that needs a third number).

pub mod area;
pub mod emitter_filter;
pub mod lane_width;
pub mod layers;
pub mod light_ray;
pub(crate) mod material;
pub mod plan;

// The parts of a `Transport`, each a type of its own that a stage (a lane kernel) reads.
pub mod camera;
pub mod light_sampler;
pub mod material_table;
pub mod rules;
pub mod streams;

pub mod bidir;
pub mod recursive;
pub mod wavefront;

pub use material::Bounce;

use crate::geometry::offset::offset_origin;

use area::ShadingPoint;
use camera::CameraTerms;
use light_sampler::LightSampler;
use material_table::MaterialTable;
use rules::Rules;
use streams::Streams;

use crate::geometry::{Hit, Ray};
use crate::lights::SampledLight;
use crate::sampling::{Frame, Numbers, warp};
use crate::scene::Scene;
use crate::settings::Settings;
use glam::{Vec2, Vec3};
use light_ray::LightPoint;
use std::f32::consts::FRAC_1_PI;

/// Dimension of a vertex stream that plays Russian roulette.
pub(crate) const DIM_ROULETTE: u32 = 2;
/// First dimension of a vertex stream used by light or hemisphere samples.
pub(crate) const DIM_DIRECT: u32 = 3;
/// Dimension that chooses between a material's lobes (unused by every other strategy: the
/// continuation's direction takes dimension 0 and light samples start at [`DIM_DIRECT`]).
pub(crate) const DIM_LOBE: u32 = 1;

/// Everything shading needs, precomputed once per render: the parts a stage reads, each its
/// own type, and the methods that need several of them.
pub struct Transport<'a> {
    pub scene: &'a Scene,
    /// The camera's terms (camera rays): the scene's camera fitted to the image by the
    /// settings, never the scene's own, which keeps the file's rule for other sizes.
    pub camera: CameraTerms,
    /// The seed and pattern every random number comes from.
    pub streams: Streams,
    /// The material table (albedo, emission, models, textures, layers).
    pub materials: MaterialTable<'a>,
    /// The light set, its sampling tables and shadow-ray margins.
    pub lights: LightSampler,
    /// Depth, what counts, direct-light strategy, MIS and roulette.
    pub rules: Rules,
    /// path+light: how camera paths weigh the caustics light tracing also draws.
    pub caustics: Option<bidir::caustics::CausticTerms>,
}

/// A hit point ready for shading, normals turned toward the incoming ray's side.
#[derive(Clone, Copy, Debug)]
pub struct Vertex {
    pub p: Vec3,
    /// Rounding error bound of `p` (see [`SurfacePoint::p_error`](crate::scene::SurfacePoint)).
    pub p_error: Vec3,
    pub ng: Vec3,
    pub ns: Vec3,
    pub albedo: Vec3,
    pub emission: Vec3,
    /// Metalness and roughness (glTF metallic-roughness materials; texture x factor).
    pub metal_rough: Vec2,
    pub material: u32,
    /// The ray hit the side the geometric normal points to (outside, for closed meshes).
    pub front: bool,
    /// Texture coordinates (zero unless the scene has textures).
    pub uv: Vec2,
    /// `ns` comes from a relief map: directions on different sides of `ng` and `ns` carry
    /// no light (see [`Vertex::consistent`]).
    pub bumped: bool,
}

impl Vertex {
    /// Whether a direction `wi` leaving the vertex is on the same side of the geometric
    /// surface as of the shading one: always for interpolated normals (the renderer's
    /// historical behaviour), checked for relief-mapped ones, whose tilted normals would
    /// otherwise let light leak through the surface.
    #[inline(always)]
    pub fn consistent(&self, wi: Vec3) -> bool {
        consistent(self.bumped, self.ng, self.ns, wi)
    }

    #[inline(always)]
    pub fn shading_point(&self) -> ShadingPoint {
        ShadingPoint { p: self.p, p_error: self.p_error, ng: self.ng, ns: self.ns }
    }
}

/// [`Vertex::consistent`] of a point with normals `ng`, `ns` (`bumped`: from a relief map),
/// for the lane kernels, which hold points rather than vertices.
#[inline(always)]
pub fn consistent(bumped: bool, ng: Vec3, ns: Vec3, wi: Vec3) -> bool {
    !bumped || (wi.dot(ng) > 0.0) == (wi.dot(ns) > 0.0)
}

/// The normals turned toward the side a ray along `dir` arrives from, and whether that is
/// the side the geometric normal points to.
#[inline(always)]
pub fn orient(geometric: Vec3, shading: Vec3, dir: Vec3) -> (Vec3, Vec3, bool) {
    let front = geometric.dot(dir) <= 0.0;
    let flip = if front { 1.0 } else { -1.0 };
    let ng = geometric * flip;
    // The shading normal goes to the same side as the geometric one.
    let ns = if shading.dot(ng) < 0.0 { -shading } else { shading };
    (ng, ns, front)
}

/// The uniform numbers one sample of `light` takes from `rng`: a 2-d pair (one hash) and a
/// third number only for a light that reads it.
#[inline]
pub fn light_numbers(rng: &mut impl Numbers, light: &SampledLight) -> [f32; 3] {
    let (a, b) = rng.next_2d();
    let c = if light.uses_third_number() { rng.next_f32() } else { 0.0 };
    [a, b, c]
}

/// A ray toward a light (`probe` false: any-hit, adds `weight` when unoccluded) or a
/// hemisphere sample (`probe` true: closest hit, adds `weight` times the emission it sees).
#[derive(Clone, Copy, Debug)]
pub struct DirectRay {
    pub ray: Ray,
    pub weight: Vec3,
}

impl<'a> Transport<'a> {
    /// The transport of `scene` under `settings`, whose effects (evaluated once per render,
    /// by the [`plan`](plan::RenderPlan)) are `effects`.
    pub fn new(scene: &'a Scene, settings: &Settings, effects: &crate::effects::Effects) -> Self {
        let lights = LightSampler::new(scene, settings);
        let rules = Rules::new(settings, effects, &lights.set);
        let camera = CameraTerms::new(&settings.image.camera(&scene.camera));
        let caustics = (settings.execution.integrator == crate::settings::IntegratorKind::PathLight)
            .then(|| {
                let sphere = bidir::scene_sphere(scene);
                bidir::caustics::CausticTerms::new(&camera, &lights.set, &sphere, settings)
            })
            .flatten();
        Transport {
            scene,
            camera,
            caustics,
            streams: Streams::new(settings),
            materials: MaterialTable::new(scene),
            rules,
            lights,
        }
    }

    /// Whether paths count the light their continuation rays find ([`arrival`](Self::arrival)):
    /// after glossy and delta bounces, and after diffuse ones under MIS.
    #[inline(always)]
    pub fn counts_arrivals(&self) -> bool {
        self.materials.non_diffuse || self.rules.mis
    }

    /// Whether a path whose ray will reach a vertex of `depth` needs that ray traced: always,
    /// except beyond the last vertex, where the ray only collects the light it arrives at and
    /// one that misses every emitter finds none ([`emitter_filter`]).
    #[inline]
    pub fn traces(&self, ray: &Ray, depth: u32) -> bool {
        match &self.lights.emitters {
            Some(f) if depth >= self.rules.max_depth => f.may_find_light(ray),
            _ => true,
        }
    }

    #[inline(always)]
    pub fn vertex(&self, ray: &Ray, hit: &Hit) -> Vertex {
        let sp = self.scene.surface_point_with(ray, hit, self.materials.textures.any());
        // The material from the render's table (one load for most meshes), as every shading
        // kernel reads it; the same id as `sp.material`.
        let material = self.materials.material_of(hit.prim) as u32;
        let bumped = self.materials.layers.any_relief && self.materials.layers.relief[material as usize];
        let (ng, ns, front) = if bumped {
            let n = self.scene.relief_normal(hit, sp.shading_normal, sp.uv, material);
            let (ng, ns, front) = orient(sp.geometric_normal, n, ray.dir);
            (ng, crate::scene::relief::keep_visible(ns, ng, -ray.dir), front)
        } else {
            orient(sp.geometric_normal, sp.shading_normal, ray.dir)
        };
        let m = material as usize;
        let emission = if front || self.materials.two_sided_emission[m] {
            self.materials.textures.emission(m, sp.uv).unwrap_or(self.materials.emission[m])
        } else {
            Vec3::ZERO
        };
        Vertex {
            p: sp.position,
            p_error: sp.p_error,
            ng,
            ns,
            albedo: self.materials.textures.albedo(m, sp.uv).unwrap_or(self.materials.albedo[m]) * sp.color,
            emission,
            metal_rough: self.materials.textures.metal_rough(m, sp.uv).unwrap_or(self.materials.metal_rough[m]),
            material,
            front,
            uv: sp.uv,
            bumped,
        }
    }

    /// Direct-light rays of the diffuse vertex `v` at `depth` (throughput not applied), handed
    /// to `out`; weighted by MIS against the cosine-sampled continuation where
    /// [`diffuse_mis`](rules::Rules::diffuse_mis) says so.
    #[inline]
    pub fn direct_rays(&self, v: &Vertex, depth: u32, mut rng: impl Numbers, mut out: impl FnMut(DirectRay)) {
        let f = v.albedo * FRAC_1_PI;
        if f == Vec3::ZERO {
            return;
        }
        rng = rng.at(DIM_DIRECT);
        if self.rules.hemisphere {
            let n = self.rules.direct_per_vertex;
            let frame = Frame::new(v.ns);
            let scale = f / (warp::UNIFORM_HEMISPHERE_PDF * n as f32);
            for _ in 0..n {
                let (a, b) = rng.next_2d();
                let local = warp::uniform_hemisphere(a, b);
                let wi = frame.to_world(local);
                if !v.consistent(wi) {
                    continue;
                }
                let origin = offset_origin(v.p, v.p_error, v.ng, wi);
                let ray = Ray { origin, dir: wi, tmin: 0.0, tmax: f32::INFINITY };
                out(DirectRay { ray, weight: scale * local.z });
            }
            return;
        }
        let mis = self.rules.diffuse_mis(depth);
        for i in 0..self.lights.set.lights.len() {
            self.direct_light(v, f, i, mis, &mut rng, &mut out);
        }
    }

    /// The light samples of the diffuse vertex `v` (BSDF value `f`) toward light `i`, drawn
    /// from `rng` at its current dimension ([`light_dims`](Self::light_dims) of them): one
    /// light's part of [`direct_rays`](Self::direct_rays). Every sample goes through the
    /// per-sample functions the lane kernel runs on its lanes ([`light_ray`], [`area`]).
    #[inline(always)]
    pub fn direct_light(
        &self,
        v: &Vertex,
        f: Vec3,
        i: usize,
        mis: bool,
        rng: &mut impl Numbers,
        out: &mut impl FnMut(DirectRay),
    ) {
        let light = &self.lights.set.lights[i];
        let ns = self.lights.set.samples_for(i, self.rules.light_samples);
        let inv = f / ns as f32;
        if let (Some(al), SampledLight::Area { radiance, .. }) = (&self.lights.area_lights[i], light) {
            let sp = v.shading_point();
            let c = inv * *radiance;
            for _ in 0..ns {
                let (a, b) = rng.next_2d();
                let r = area::area_ray(&sp, al, a, b);
                if r.valid && v.consistent(r.ray.dir) {
                    out(DirectRay { ray: r.ray, weight: c * area::mis_weighted(r.g, ns, mis) });
                }
            }
            return;
        }
        let (sp, margin) = (v.shading_point(), self.lights.shadow_margins[i]);
        for _ in 0..ns {
            let u = light_numbers(rng, light);
            let l = LightPoint::of(if mis {
                light.sample_pdf(v.p, v.ns, u)
            } else {
                light.sample(v.p, v.ns, u).map(|ls| (ls, 0.0))
            });
            let r = light_ray::diffuse_light_ray(&sp, &l, inv, margin, ns, mis, v.consistent(l.wi));
            if r.valid {
                out(DirectRay { ray: r.ray, weight: r.weight });
            }
        }
    }

    /// Dimensions of a vertex stream that the light samples of light `i` take (one per 2-d
    /// sample, two for a light that also reads a third number).
    #[inline(always)]
    pub fn light_dims(&self, i: usize) -> u32 {
        let ns = self.lights.set.samples_for(i, self.rules.light_samples);
        let third = self.lights.area_lights[i].is_none() && self.lights.set.lights[i].uses_third_number();
        ns * (1 + third as u32)
    }

    /// What a hemisphere probe ray sees: the emission it hits, or light from infinity.
    #[inline]
    pub fn probe_radiance(&self, ray: &Ray, hit: Option<&Hit>) -> Vec3 {
        match hit {
            Some(h) => {
                let m = self.materials.material_of(h.prim);
                if !self.materials.two_sided_emission[m] && !self.scene.front_face(ray, h) {
                    Vec3::ZERO
                } else if self.materials.textures.has_emission(m) {
                    let uv = self.scene.surface_point_with(ray, h, true).uv;
                    self.materials.textures.emission(m, uv).unwrap_or(self.materials.emission[m])
                } else {
                    self.materials.emission[m]
                }
            }
            None => self.lights.set.infinite.radiance(ray.dir),
        }
    }

    /// The continuation ray of a vertex at `depth`, the factor its throughput is multiplied
    /// by (cosine-weighted sampling of the diffuse BSDF: f cos / pdf = albedo), Russian
    /// roulette not yet applied, and what the light the ray finds means ([`Bounce`]).
    /// `None`: the path ends here.
    #[inline]
    pub fn scatter(&self, v: &Vertex, depth: u32, rng: impl Numbers) -> Option<(Ray, Vec3, Bounce)> {
        if !self.rules.diffuse_continues(depth) || v.albedo == Vec3::ZERO {
            return None;
        }
        let (a, b) = rng.at(0).next_2d();
        let sp = v.shading_point();
        let ray = area::cosine_ray(&sp, a, b);
        if !v.consistent(ray.dir) {
            return None;
        }
        Some((ray, v.albedo, self.diffuse_bounce(&sp, &ray, depth)))
    }

    /// The [`Bounce`] of a cosine-sampled continuation `ray` from `sp` at `depth`.
    #[inline(always)]
    pub fn diffuse_bounce(&self, sp: &ShadingPoint, ray: &Ray, depth: u32) -> Bounce {
        if self.rules.diffuse_mis(depth) {
            Bounce { n: sp.ns, pdf: ray.dir.dot(sp.ns).max(0.0) * FRAC_1_PI }
        } else {
            Bounce::DIFFUSE
        }
    }

    /// [`scatter`](Self::scatter) followed by [`roulette`](rules::Rules::roulette), for a path whose
    /// throughput before this vertex is `throughput`.
    #[inline]
    pub fn continuation(
        &self,
        v: &Vertex,
        depth: u32,
        rng: impl Numbers,
        throughput: Vec3,
    ) -> Option<(Ray, Vec3, Bounce)> {
        let (ray, w, b) = self.scatter(v, depth, rng)?;
        let k = self.rules.roulette(depth, rng, throughput * w)?;
        Some((ray, w * k, b))
    }

    /// The camera ray of sample `sample` of pixel (x, y): jittered inside the pixel (its
    /// centre when there is one sample per pixel, as the reference does), through the thin
    /// lens when the camera has an aperture.
    #[inline]
    pub fn camera_ray(&self, x: u32, y: u32, width: usize, height: usize, sample: u32, spp: u32) -> Ray {
        let key = self.streams.path_key(y * width as u32 + x, sample);
        self.camera_ray_keyed(x, y, width, height, key, spp)
    }

    /// [`camera_ray`](Self::camera_ray) for the path with key `key`.
    #[inline]
    pub fn camera_ray_keyed(&self, x: u32, y: u32, width: usize, height: usize, key: u64, spp: u32) -> Ray {
        self.camera.ray(x, y, width, height, self.streams.pattern.vertex(key, 0), spp)
    }
}
