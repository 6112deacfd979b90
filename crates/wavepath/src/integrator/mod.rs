//! What happens at one path vertex, shared by both integrators: emission, direct light
//! (light or hemisphere sampling) and the continuation ray, with the seed's semantics.
//!
//! The wavefront integrator spreads this work over queues and stages; the recursive
//! reference calls it one ray at a time. Each vertex draws its random numbers from its own
//! stream (pixel, sample, depth), at fixed dimensions: 0 continuation direction (two numbers
//! from one hash), 2 Russian roulette, 3.. light or hemisphere samples (one dimension per
//! 2-d sample, plus one for a light that needs a third number).

pub mod area;
pub mod layers;
mod material;
pub mod plan;

pub mod recursive;
pub mod wavefront;

pub use material::Bounce;

use crate::geometry::offset::{self, offset_origin, shadow_margin};

use area::{AreaLight, ShadingPoint};

use crate::bsdf::power_heuristic;
use crate::geometry::{Hit, Ray};
use crate::lights::{LightSet, SampledLight};
use crate::sampling::{Frame, Pattern, Sampler, warp};
use crate::scene::{Scene, Textures};
use crate::settings::{RouletteKind, Settings, Shading};
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// Dimension of a vertex stream that plays Russian roulette.
pub(crate) const DIM_ROULETTE: u32 = 2;
/// First dimension of a vertex stream used by light or hemisphere samples.
pub(crate) const DIM_DIRECT: u32 = 3;
/// Dimension that chooses between a material's lobes (unused by every other strategy: the
/// continuation's direction takes dimension 0 and light samples start at [`DIM_DIRECT`]).
const DIM_LOBE: u32 = 1;

