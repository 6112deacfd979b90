//! Shade for the common case, eight paths at a time: Lambertian materials, light sampling,
//! only area lights. What is per path and irregular (the hit's surface point, the random
//! numbers) is gathered one path at a time into structure-of-arrays lanes; the light
//! samples, offsets, shadow-ray setup and the continuation rays then run lane-parallel:
//! [`crate::integrator::area`]'s branch-free per-sample functions in fixed loops of 8 lanes
//! that the compiler vectorises (8 square roots and divisions per instruction instead of
//! one). The functions are the ones the one-vertex-at-a-time code calls, so the image is
//! the same, bit for bit, as [`super::shade::shade`]'s.
//!
//! The lane kernel is compiled with AVX2 and FMA enabled (behind run-time detection; Rust
//! never contracts `a * b + c` into an FMA, so the bits do not change) and everything it
//! calls is `#[inline(always)]`: a helper left out of line would be compiled without AVX2.

use super::Features;
use super::queues::{PathQueue, ShadowQueue, ShadowSlots};
use crate::cpu::Avx2;
use crate::geometry::{Hit, Ray};
use crate::integrator::area::{AreaLight, ShadingPoint, area_ray, cosine_ray};
use crate::integrator::{Bounce, DIM_DIRECT, DIM_ROULETTE, Transport, orient};
use crate::lights::SampledLight;
use crate::sampling::{Sampler, SamplerKind, rng8};
use crate::scene::surface::{interpolated_normal, sphere_point, triangle_point};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Paths per group.
const L: usize = 8;

/// Whether the lane kernel can shade this render's paths: Lambertian materials without
/// textures, light sampling (not hemisphere probes) without MIS, and nothing but area lights. Decided once
/// per render, with the kernel (`super::Lanes`).
pub fn can_shade(t: &Transport, non_diffuse: bool) -> bool {
    !non_diffuse
        && !t.rules.hemisphere
        && !t.rules.mis
        && t.materials.two_sided_emission.iter().all(|&two| two)
        && !t.materials.textures.any()
        && !t.materials.layers.any_relief
        && t.scene.mesh.colors.is_none()
        && t.lights.area_lights.iter().all(Option::is_some)
}

/// [`super::shade::shade`] eight paths at a time (for renders where [`can_shade`] holds).
#[cfg(target_arch = "x86_64")]
pub fn shade_lanes<F: Features>(avx: Avx2, t: &Transport, q: &mut PathQueue, shadow: &mut ShadowQueue) {
    // SAFETY: the token proves the CPU has AVX2 and FMA.
    unsafe { shade_avx2::<F>(avx, t, q, shadow) }
}

/// The kernel compiled with exactly the features it uses: run through `cpu::with_avx2` (which
/// also enables BMI1 and POPCNT, for the BVH) it compiled to 4.7% more instructions
/// (callgrind, CBspheres_lambertian 128x96, shade stage).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn shade_avx2<F: Features>(avx: Avx2, t: &Transport, q: &mut PathQueue, shadow: &mut ShadowQueue) {
    shade_groups::<F>(avx, t, q, shadow)
}

/// The shading points of a group, one array per component.
#[derive(Default)]
struct Points {
    p: [[f32; L]; 3],
    e: [[f32; L]; 3],
    ng: [[f32; L]; 3],
    ns: [[f32; L]; 3],
}

impl Points {
    #[inline(always)]
    fn set(&mut self, j: usize, s: &ShadingPoint) {
        for (a, v) in [(&mut self.p, s.p), (&mut self.e, s.p_error), (&mut self.ng, s.ng), (&mut self.ns, s.ns)] {
            a[0][j] = v.x;
            a[1][j] = v.y;
            a[2][j] = v.z;
        }
    }

    #[inline(always)]
    fn get(&self, j: usize) -> ShadingPoint {
        ShadingPoint { p: get(&self.p, j), p_error: get(&self.e, j), ng: get(&self.ng, j), ns: get(&self.ns, j) }
    }
}

