//! The reference: a small recursive path tracer, one ray at a time, one pixel after another
//! (rows in parallel). It follows the seed's structure (`est_radiance_global_illumination`
//! = zero-bounce + at-least-one-bounce radiance) so the wavefront integrator can be checked
//! against something obviously right.

use super::{DirectRay, Transport, Vertex};
use crate::accel::{Intersector, TraceCounters};
use crate::film::{Accumulator, PixelSums};
use crate::geometry::Ray;
use crate::settings::Settings;
use crate::stats::RenderStats;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

#[derive(Default, Clone, Copy)]
struct RowStats {
    trace: TraceCounters,
    camera: u64,
    extension: u64,
    shadow: u64,
}

struct PathTracer<'t, 'a> {
    transport: &'t Transport<'a>,
    accel: &'t dyn Intersector,
    pixel: u32,
    sample: u32,
    st: RowStats,
}

impl PathTracer<'_, '_> {
    fn radiance(&mut self, ray: &Ray) -> Vec3 {
        self.st.camera += 1;
        let Some(hit) = self.accel.closest_hit(ray, &mut self.st.trace) else {
            return if self.transport.rules.counts_emission() {
                self.transport.lights.set.background_toward(ray.dir)
            } else {
                Vec3::ZERO
            };
        };
        let v = self.transport.vertex(ray, &hit);
        let mut l = if self.transport.rules.counts_emission() { v.emission } else { Vec3::ZERO };
        if self.transport.rules.max_depth >= 1 {
            l += self.at_least_one_bounce(ray, &v, 0, Vec3::ONE);
        }
        l
    }

    /// Light leaving `v` (the vertex at `depth`) toward `ray`'s origin, for a path whose
    /// throughput up to `v` is `throughput` (what throughput roulette plays with).
    fn at_least_one_bounce(&mut self, ray: &Ray, v: &Vertex, depth: u32, throughput: Vec3) -> Vec3 {
        let rng = self.transport.streams.sampler(self.pixel, self.sample, depth);
        let mut l = Vec3::ZERO;
        let sh = self.transport.materials.non_diffuse.then(|| self.transport.shading(v, ray.dir));
        if self.transport.rules.counts_direct(depth) {
            let (transport, accel) = (self.transport, self.accel);
            let mut shadow = 0;
            let mut trace = self.st.trace;
            let mut add = |d: DirectRay| {
                shadow += 1;
                if transport.rules.hemisphere {
                    let hit = accel.closest_hit(&d.ray, &mut trace);
                    l += d.weight * transport.probe_radiance(&d.ray, hit.as_ref());
                } else if !accel.any_hit(&d.ray, &mut trace) {
                    l += d.weight;
                }
            };
            match &sh {
                Some(sh) => transport.direct_rays_shaded(v, sh, depth, rng, add),
                None => transport.direct_rays(v, depth, rng, &mut add),
            }
            self.st.trace = trace;
            self.st.shadow += shadow;
        }
        let next = match &sh {
            Some(sh) => self.transport.continuation_shaded(v, sh, depth, rng, throughput),
            None => self.transport.continuation(v, depth, rng, throughput),
        };
        if let Some((ray, w, bounce)) = next.filter(|(ray, ..)| self.transport.traces(ray, depth + 1)) {
            self.st.extension += 1;
            match self.accel.closest_hit(&ray, &mut self.st.trace) {
                Some(hit) => {
                    let next = self.transport.vertex(&ray, &hit);
                    let w = if self.transport.materials.layers.volumes {
                        w * self.transport.materials.layers.absorbed(&next, hit.t)
                    } else {
                        w
                    };
                    if self.transport.counts_arrivals() {
                        l += w * self.transport.arrival(bounce, &ray, Some(&hit), next.emission, depth + 1);
                    }
                    l += w * self.at_least_one_bounce(&ray, &next, depth + 1, throughput * w);
                }
                None if self.transport.counts_arrivals() => {
                    l += w * self.transport.arrival(bounce, &ray, None, Vec3::ZERO, depth + 1)
                }
                None => {}
            }
        }
        l
    }
}

/// Whether a pixel's earlier sums and this render's, together, meet the adaptive tolerance.
fn all_converged(mut before: PixelSums, sums: &PixelSums, tol: f32) -> bool {
    before.merge(sums);
    before.converged(tol)
}

/// Renders with the recursive reference the image part `settings` covers (its cell and
/// sample range) with `transport` (its render plan's), adding each pixel's sums into `acc`
/// (an image of the settings' size; adaptive sampling judges a pixel by all its sums, earlier
/// renders' included); `progress` is told how many samples finished. Gives up (`None`) once
/// `stop` is set: rows not yet started are skipped, so the caller waits at most one row per
/// thread. The statistics' samples per pixel and invalid samples are `acc`'s in the
/// settings' region.
pub fn render_recursive_into(
    transport: &Transport,
    settings: &Settings,
    accel: &dyn Intersector,
    progress: &(dyn Fn(u64) + Sync),
    stop: &AtomicBool,
    acc: &mut Accumulator,
) -> Option<RenderStats> {
    let start = Instant::now();
    let (w, h) = (settings.image.width, settings.image.height);
    debug_assert_eq!((acc.width, acc.height), (w, h));
    let region = settings.region();
    let spp = settings.sampling.spp.max(1);
    let rows: Vec<RowStats> = acc
        .pixels
        .par_chunks_mut(w)
        .enumerate()
        .filter(|(y, _)| *y >= region.y && *y < region.y + region.h)
        .map(|(y, row)| {
            let mut st = RowStats::default();
            if stop.load(Ordering::Relaxed) {
                return st;
            }
            for (x, out) in row.iter_mut().enumerate().skip(region.x).take(region.w) {
                let pixel = (y * w + x) as u32;
                // This render's sums, merged into the earlier ones at the end (as separate
                // renders' sums are merged); the adaptive test judges all of them.
                let before = *out;
                let mut sums = PixelSums::default();
                let (first, end) = settings.sample_span();
                for i in first..end {
                    if let Some((b, tol)) = settings.sampling.adaptive
                        && i > first
                        && i.is_multiple_of(b)
                        && all_converged(before, &sums, tol)
                    {
                        break;
                    }
                    let ray = transport.camera_ray(x as u32, y as u32, w, h, i, spp);
                    let mut tracer = PathTracer { transport, accel, pixel, sample: i, st };
                    let l = tracer.radiance(&ray);
                    st = tracer.st;
                    sums.add(l);
                }
                progress(sums.taken as u64);
                out.merge(&sums);
            }
            st
        })
        .collect();
    if stop.load(Ordering::Relaxed) {
        return None;
    }
    let mut stats = RenderStats::default();
    for r in &rows {
        stats.counters.add(&r.trace);
        stats.camera_rays += r.camera;
        stats.extension_rays += r.extension;
        stats.shadow_rays += r.shadow;
    }
    stats.render_s = start.elapsed().as_secs_f64();
    stats.invalid_samples = acc.invalid_samples_in(region);
    stats.samples_per_pixel = acc.samples_taken_in(region);
    Some(stats)
}
