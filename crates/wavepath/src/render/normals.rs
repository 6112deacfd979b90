use crate::accel::{Intersector, TraceCounters};
use crate::film::Film;
use crate::sampling::Sampler;
use crate::scene::{Camera, Scene};
use crate::settings::Settings;
use crate::stats::RenderStats;
use glam::Vec3;
use rayon::prelude::*;
use std::time::Instant;

/// The seed's debug view: each pixel shows the average over its samples of the shading
/// normal mapped to colour as n * 0.5 + 0.5; misses are black.
///
/// Samples are jittered inside the pixel (one uniform offset per sample; the pixel centre
/// when `spp` is 1, as the reference does), with random numbers from (seed, pixel, sample).
/// Rays leave `camera`, already fitted to the image (a render plan's), not the scene's own.
pub fn render_normals(
    scene: &Scene,
    camera: &Camera,
    accel: &dyn Intersector,
    settings: &Settings,
) -> (Film, RenderStats) {
    let (w, h) = (settings.image.width, settings.image.height);
    let region = settings.region();
    let spp = settings.sampling.spp.max(1);
    let start = Instant::now();
    let mut film = Film::new(w, h);
    let counters: Vec<TraceCounters> = film
        .pixels
        .par_chunks_mut(w)
        .enumerate()
        .filter(|(y, _)| *y >= region.y && *y < region.y + region.h)
        .map(|(y, row)| {
            let mut c = TraceCounters::default();
            for (x, out) in row.iter_mut().enumerate().skip(region.x).take(region.w) {
                let pixel = (y * w + x) as u64;
                let mut sum = Vec3::ZERO;
                let (first, end) = settings.sample_span();
                for s in first..end {
                    let (jx, jy) = if spp == 1 {
                        (0.5, 0.5)
                    } else {
                        Sampler::for_sample(settings.sampling.seed, pixel, s as u64).next_2d()
                    };
                    let ray = camera.generate_ray((x as f32 + jx) / w as f32, (y as f32 + jy) / h as f32);
                    if let Some(hit) = accel.closest_hit(&ray, &mut c) {
                        let sp = scene.surface_point(&ray, &hit);
                        let n = scene.relief_normal(&hit, sp.shading_normal, sp.uv, sp.material);
                        sum += n * 0.5 + Vec3::splat(0.5);
                    }
                }
                *out = sum / (end - first).max(1) as f32;
            }
            c
        })
        .collect();
    let mut stats = RenderStats::default();
    for c in &counters {
        stats.counters.add(c);
    }
    stats.camera_rays = stats.counters.rays;
    stats.render_s = start.elapsed().as_secs_f64();
    stats.stages.traverse = Some(stats.render_s);
    stats.samples_per_pixel = vec![spp; region.w * region.h];
    (film, stats)
}
