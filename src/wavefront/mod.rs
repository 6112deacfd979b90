//! The wavefront integrator: paths live in structure-of-arrays queues and move through
//! five stages, each one module with one entry point, parallel over chunks and timed:
//!
//! ```text
//! generate -> (traverse -> shade -> shadow -> compact)* until no path is left
//! ```
//!
//! A frame takes one batch of samples for every active pixel (with adaptive sampling a
//! batch is the `-a` batch size and converged pixels leave before the next frame); a frame
//! is processed in waves of at most 2^16 paths so memory stays bounded. Results do not depend
//! on the thread count: every random number comes from (seed, pixel, sample, depth), every
//! sum runs in slot order.

pub mod compact;
pub mod generate;
pub mod queues;
pub mod shade;
pub mod shadow;
pub mod traverse;

use crate::accel::Intersector;
use crate::film::{Accumulator, PixelSums};
use crate::integrator::Transport;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::stats::RenderStats;
use generate::Wave;
use glam::Vec3;
use queues::{HitQueue, PathQueue, ShadowQueue};
use rayon::prelude::*;
use std::time::Instant;

/// Queue entries one rayon task handles.
pub const CHUNK: usize = 256;
/// Most paths in flight at once: small enough that a wave's queues stay near the L2/L3
/// caches (2^20 was no faster and needs ~200 MB), large enough to amortise stage dispatch.
pub const MAX_WAVE_PATHS: usize = 1 << 16;
/// Most shadow-queue entries at once (each path reserves `direct_per_vertex`).
pub const MAX_SHADOW_RAYS: usize = 1 << 18;

/// Every buffer a render needs, allocated once and reused by every wave and frame.
#[derive(Default)]
pub struct Queues {
    pub paths: PathQueue,
    pub next: PathQueue,
    pub hits: HitQueue,
    pub shadow: ShadowQueue,
    slot_radiance: Vec<Vec3>,
    partial: Vec<PixelSums>,
}

/// Renders with the wavefront integrator; `progress` is told how many samples finished.
pub fn render_wavefront(
    scene: &Scene,
    accel: &dyn Intersector,
    s: &Settings,
    progress: &(dyn Fn(u64) + Sync),
) -> (Accumulator, RenderStats) {
    let start = Instant::now();
    let t = Transport::new(scene, s);
    let (w, h) = (s.width, s.height);
    let region = s.region();
    let mut acc = Accumulator::new(w, h);
    let mut stats = RenderStats::default();
    let mut q = Queues::default();
    let per = t.direct_per_vertex.max(1) as usize;
    let cap = MAX_WAVE_PATHS.min((MAX_SHADOW_RAYS / per).max(CHUNK * 16));
    let mut active: Vec<u32> = (region.y..region.y + region.h)
        .flat_map(|y| (region.x..region.x + region.w).map(move |x| (y * w + x) as u32))
        .collect();
    let (first, end) = s.sample_span();
    let mut n = first;
    while n < end && !active.is_empty() {
        let check = match s.adaptive {
            Some((b, _)) => (n / b + 1) * b,
            None => end,
        }
        .min(end);
        let batch = (check - n).min(cap as u32);
        let per_wave = (cap / batch as usize).max(1);
        for pixels in active.chunks(per_wave) {
            let wave = Wave { pixels, base: n, batch };
            run_wave(&t, accel, &wave, &mut q, &mut acc, &mut stats, s);
            progress(wave.len() as u64);
        }
        n += batch;
        if let Some((b, tol)) = s.adaptive
            && n.is_multiple_of(b)
            && n < end
        {
            active.retain(|&p| !acc.pixels[p as usize].converged(tol));
        }
    }
    stats.render_s = start.elapsed().as_secs_f64();
    stats.invalid_samples = acc.invalid_samples();
    stats.samples_per_pixel = crate::integrator::recursive::region_samples(&acc, s);
    (acc, stats)
}

/// One wave: generate, then the bounce loop until every path has finished, then each
/// sample's radiance goes into its pixel's sums.
fn run_wave(
    t: &Transport,
    accel: &dyn Intersector,
    wave: &Wave,
    q: &mut Queues,
    acc: &mut Accumulator,
    stats: &mut RenderStats,
    s: &Settings,
) {
    let n = wave.len();
    let clock = Instant::now();
    generate::generate(t, &mut q.paths, wave, s.width, s.height, s.spp.max(1));
    if q.slot_radiance.len() < n {
        q.slot_radiance.resize(n, Vec3::ZERO);
    }
    stats.stages.generate += clock.elapsed().as_secs_f64();
    stats.camera_rays += n as u64;
    let mut first = true;
    while q.paths.len > 0 {
        let clock = Instant::now();
        let c = traverse::traverse(accel, &q.paths, &mut q.hits);
        stats.counters.add(&c);
        if !first {
            stats.extension_rays += q.paths.len as u64;
        }
        first = false;
        let clock = lap(clock, &mut stats.stages.traverse);
        shade::shade(t, wave, &mut q.paths, &q.hits, &mut q.shadow);
        let clock = lap(clock, &mut stats.stages.shade);
        let (c, rays) = shadow::shadow(t, accel, &mut q.shadow);
        stats.counters.add(&c);
        stats.shadow_rays += rays;
        let clock = lap(clock, &mut stats.stages.shadow);
        compact::compact(t, wave, &mut q.paths, &mut q.next, &q.shadow, &mut q.slot_radiance);
        std::mem::swap(&mut q.paths, &mut q.next);
        lap(clock, &mut stats.stages.compact);
    }
    // Resolve: per wave pixel, its samples in slot order; then into the image's sums.
    let clock = Instant::now();
    let npix = wave.pixels.len();
    let batch = wave.batch as usize;
    if q.partial.len() < npix {
        q.partial.resize(npix, PixelSums::default());
    }
    let radiance = &q.slot_radiance;
    q.partial[..npix].par_iter_mut().enumerate().for_each(|(j, p)| {
        *p = PixelSums::default();
        for l in &radiance[j * batch..(j + 1) * batch] {
            p.add(*l);
        }
    });
    for (j, &pixel) in wave.pixels.iter().enumerate() {
        acc.pixels[pixel as usize].merge(&q.partial[j]);
    }
    stats.stages.compact += clock.elapsed().as_secs_f64();
}

#[inline]
fn lap(since: Instant, into: &mut f64) -> Instant {
    let now = Instant::now();
    *into += (now - since).as_secs_f64();
    now
}