/// What the surface points of a group are reconstructed from: a triangle's corners (and
/// corner normals) and barycentrics, or a sphere and the ray's hit point on it.
#[derive(Default)]
struct Surfaces {
    corner: [[[f32; L]; 3]; 3],
    normal: [[[f32; L]; 3]; 3],
    u: [f32; L],
    v: [f32; L],
    center: [[f32; L]; 3],
    radius: [f32; L],
    hit: [[f32; L]; 3],
    dir: [[f32; L]; 3],
    triangle: [bool; L],
}

#[inline(always)]
fn put(a: &mut [[f32; L]; 3], j: usize, v: Vec3) {
    a[0][j] = v.x;
    a[1][j] = v.y;
    a[2][j] = v.z;
}

#[inline(always)]
fn get(a: &[[f32; L]; 3], j: usize) -> Vec3 {
    Vec3::new(a[0][j], a[1][j], a[2][j])
}

impl Surfaces {
    /// Gathers lane `j`'s hit (prim `prim`, on `ray`); `normals` is the mesh's corner
    /// normals, looked up once per stage rather than once per corner.
    #[inline(always)]
    fn set(&mut self, t: &Transport, normals: Option<&[Vec3]>, j: usize, ray: &Ray, hit: &Hit) {
        let mesh = &t.scene.mesh;
        let prim = hit.prim as usize;
        put(&mut self.dir, j, ray.dir);
        self.triangle[j] = prim < mesh.triangles.len();
        if self.triangle[j] {
            let ids = mesh.triangles[prim];
            for (k, &id) in ids.iter().enumerate() {
                put(&mut self.corner[k], j, mesh.positions[id as usize]);
            }
            if let Some(n) = normals {
                for (k, &id) in ids.iter().enumerate() {
                    put(&mut self.normal[k], j, n[id as usize]);
                }
            }
            (self.u[j], self.v[j]) = (hit.u, hit.v);
        } else {
            let s = &t.scene.spheres[prim - mesh.triangles.len()];
            put(&mut self.center, j, s.center);
            self.radius[j] = s.radius;
            put(&mut self.hit, j, ray.at(hit.t));
        }
    }

    /// Lane `j`'s shading point: both reconstructions (the same functions as
    /// `Scene::surface_point`), one kept, so all lanes run the same instructions; only the
    /// triangle's when the scene has no spheres (`SPHERES` false).
    #[inline(always)]
    fn point<const NORMALS: bool, const SPHERES: bool>(&self, j: usize) -> ShadingPoint {
        let (u, v) = (self.u[j], self.v[j]);
        let c = &self.corner;
        let (tp, te, tn) = triangle_point(get(&c[0], j), get(&c[1], j), get(&c[2], j), u, v);
        let ts = if NORMALS {
            let n = &self.normal;
            interpolated_normal([get(&n[0], j), get(&n[1], j), get(&n[2], j)], u, v, tn)
        } else {
            tn
        };
        let (p, p_error, g, sh) = if SPHERES {
            let (sp, se, sn) = sphere_point(get(&self.center, j), self.radius[j], get(&self.hit, j));
            if self.triangle[j] { (tp, te, tn, ts) } else { (sp, se, sn, sn) }
        } else {
            (tp, te, tn, ts)
        };
        let (ng, ns, _) = orient(g, sh, get(&self.dir, j));
        ShadingPoint { p, p_error, ng, ns }
    }
}

/// Reconstructs the shading points of all lanes (lane-parallel).
#[inline(always)]
fn surface_points(s: &Surfaces, normals: bool, spheres: bool, out: &mut Points) {
    // Plain loops, no closures: a closure may be compiled out of line, without AVX2.
    match (normals, spheres) {
        (true, true) => points_of::<true, true>(s, out),
        (true, false) => points_of::<true, false>(s, out),
        (false, true) => points_of::<false, true>(s, out),
        (false, false) => points_of::<false, false>(s, out),
    }
}

