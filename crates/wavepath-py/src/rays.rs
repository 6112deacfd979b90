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

    /// Fills `buf` with rays `start..start + n`. A row that is not a ray (a non-finite origin
    /// or direction, a zero direction, a NaN bound) is recorded in `bad` (the first one wins)
    /// and replaced by an empty ray, so the chunk is still traced whole.
    fn fill(&self, start: usize, buf: &mut Vec<Ray>, n: usize, bad: &AtomicUsize, scratch: &mut Scratch) {
        buf.clear();
        if !self.fill_f32(start, n, buf) {
            self.fill_converted(start, n, buf, scratch);
        }
        for (j, r) in buf.iter_mut().enumerate() {
            let ok = r.origin.is_finite()
                && r.dir.is_finite()
                && r.dir != Vec3::ZERO
                && !r.tmin.is_nan()
                && !r.tmax.is_nan();
            if !ok {
                bad.fetch_min(start + j, Ordering::Relaxed);
                *r = Ray { origin: Vec3::ZERO, dir: Vec3::X, tmin: 1.0, tmax: 0.0 };
            }
        }
    }

    /// The common case in one pass: float32 rows read straight into rays (bounds one number
    /// or float32 arrays). False when the inputs are otherwise.
    fn fill_f32(&self, start: usize, n: usize, buf: &mut Vec<Ray>) -> bool {
        let (Some(o), Some(d)) = (self.origins.f32_rows(start, n), self.directions.f32_rows(start, n)) else {
            return false;
        };
        let rays = o.chunks_exact(3).zip(d.chunks_exact(3));
        let ray = |o: &[f32], d: &[f32], tmin: f32, tmax: f32| Ray {
            origin: Vec3::new(o[0], o[1], o[2]),
            dir: Vec3::new(d[0], d[1], d[2]),
            tmin,
            tmax,
        };
        match (self.tmin, self.tmax) {
            (PerRayView::All(lo), PerRayView::All(hi)) => buf.extend(rays.map(|(o, d)| ray(o, d, lo, hi))),
            _ => match (self.tmin.f32_values(start, n), self.tmax.f32_values(start, n)) {
                (Some(lo), Some(hi)) => {
                    buf.extend(rays.zip(lo.iter().zip(hi)).map(|((o, d), (&lo, &hi))| ray(o, d, lo, hi)))
                }
                _ => return false,
            },
        }
        true
    }

    /// Any other dtypes and layouts: column by column through `scratch`, converted to f32.
    fn fill_converted(&self, start: usize, n: usize, buf: &mut Vec<Ray>, scratch: &mut Scratch) {
        let Scratch { o, d, lo, hi } = scratch;
        self.origins.read_vec3s(start, &mut o[..n]);
        self.directions.read_vec3s(start, &mut d[..n]);
        self.tmin.read(start, &mut lo[..n]);
        self.tmax.read(start, &mut hi[..n]);
        buf.extend((0..n).map(|j| Ray { origin: o[j], dir: d[j], tmin: lo[j], tmax: hi[j] }));
    }
}

/// Per-thread buffers of one chunk's inputs, converted column by column.
pub struct Scratch {
    o: Vec<Vec3>,
    d: Vec<Vec3>,
    lo: Vec<f32>,
    hi: Vec<f32>,
}

impl Default for Scratch {
    fn default() -> Self {
        Scratch { o: vec![Vec3::ZERO; CHUNK], d: vec![Vec3::ZERO; CHUNK], lo: vec![0.0; CHUNK], hi: vec![0.0; CHUNK] }
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
    // Zeroed allocations come from calloc, untouched until written: every entry is written
    // once below (misses included), so no pass fills them first.
    let mut t = vec![0.0f32; n];
    let mut prim = vec![0u32; n];
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
            || (Vec::with_capacity(CHUNK), vec![None; CHUNK], Scratch::default()),
            |(buf, hits, scratch), (k, (((t, prim), uv), nrm))| {
                let start = k * CHUNK;
                rays.fill(start, buf, t.len(), &bad, scratch);
                let hits: &mut [Option<Hit>] = &mut hits[..t.len()];
                let mut c = TraceCounters::default();
                accel.closest_hits(buf, hits, &mut c);
                for (j, h) in hits.iter().enumerate() {
                    match h {
                        Some(h) => {
                            t[j] = h.t;
                            prim[j] = h.prim;
                            uv[2 * j] = h.u;
                            uv[2 * j + 1] = h.v;
                            if let Some(nrm) = nrm.as_deref_mut() {
                                let g = geometric_normal(scene, &buf[j], h);
                                nrm[3 * j..3 * j + 3].copy_from_slice(&g.to_array());
                            }
                        }
                        None => {
                            t[j] = f32::INFINITY;
                            prim[j] = wavepath_miss();
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
        || (Vec::with_capacity(CHUNK), Scratch::default()),
        |(buf, scratch), (k, out)| {
            rays.fill(k * CHUNK, buf, out.len(), &bad, scratch);
            let mut c = TraceCounters::default();
            // Rays from one origin (camera rays, shadow rays of one point) run as packets.
            accel.any_hits_packets(buf, out, &mut c);
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
