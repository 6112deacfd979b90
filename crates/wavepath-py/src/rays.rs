//! `Scene.intersect` and `Scene.occluded`: rays from numpy arrays through the scene's BVH,
//! on all cores without the GIL, in the chunks the peers' harness uses.

use crate::arrays::{FloatRows, PerRayView};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use wavepath::{Hit, Intersector, Ray, Scene, TraceCounters};

/// Rays traced per task: the chunk of `wavepath rays trace`.
pub const CHUNK: usize = 1024;

/// The rays as given: origins, directions and their `[tmin, tmax]`.
#[derive(Clone, Copy)]
pub struct RayArrays<'a> {
    pub origins: FloatRows<'a>,
    pub directions: FloatRows<'a>,
    pub tmin: PerRayView<'a>,
    pub tmax: PerRayView<'a>,
}

impl RayArrays<'_> {
    pub fn len(&self) -> usize {
        self.origins.len()
    }

    /// Ray `i`, or `None` when it is not a ray (a non-finite origin or direction, a zero
    /// direction, a NaN bound).
    #[inline]
    fn ray(&self, i: usize) -> Option<Ray> {
        let r = Ray {
            origin: self.origins.vec3(i),
            dir: self.directions.vec3(i),
            tmin: self.tmin.at(i),
            tmax: self.tmax.at(i),
        };
        let ok =
            r.origin.is_finite() && r.dir.is_finite() && r.dir != Vec3::ZERO && !r.tmin.is_nan() && !r.tmax.is_nan();
        ok.then_some(r)
    }

    /// Fills `buf` with rays `start..start + buf.len()`; records the first bad one in `bad`.
    fn fill(&self, start: usize, buf: &mut Vec<Ray>, n: usize, bad: &AtomicUsize) {
        buf.clear();
        for i in start..start + n {
            match self.ray(i) {
                Some(r) => buf.push(r),
                None => {
                    bad.fetch_min(i, Ordering::Relaxed);
                    buf.push(Ray { origin: Vec3::ZERO, dir: Vec3::X, tmin: 1.0, tmax: 0.0 });
                }
            }
        }
    }
}

/// What `intersect` returns, before it becomes numpy arrays.
pub struct Hits {
    pub t: Vec<f32>,
    pub prim: Vec<u32>,
    pub uv: Vec<f32>,
    pub normal: Option<Vec<f32>>,
    /// The first ray that was not a ray (`usize::MAX`: none).
    pub bad: usize,
}

/// Closest hits of every ray; with `normals`, the unit geometric normal of each hit
/// (the triangle's winding normal, or the sphere's outward one).
pub fn intersect(scene: &Scene, accel: &dyn Intersector, rays: RayArrays, normals: bool) -> Hits {
    let n = rays.len();
    let mut t = vec![f32::INFINITY; n];
    let mut prim = vec![wavepath_miss(); n];
    let mut uv = vec![0.0f32; 2 * n];
    let mut normal = normals.then(|| vec![0.0f32; 3 * n]);
    let bad = AtomicUsize::new(usize::MAX);
    let mut normal_chunks: Vec<Option<&mut [f32]>> = match normal.as_mut() {
        Some(v) => v.chunks_mut(3 * CHUNK).map(Some).collect(),
        None => (0..n.div_ceil(CHUNK)).map(|_| None).collect(),
    };
    t.par_chunks_mut(CHUNK)
        .zip(prim.par_chunks_mut(CHUNK))
        .zip(uv.par_chunks_mut(2 * CHUNK))
        .zip(normal_chunks.par_iter_mut())
        .enumerate()
        .for_each_init(
            || (Vec::with_capacity(CHUNK), vec![None; CHUNK]),
            |(buf, hits), (k, (((t, prim), uv), nrm))| {
                let start = k * CHUNK;
                rays.fill(start, buf, t.len(), &bad);
                let hits: &mut [Option<Hit>] = &mut hits[..t.len()];
                let mut c = TraceCounters::default();
                accel.closest_hits(buf, hits, &mut c);
                for (j, h) in hits.iter().enumerate() {
                    if let Some(h) = h {
                        t[j] = h.t;
                        prim[j] = h.prim;
                        uv[2 * j] = h.u;
                        uv[2 * j + 1] = h.v;
                        if let Some(nrm) = nrm.as_deref_mut() {
                            let g = geometric_normal(scene, &buf[j], h);
                            nrm[3 * j..3 * j + 3].copy_from_slice(&g.to_array());
                        }
                    }
                }
            },
        );
    Hits { t, prim, uv, normal, bad: bad.into_inner() }
}

/// Whether anything lies on each ray within its bounds; the first bad ray's index or `usize::MAX`.
pub fn occluded(accel: &dyn Intersector, rays: RayArrays) -> (Vec<bool>, usize) {
    let n = rays.len();
    let mut out = vec![false; n];
    let bad = AtomicUsize::new(usize::MAX);
    out.par_chunks_mut(CHUNK).enumerate().for_each_init(
        || Vec::with_capacity(CHUNK),
        |buf, (k, out)| {
            rays.fill(k * CHUNK, buf, out.len(), &bad);
            let mut c = TraceCounters::default();
            accel.any_hits(buf, out, &mut c);
        },
    );
    (out, bad.into_inner())
}

/// The primitive id of a miss, as in hit files.
pub const fn wavepath_miss() -> u32 {
    u32::MAX
}

fn geometric_normal(scene: &Scene, ray: &Ray, h: &Hit) -> Vec3 {
    let tris = scene.mesh.triangle_count();
    let i = h.prim as usize;
    if i < tris {
        let [a, b, c] = scene.mesh.corners(i);
        (b - a).cross(c - a).normalize_or_zero()
    } else {
        let s = &scene.spheres[i - tris];
        ((ray.origin + ray.dir * h.t - s.center) / s.radius).normalize_or_zero()
    }
}