#[inline(always)]
fn points_of<const NORMALS: bool, const SPHERES: bool>(s: &Surfaces, out: &mut Points) {
    for j in 0..L {
        out.set(j, &s.point::<NORMALS, SPHERES>(j));
    }
}

/// A group's rays, one array per component.
#[derive(Default)]
struct Rays {
    o: [[f32; L]; 3],
    d: [[f32; L]; 3],
    tmax: [f32; L],
    g: [f32; L],
    valid: [bool; L],
}

impl Rays {
    #[inline(always)]
    fn set(&mut self, j: usize, r: &Ray) {
        for (a, v) in [(&mut self.o, r.origin), (&mut self.d, r.dir)] {
            a[0][j] = v.x;
            a[1][j] = v.y;
            a[2][j] = v.z;
        }
        self.tmax[j] = r.tmax;
    }

    #[inline(always)]
    fn ray(&self, j: usize) -> Ray {
        Ray { origin: get(&self.o, j), dir: get(&self.d, j), tmin: 0.0, tmax: self.tmax[j] }
    }
}

/// `u` where `used`, else 0.5 (a lane whose sample is not taken computes on a harmless value).
#[inline(always)]
fn unused_half(u: [f32; L], used: &[bool; L]) -> [f32; L] {
    let mut out = [0.5; L];
    for j in 0..L {
        if used[j] {
            out[j] = u[j];
        }
    }
    out
}

/// The shadow rays toward light `l` of all lanes (lane-parallel).
#[inline(always)]
fn area_rays(pts: &Points, l: &AreaLight, ua: &[f32; L], ub: &[f32; L], out: &mut Rays) {
    for j in 0..L {
        let r = area_ray(&pts.get(j), l, ua[j], ub[j]);
        out.set(j, &r.ray);
        out.g[j] = r.g;
        out.valid[j] = r.valid;
    }
}

/// The continuation rays of all lanes (lane-parallel).
#[inline(always)]
fn cosine_rays(pts: &Points, ua: &[f32; L], ub: &[f32; L], out: &mut Rays) {
    for j in 0..L {
        let r = cosine_ray(&pts.get(j), ua[j], ub[j]);
        out.set(j, &r);
    }
}