/// Everything shading needs, precomputed once per render.
pub struct Transport<'a> {
    pub scene: &'a Scene,
    pub lights: LightSet,
    /// Per material: diffuse albedo and emitted radiance.
    pub albedo: Vec<Vec3>,
    pub emission: Vec<Vec3>,
    /// Per material: whether it emits from both faces or only from the front one.
    pub two_sided_emission: Vec<bool>,
    /// Per material: metalness and roughness factors (metallic-roughness materials).
    pub metal_rough: Vec<Vec2>,
    /// Per material: its scattering model (used only when `non_diffuse`).
    pub models: Vec<crate::bsdf::Model>,
    /// Some material is not Lambertian: shading goes through [`material::ShadingFrame`].
    pub non_diffuse: bool,
    /// Diffuse vertices weigh their light samples against their BSDF sample by MIS
    /// ([`diffuse_mis`](Self::diffuse_mis)) where the scene calls for it (the `mis` effect).
    pub mis: bool,
    /// Albedo textures per material; empty lookups when the scene has none.
    pub textures: Textures,
    pub max_depth: u32,
    pub accumulate: bool,
    pub hemisphere: bool,
    pub light_samples: u32,
    pub rr_continue: f32,
    /// Continue probability from the path's throughput instead of `rr_continue`.
    pub rr_throughput: bool,
    /// First depth that plays roulette.
    pub rr_depth: u32,
    pub seed: u64,
    /// How each pixel's samples spread over the path space (`--sampler`).
    pub pattern: Pattern,
    /// Shadow (or hemisphere probe) rays one vertex casts at most.
    pub direct_per_vertex: u32,
    /// tan(hfov / 2), tan(vfov / 2): the pinhole camera's image-plane half extents, computed
    /// once instead of per camera ray (the same values `Camera::generate_ray` computes).
    tan_half_fov: (f32, f32),
    /// Per light: its sampling data when it is an area light.
    pub area_lights: Vec<Option<AreaLight>>,
    /// Per light: [`shadow_margin`] of its points.
    shadow_margins: Vec<f32>,
    /// What the glTF material extensions need per render ([`layers::LayerData`]).
    pub layers: layers::LayerData,
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
        !self.bumped || (wi.dot(self.ng) > 0.0) == (wi.dot(self.ns) > 0.0)
    }

    #[inline(always)]
    pub fn shading_point(&self) -> ShadingPoint {
        ShadingPoint { p: self.p, p_error: self.p_error, ng: self.ng, ns: self.ns }
    }
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
pub fn light_numbers(rng: &mut Sampler, light: &SampledLight) -> [f32; 3] {
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
        let mut lights = LightSet::new(scene);
        if settings.cs184.light_pdf {
            lights.use_cs184_area_pdf();
        }
        let models: Vec<crate::bsdf::Model> = scene.materials.iter().map(crate::bsdf::Model::of_material).collect();
        let non_diffuse = models.iter().any(|m| m.kind() != crate::bsdf::Kind::Diffuse);
        let max_depth = if settings.paths.shading == Shading::Direct {
            settings.paths.max_depth.min(1)
        } else {
            settings.paths.max_depth
        };
        let light_samples = settings.sampling.light_samples.max(1);
        let direct_per_vertex = if settings.paths.hemisphere {
            // As the seed: as many hemisphere samples as light sampling would take for
            // area lights, lights x -l.
            (lights.lights.len() as u32 * light_samples).max(light_samples)
        } else {
            lights.samples_per_point(light_samples)
        };
        let shadow_margins: Vec<f32> = lights.lights.iter().map(|l| shadow_margin(l.point_error())).collect();
        let area_lights = lights
            .lights
            .iter()
            .zip(&shadow_margins)
            .map(|(l, &margin)| match *l {
                // The fast path computes the correct estimator only; the biased one goes
                // through the general light sample.
                SampledLight::Area { position, normal, dim_x, dim_y, area, cs184_pdf: false, .. } => {
                    Some(AreaLight { position, normal, dim_x, dim_y, area, margin })
                }
                _ => None,
            })
            .collect();
        Transport {
            area_lights,
            shadow_margins,
            layers: layers::LayerData::new(scene),
            scene,
            albedo: scene.materials.iter().map(|m| m.bsdf.diffuse_albedo()).collect(),
            emission: scene.materials.iter().map(|m| m.emission).collect(),
            two_sided_emission: scene.materials.iter().map(|m| m.two_sided_emission).collect(),
            metal_rough: scene
                .materials
                .iter()
                .map(|m| match m.bsdf {
                    crate::scene::Bsdf::MetallicRoughness { metallic, roughness, .. } => Vec2::new(metallic, roughness),
                    _ => Vec2::ZERO,
                })
                .collect(),
            models,
            non_diffuse,
            mis: effects.mis,
            textures: Textures::new(scene),
            lights,
            max_depth,
            accumulate: settings.paths.accumulate,
            hemisphere: settings.paths.hemisphere,
            light_samples,
            rr_continue: settings.paths.roulette.continue_prob.clamp(1e-3, 1.0),
            rr_throughput: settings.paths.roulette.kind == RouletteKind::Throughput,
            rr_depth: settings.paths.roulette.start_depth.max(1),
            seed: settings.sampling.seed,
            pattern: Pattern::new(settings.sampling.sampler, settings.sampling.spp),
            direct_per_vertex,
            tan_half_fov: (
                (scene.camera.hfov_deg.to_radians() * 0.5).tan(),
                (scene.camera.vfov_deg.to_radians() * 0.5).tan(),
            ),
        }
    }

    /// Whether emission seen directly by the camera is part of the image.
    #[inline]
    pub fn counts_emission(&self) -> bool {
        self.accumulate || self.max_depth == 0
    }

    /// Whether direct light at a vertex of `depth` (0 = the camera's hit) is part of the image:
    /// it took `depth + 1` bounces.
    #[inline]
    pub fn counts_direct(&self, depth: u32) -> bool {
        depth < self.max_depth && (self.accumulate || depth + 1 == self.max_depth)
    }

    /// Whether a diffuse vertex at `depth` combines its light samples with its continuation
    /// ray by the power heuristic. Only where that ray is traced and the light it finds
    /// counts: a vertex at the last depth keeps light sampling alone (no extra ray), as does
    /// every vertex under `-o 0`.
    #[inline(always)]
    pub fn diffuse_mis(&self, depth: u32) -> bool {
        self.mis && self.continues(depth) && self.counts_direct(depth)
    }

    /// Whether paths count the light their continuation rays find ([`arrival`](Self::arrival)):
    /// after glossy and delta bounces, and after diffuse ones under MIS.
    #[inline(always)]
    pub fn counts_arrivals(&self) -> bool {
        self.non_diffuse || self.mis
    }

    /// Whether a vertex of `depth` spawns a continuation ray.
    #[inline]
    pub fn continues(&self, depth: u32) -> bool {
        depth + 1 < self.max_depth
    }

    #[inline(always)]
    pub fn vertex(&self, ray: &Ray, hit: &Hit) -> Vertex {
        let sp = self.scene.surface_point_with(ray, hit, self.textures.any());
        let bumped = self.layers.any_relief && self.layers.relief[sp.material as usize];
        let (ng, ns, front) = if bumped {
            let n = self.scene.relief_normal(hit, sp.shading_normal, sp.uv, sp.material);
            let (ng, ns, front) = orient(sp.geometric_normal, n, ray.dir);
            (ng, crate::scene::relief::keep_visible(ns, ng, -ray.dir), front)
        } else {
            orient(sp.geometric_normal, sp.shading_normal, ray.dir)
        };
        let m = sp.material as usize;
        let emission = if front || self.two_sided_emission[m] {
            self.textures.emission(m, sp.uv).unwrap_or(self.emission[m])
        } else {
            Vec3::ZERO
        };
        Vertex {
            p: sp.position,
            p_error: sp.p_error,
            ng,
            ns,
            albedo: self.textures.albedo(m, sp.uv).unwrap_or(self.albedo[m]) * sp.color,
            emission,
            metal_rough: self.textures.metal_rough(m, sp.uv).unwrap_or(self.metal_rough[m]),
            material: sp.material,
            front,
            uv: sp.uv,
            bumped,
        }
    }

    /// The stream of the vertex at `depth` of path (pixel, sample).
    #[inline]
    pub fn sampler(&self, pixel: u32, sample: u32, depth: u32) -> Sampler {
        self.vertex_sampler(self.path_key(pixel, sample), depth)
    }

    /// The key of path (pixel, sample)'s random streams (see [`Pattern::path_key`]).
    #[inline]
    pub fn path_key(&self, pixel: u32, sample: u32) -> u64 {
        self.pattern.path_key(self.seed, pixel as u64, sample as u64)
    }

    /// The stream of the vertex at `depth` of the path with key `key`; the same numbers as
    /// [`sampler`](Self::sampler).
    #[inline]
    pub fn vertex_sampler(&self, key: u64, depth: u32) -> Sampler {
        self.pattern.vertex(key, depth + 1)
    }

    /// Direct-light rays of the diffuse vertex `v` at `depth` (throughput not applied), handed
    /// to `out`; weighted by MIS against the cosine-sampled continuation where
    /// [`diffuse_mis`](Self::diffuse_mis) says so.
    #[inline]
    pub fn direct_rays(&self, v: &Vertex, depth: u32, mut rng: Sampler, mut out: impl FnMut(DirectRay)) {
        let f = v.albedo * FRAC_1_PI;
        if f == Vec3::ZERO {
            return;
        }
        rng = rng.at(DIM_DIRECT);
        if self.hemisphere {
            let n = self.direct_per_vertex;
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
        let sp = v.shading_point();
        let mis = self.diffuse_mis(depth);
        for (i, light) in self.lights.lights.iter().enumerate() {
            let ns = self.lights.samples_for(i, self.light_samples);
            let inv = f / ns as f32;
            if let (Some(al), SampledLight::Area { radiance, .. }) = (&self.area_lights[i], light) {
                let c = inv * *radiance;
                for _ in 0..ns {
                    let (a, b) = rng.next_2d();
                    let r = area::area_ray(&sp, al, a, b);
                    if r.valid && v.consistent(r.ray.dir) {
                        out(DirectRay { ray: r.ray, weight: c * area::mis_weighted(r.g, ns, mis) });
                    }
                }
                continue;
            }
            for _ in 0..ns {
                let u = light_numbers(&mut rng, light);
                let (ls, w) = if mis {
                    let Some((ls, pdf_l)) = light.sample_pdf(v.p, v.ns, u) else { continue };
                    let w = power_heuristic(ns as f32 * pdf_l, ls.wi.dot(v.ns).max(0.0) * FRAC_1_PI);
                    (ls, w)
                } else {
                    let Some(ls) = light.sample(v.p, v.ns, u) else { continue };
                    (ls, 1.0)
                };
                let cos = ls.wi.dot(v.ns);
                if cos <= 0.0 || w <= 0.0 || !v.consistent(ls.wi) {
                    continue;
                }
                let origin = offset_origin(v.p, v.p_error, v.ng, ls.wi);
                let Some(ray) = self.light_shadow_ray(i, origin, ls.wi, ls.target) else { continue };
                out(DirectRay { ray, weight: inv * ls.weight * (cos * w) });
            }
        }
    }

    /// The shadow ray of light `i` from `origin` along `dir` or, for a light point `target`,
    /// toward it ([`shadow_ray`] with the light's margin precomputed).
    #[inline]
    pub fn light_shadow_ray(&self, i: usize, origin: Vec3, dir: Vec3, target: Option<Vec3>) -> Option<Ray> {
        let Some(q) = target else {
            return Some(Ray { origin, dir, tmin: 0.0, tmax: f32::INFINITY });
        };
        let e = q - origin;
        let len = e.length();
        let rcp = 1.0 / len;
        if !(rcp.is_finite() && rcp > 0.0) {
            return None;
        }
        let dir = e * rcp;
        let tmax = offset::shadow_tmax_at(len, self.shadow_margins[i]);
        (tmax > 0.0).then_some(Ray { origin, dir, tmin: 0.0, tmax })
    }

    /// What a hemisphere probe ray sees: the emission it hits, or light from infinity.
    #[inline]
    pub fn probe_radiance(&self, ray: &Ray, hit: Option<&Hit>) -> Vec3 {
        match hit {
            Some(h) => {
                let m = self.material_of(h.prim);
                if !self.two_sided_emission[m] && !self.scene.front_face(ray, h) {
                    Vec3::ZERO
                } else if self.textures.has_emission(m) {
                    let uv = self.scene.surface_point_with(ray, h, true).uv;
                    self.textures.emission(m, uv).unwrap_or(self.emission[m])
                } else {
                    self.emission[m]
                }
            }
            None => self.lights.infinite.radiance(ray.dir),
        }
    }

    #[inline]
    pub fn material_of(&self, prim: u32) -> usize {
        let ntri = self.scene.mesh.triangles.len();
        let p = prim as usize;
        if p < ntri { self.scene.mesh.material_ids[p] as usize } else { self.scene.spheres[p - ntri].material as usize }
    }

    /// The continuation ray of a vertex at `depth`, the factor its throughput is multiplied
    /// by (cosine-weighted sampling of the diffuse BSDF: f cos / pdf = albedo), Russian
    /// roulette not yet applied, and what the light the ray finds means ([`Bounce`]).
    /// `None`: the path ends here.
    #[inline]
    pub fn scatter(&self, v: &Vertex, depth: u32, rng: Sampler) -> Option<(Ray, Vec3, Bounce)> {
        if !self.continues(depth) || v.albedo == Vec3::ZERO {
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
        if self.diffuse_mis(depth) {
            Bounce { n: sp.ns, pdf: ray.dir.dot(sp.ns).max(0.0) * FRAC_1_PI }
        } else {
            Bounce::DIFFUSE
        }
    }

    /// Russian roulette for the continuation of a vertex at `depth` whose path throughput,
    /// the continuation's BSDF weight included, is `throughput`: `None` stops the path,
    /// otherwise the factor (1 / continue probability) its throughput is multiplied by. It
    /// is played from depth `rr_depth` on (at least 1: it never stops the first indirect
    /// bounce, the continuation of the camera's hit).
    #[inline]
    pub fn roulette(&self, depth: u32, rng: Sampler, throughput: Vec3) -> Option<f32> {
        if !self.plays_roulette(depth) {
            return Some(1.0);
        }
        self.roulette_with(rng.at(DIM_ROULETTE).next_f32(), throughput)
    }

    /// Whether the continuation of a vertex at `depth` plays Russian roulette.
    #[inline(always)]
    pub fn plays_roulette(&self, depth: u32) -> bool {
        depth >= self.rr_depth && (self.rr_throughput || self.rr_continue < 1.0)
    }

    /// [`roulette`](Self::roulette) where it is played, from the vertex stream's number at
    /// [`DIM_ROULETTE`] (drawn eight paths at a time by the lane kernel). By throughput, the
    /// surviving path's throughput has its largest component at most 1: its weight stays
    /// bounded, and paths that carry little are the ones that stop.
    #[inline(always)]
    pub fn roulette_with(&self, u: f32, throughput: Vec3) -> Option<f32> {
        let p = if self.rr_throughput { throughput.max_element().min(1.0) } else { self.rr_continue };
        if p >= 1.0 {
            return Some(1.0);
        }
        (u < p).then(|| 1.0 / p)
    }

    /// [`scatter`](Self::scatter) followed by [`roulette`](Self::roulette), for a path whose
    /// throughput before this vertex is `throughput`.
    #[inline]
    pub fn continuation(&self, v: &Vertex, depth: u32, rng: Sampler, throughput: Vec3) -> Option<(Ray, Vec3, Bounce)> {
        let (ray, w, b) = self.scatter(v, depth, rng)?;
        let k = self.roulette(depth, rng, throughput * w)?;
        Some((ray, w * k, b))
    }

    /// The camera ray of sample `sample` of pixel (x, y): jittered inside the pixel (its
    /// centre when there is one sample per pixel, as the reference does), through the thin
    /// lens when the camera has an aperture.
    #[inline]
    pub fn camera_ray(&self, x: u32, y: u32, width: usize, height: usize, sample: u32, spp: u32) -> Ray {
        let key = self.path_key(y * width as u32 + x, sample);
        self.camera_ray_keyed(x, y, width, height, key, spp)
    }

    /// [`camera_ray`](Self::camera_ray) for the path with key `key`.
    #[inline]
    pub fn camera_ray_keyed(&self, x: u32, y: u32, width: usize, height: usize, key: u64, spp: u32) -> Ray {
        let mut rng = self.pattern.vertex(key, 0);
        let (jx, jy) = if spp <= 1 { (0.5, 0.5) } else { rng.next_2d() };
        let cam = &self.scene.camera;
        if cam.lens_radius > 0.0 || cam.orthographic {
            let (px, py) = ((x as f32 + jx) / width as f32, (y as f32 + jy) / height as f32);
            let mut lr = rng.at(2);
            let (a, b) = lr.next_2d();
            cam.generate_lens_ray(px, py, warp::concentric_disk(a, b))
        } else {
            self.pinhole_ray(x, y, width, height, jx, jy)
        }
    }

    /// Whether camera rays are [`pinhole_ray`](Self::pinhole_ray)s (no aperture, not
    /// orthographic).
    #[inline]
    pub fn pinhole(&self) -> bool {
        self.scene.camera.lens_radius <= 0.0 && !self.scene.camera.orthographic
    }

    /// The pinhole camera's ray through (x + jx, y + jy): `Camera::generate_ray` with the
    /// field of view's tangents precomputed. Branch-free, so a loop over lanes vectorises.
    #[inline(always)]
    pub fn pinhole_ray(&self, x: u32, y: u32, width: usize, height: usize, jx: f32, jy: f32) -> Ray {
        let (px, py) = ((x as f32 + jx) / width as f32, (y as f32 + jy) / height as f32);
        let cam = &self.scene.camera;
        let (tw, th) = self.tan_half_fov;
        let d = Vec3::new((px - 0.5) * 2.0 * tw, (py - 0.5) * 2.0 * th, -1.0);
        Ray { origin: cam.position, dir: (cam.c2w * d).normalize(), tmin: cam.nclip, tmax: cam.fclip }
    }
}
