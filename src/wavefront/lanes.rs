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
use super::queues::{PathQueue, ShadowQueue};
use crate::integrator::area::{AreaLight, ShadingPoint, area_ray, cosine_ray};
use crate::integrator::{DIM_DIRECT, Transport};
use crate::lights::SampledLight;
use crate::ray::{Hit, Ray};
use crate::sampling::Sampler;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Paths per group.
const L: usize = 8;

/// Whether the lane kernel can shade this render's paths: no BSDF models, light sampling
/// (not hemisphere probes) and nothing but area lights.
pub fn applies<F: Features>(t: &Transport) -> bool {
    !F::NON_DIFFUSE && !t.hemisphere && t.area_lights.iter().all(Option::is_some)
}

/// [`super::shade::shade`] eight paths at a time when the CPU has AVX2 and FMA; `false` (and
/// nothing done) when it has not.
pub fn shade_lanes<F: Features>(
    t: &Transport,
    q: &mut PathQueue,
    hits: &[Option<Hit>],
    shadow: &mut ShadowQueue,
) -> bool {
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
        // SAFETY: AVX2 and FMA were detected on this CPU just above.
        unsafe { shade_avx2::<F>(t, q, hits, shadow) };
        return true;
    }
    let _ = (t, q, hits, shadow);
    false
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn shade_avx2<F: Features>(t: &Transport, q: &mut PathQueue, hits: &[Option<Hit>], shadow: &mut ShadowQueue) {
    shade_groups::<F>(t, q, hits, shadow);
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
        let v = |a: &[[f32; L]; 3]| Vec3::new(a[0][j], a[1][j], a[2][j]);
        ShadingPoint { p: v(&self.p), p_error: v(&self.e), ng: v(&self.ng), ns: v(&self.ns) }
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
        let v = |a: &[[f32; L]; 3]| Vec3::new(a[0][j], a[1][j], a[2][j]);
        Ray { origin: v(&self.o), dir: v(&self.d), tmin: 0.0, tmax: self.tmax[j] }
    }
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

#[inline(always)]
fn shade_groups<F: Features>(t: &Transport, q: &mut PathQueue, hits: &[Option<Hit>], shadow: &mut ShadowQueue) {
    shadow.clear();
    let sees_emission = t.counts_emission();
    let n = q.len().min(hits.len());
    let mut pts = Points::default();
    let mut rays = Rays::default();
    for base in (0..n).step_by(L) {
        let m = (n - base).min(L);
        let mut rng = [Sampler::default(); L];
        let mut albedo = [Vec3::ZERO; L];
        let mut direct = [false; L];
        let mut cont = [false; L];
        // Gather, one path at a time.
        for j in 0..m {
            let i = base + j;
            let depth = q.depth[i];
            q.alive[i] = false;
            let Some(hit) = hits[i] else {
                if F::ENVIRONMENT && depth == 0 && sees_emission {
                    q.radiance[i] += q.throughput[i] * t.lights.background_toward(q.ray[i].dir);
                }
                continue;
            };
            let v = t.vertex(&q.ray[i], &hit);
            if F::EMISSION && depth == 0 && sees_emission {
                q.radiance[i] += v.emission;
            }
            if !F::DIRECT && !F::INDIRECT {
                continue;
            }
            rng[j] = t.vertex_sampler(q.key[i], depth);
            pts.set(j, &v.shading_point());
            albedo[j] = v.albedo;
            // As `Transport::direct_rays` and `Transport::scatter` decide.
            direct[j] = F::DIRECT && t.counts_direct(depth) && v.albedo * FRAC_1_PI != Vec3::ZERO;
            cont[j] = F::INDIRECT && t.continues(depth) && v.albedo != Vec3::ZERO;
        }
        if F::DIRECT && direct.iter().any(|&d| d) {
            let mut dim = DIM_DIRECT;
            for (li, light) in t.lights.lights.iter().enumerate() {
                let (Some(al), SampledLight::Area { radiance, .. }) = (&t.area_lights[li], light) else {
                    unreachable!("the lane kernel runs only with area lights")
                };
                let ns = t.lights.samples_for(li, t.light_samples);
                let c: [Vec3; L] = std::array::from_fn(|j| albedo[j] * FRAC_1_PI / ns as f32 * *radiance);
                for _ in 0..ns {
                    let (mut ua, mut ub) = ([0.5; L], [0.5; L]);
                    for j in 0..m {
                        if direct[j] {
                            (ua[j], ub[j]) = rng[j].at(dim).next_2d();
                        }
                    }
                    dim += 1;
                    area_rays(&pts, al, &ua, &ub, &mut rays);
                    for j in 0..m {
                        if direct[j] && rays.valid[j] {
                            let i = base + j;
                            shadow.push(rays.ray(j), c[j] * rays.g[j] * q.throughput[i], i as u32);
                        }
                    }
                }
            }
        }
        if F::INDIRECT && cont.iter().any(|&c| c) {
            let (mut ua, mut ub) = ([0.5; L], [0.5; L]);
            for j in 0..m {
                if cont[j] {
                    (ua[j], ub[j]) = rng[j].at(0).next_2d();
                }
            }
            cosine_rays(&pts, &ua, &ub, &mut rays);
            for j in 0..m {
                if cont[j] {
                    let i = base + j;
                    let depth = q.depth[i];
                    q.ray[i] = rays.ray(j);
                    q.throughput[i] *= albedo[j];
                    q.depth[i] = depth + 1;
                    q.alive[i] = true;
                    super::shade::roulette::<F>(t, q, i, depth, rng[j]);
                }
            }
        }
    }
}