/// The lanes of a wave, eight paths at a time; the random numbers are drawn eight streams
/// at a time (hence the token).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn shade_groups<F: Features>(avx: Avx2, t: &Transport, q: &mut PathQueue, shadow: &mut ShadowQueue) {
    shadow.clear();
    let sees_emission = t.rules.counts_emission();
    let n = q.len();
    let mut pts = Points::default();
    let mut rays = Rays::default();
    let mut surf = Surfaces::default();
    let corner_normals = t.scene.mesh.normals.as_deref();
    let normals = corner_normals.is_some();
    let spheres = !t.scene.spheres.is_empty();
    let mut pending: Vec<Rays> = Vec::new();
    let hashed = t.streams.pattern.kind == SamplerKind::Independent;
    for base in (0..n).step_by(L) {
        let m = (n - base).min(L);
        let mut vertex_input = [0u64; L];
        let mut patterned = [Sampler::default(); L];
        let mut albedo = [Vec3::ZERO; L];
        let mut direct = [false; L];
        let mut cont = [false; L];
        // Gather, one path at a time.
        for j in 0..m {
            let i = base + j;
            let depth = q.depth[i];
            q.alive[i] = false;
            let Some(hit) = q.hit[i] else {
                if F::ENVIRONMENT && depth == 0 && sees_emission {
                    q.radiance[i] += q.throughput[i] * t.lights.set.background_toward(q.ray[i].dir);
                }
                continue;
            };
            let m = t.materials.material_of(hit.prim);
            if F::EMISSION && depth == 0 && sees_emission {
                q.radiance[i] += t.materials.emission[m];
            }
            if !F::DIRECT && !F::INDIRECT {
                continue;
            }
            // As `Transport::vertex_sampler`, hashed for all lanes below.
            vertex_input[j] = Sampler::vertex_input(q.key[i], depth + 1);
            if !hashed {
                patterned[j] = t.streams.vertex_sampler(q.key[i], depth);
            }
            surf.set(t, corner_normals, j, &q.ray[i], &hit);
            albedo[j] = t.materials.albedo[m];
            // As `Transport::direct_rays` and `Transport::scatter` decide.
            direct[j] = F::DIRECT && t.rules.counts_direct(depth) && albedo[j] * FRAC_1_PI != Vec3::ZERO;
            cont[j] = F::INDIRECT && t.rules.continues(depth) && albedo[j] != Vec3::ZERO;
        }
        if !direct.iter().chain(&cont).any(|&b| b) {
            continue;
        }
        // Patterned streams (stratified, Sobol) are drawn one lane at a time by `rng8`.
        let rng = if hashed { rng8::for_vertex_x8(avx, &vertex_input) } else { patterned };
        surface_points(&surf, normals, spheres, &mut pts);
        if F::DIRECT && direct.iter().any(|&d| d) {
            let mut dim = DIM_DIRECT;
            for (li, light) in t.lights.set.lights.iter().enumerate() {
                let (Some(al), SampledLight::Area { radiance, .. }) = (&t.lights.area_lights[li], light) else {
                    unreachable!("the lane kernel runs only with area lights")
                };
                let ns = t.lights.set.samples_for(li, t.rules.light_samples);
                let mut c = [Vec3::ZERO; L];
                for j in 0..L {
                    c[j] = albedo[j] * FRAC_1_PI / ns as f32 * *radiance;
                }
                // Sample-major here (lane-parallel), pushed path-major below: the rays of
                // one point sit together in the queue, where the shadow stage traces them
                // as one packet (each path still adds its own in sample order).
                if pending.len() < ns as usize {
                    pending.resize_with(ns as usize, Rays::default);
                }
                for p in pending.iter_mut().take(ns as usize) {
                    let (ua, ub) = rng8::next_2d_x8(avx, &rng, dim);
                    let (ua, ub) = (unused_half(ua, &direct), unused_half(ub, &direct));
                    dim += 1;
                    area_rays(&pts, al, &ua, &ub, p);
                }
                // Every candidate is stored; the cursor moves past the valid ones only.
                let samples = &pending[..ns as usize];
                let ShadowSlots { ray: rs, weight: ws, owner: os } = shadow.open(m * samples.len());
                let mut w = 0;
                for j in 0..m {
                    if !direct[j] {
                        continue;
                    }
                    let tp = q.throughput[base + j];
                    let owner = (base + j) as u32;
                    for p in samples {
                        rs[w] = p.ray(j);
                        ws[w] = c[j] * p.g[j] * tp;
                        os[w] = owner;
                        w += p.valid[j] as usize;
                    }
                }
                shadow.commit(w);
            }
        }
        if F::INDIRECT && cont.iter().any(|&c| c) {
            let (ua, ub) = rng8::next_2d_x8(avx, &rng, 0);
            let (ua, ub) = (unused_half(ua, &cont), unused_half(ub, &cont));
            let rr = if F::ROULETTE { rng8::next_f32_x8(avx, &rng, DIM_ROULETTE) } else { [0.0; L] };
            cosine_rays(&pts, &ua, &ub, &mut rays);
            for j in 0..m {
                if cont[j] {
                    let i = base + j;
                    let depth = q.depth[i];
                    q.ray[i] = rays.ray(j);
                    // As `Transport::diffuse_bounce` without MIS.
                    q.bounce[i] = Bounce::DIFFUSE;
                    q.throughput[i] *= albedo[j];
                    q.depth[i] = depth + 1;
                    q.alive[i] = true;
                    // As `super::shade::roulette`.
                    if F::ROULETTE && t.rules.plays_roulette(depth) {
                        match t.rules.roulette_with(rr[j], q.throughput[i]) {
                            Some(f) => q.throughput[i] *= f,
                            None => q.alive[i] = false,
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{BruteForce, TraceCounters};
    use crate::integrator::wavefront::generate::{Wave, generate};
    use crate::integrator::wavefront::{Kernel, compact, shade, traverse};
    use crate::settings::{RouletteKind, Settings, Shading};

    type K = Kernel<true, false, true, true, true, false>;

    /// Each path's shadow rays (in the order they were made) and weights, by owner.
    fn by_owner(s: &ShadowQueue, n: usize) -> Vec<Vec<(Ray, Vec3)>> {
        let mut out = vec![Vec::new(); n];
        for k in 0..s.len() {
            out[s.owner()[k] as usize].push((s.ray()[k], s.weight()[k]));
        }
        out
    }

    /// The lane kernel gives every path the same continuation, throughput, radiance and
    /// shadow rays (bit for bit) as the one-path-at-a-time kernel, over five bounces, on
    /// triangles with and without corner normals, with spheres and without any.
    #[test]
    fn lanes_match_the_scalar_kernel() {
        for (with_normals, with_spheres, rr_throughput) in
            [(false, true, false), (true, true, false), (true, false, false), (true, true, true)]
        {
            let mut scene = crate::load::default_scene();
            assert!(!scene.spheres.is_empty());
            if !with_spheres {
                scene.spheres.clear();
            }
            if with_normals {
                let n = scene.mesh.positions.len();
                // Unit normals tilted differently at every vertex.
                let normals = (0..n)
                    .map(|i| Vec3::new((i as f32 * 0.7).sin(), 1.0, (i as f32 * 1.3).cos()).normalize())
                    .collect();
                scene.mesh.normals = Some(normals);
            }
            let mut s = Settings::default();
            s.image.width = 24;
            s.image.height = 18;
            s.sampling.spp = 8;
            s.sampling.light_samples = 3;
            s.paths.max_depth = 5;
            s.paths.shading = Shading::Global;
            s.paths.roulette.kind = if rr_throughput { RouletteKind::Throughput } else { RouletteKind::Fixed };
            s.paths.roulette.start_depth = 1 + rr_throughput as u32;
            let t = Transport::new(&scene, &s, &crate::effects::Effects::of(&scene, &s));
            assert!(can_shade(&t, K::NON_DIFFUSE));
            let Some(avx) = Avx2::new() else { return }; // nothing to compare on this CPU
            let accel = BruteForce::new(&scene);
            let pixels: Vec<u32> = (0..(24 * 18) as u32).collect();
            let wave = Wave { pixels: &pixels, base: 0, batch: 8 };
            let mut q = PathQueue::default();
            generate(&t, None, &mut q, &wave, 24, 18, 8);
            let (mut sl, mut ss) = (ShadowQueue::default(), ShadowQueue::default());
            let mut slot_radiance = vec![Vec3::ZERO; wave.len()];
            let mut shadow_rays = 0;
            while !q.is_empty() {
                traverse::traverse(&accel, &mut q, &mut TraceCounters::default());
                let mut qs = q.clone();
                shade_lanes::<K>(avx, &t, &mut q, &mut sl);
                shade::shade_scalar::<K>(&t, &mut qs, &mut ss);
                assert_eq!(q.ray, qs.ray);
                assert_eq!(q.throughput, qs.throughput);
                assert_eq!(q.radiance, qs.radiance);
                assert_eq!(q.alive, qs.alive);
                assert_eq!(q.depth, qs.depth);
                assert_eq!(q.bounce, qs.bounce);
                assert_eq!(by_owner(&sl, q.len()), by_owner(&ss, q.len()));
                shadow_rays += sl.len();
                compact::compact(&mut q, &mut slot_radiance);
            }
            assert!(shadow_rays > 1000, "{shadow_rays}");
        }
    }
}
