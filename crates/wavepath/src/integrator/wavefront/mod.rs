//! The wavefront integrator: paths live in structure-of-arrays queues and move through
//! five stages, each one module with one entry point:
//!
//! ```text
//! generate -> (traverse -> shade -> shadow -> compact)* until no path is left
//! ```
//!
//! A frame takes one batch of samples for every active pixel (with adaptive sampling a
//! batch is the `-a` batch size and converged pixels leave before the next frame). A frame
//! is cut into small waves (a few thousand paths, so a wave's queues stay in the L2 cache);
//! worker threads take whole waves one at a time from a shared counter ([`handout`]), and
//! each thread runs all stages of its wave itself on queues it keeps for the whole render.
//! There is no barrier per stage and no allocation per wave. Stage times are summed over threads (thread-seconds: on a loaded
//! machine they include time the thread waited for a core).
//!
//! The stages run the parts the [`Effects`] of the scene call for (the transport's
//! [`Features`](crate::integrator::rules::Features)): a stage that is off does not run and
//! reports no time.
//! Results do not depend on the thread count: every random number comes from (seed, pixel,
//! sample, depth), every sum runs in slot order.

pub mod aov;
pub mod compact;
pub mod generate;
mod handout;
pub mod lanes;
mod one_path;
pub mod queues;
pub mod shade;
pub mod shadow;
pub mod traverse;

use crate::accel::{Intersector, TraceCounters};
use crate::cpu::Isa;
use crate::effects::Effects;
use crate::film::{Accumulator, AovSums, PixelSums};
use crate::integrator::Transport;
use crate::integrator::bidir::{KeptSplats, LightPass};
use crate::settings::Settings;
use crate::stats::{RenderStats, StageTimes};
use generate::Wave;
use glam::Vec3;
use handout::Workers;
pub use lanes::width::ShadeWidth;
use queues::{PathQueue, ShadowQueue};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Paths one wave holds at most: its queues (~300 bytes per path with a few shadow rays)
/// stay in a core's L2 cache, and there are enough waves per frame to balance threads.
pub const WAVE_PATHS: usize = 4096;
/// Batch size of the adaptive bookkeeping when `--all-effects` forces it on without `-a`.
const FORCED_ADAPTIVE_BATCH: u32 = 8;

/// Which stages run paths in lanes, decided once per render beside the kernel: the token
/// when the stage's lane kernel runs, `None` when its one-path-at-a-time kernel does.
#[derive(Clone, Copy, Debug)]
pub struct Lanes {
    /// Camera rays, eight samples at a time: a pinhole camera (a lens draws more numbers),
    /// at most AVX2's width (eight lanes fill its registers).
    pub camera: Option<ShadeWidth>,
    /// Shading of the Lambertian hits, eight or sixteen paths at a time ([`lanes`]).
    pub shade: Option<ShadeWidth>,
}

impl Lanes {
    /// The lane kernels this render runs: those its scene allows, at the widest width the
    /// settings' instruction set and the CPU allow (none under `--isa scalar`).
    pub fn of(t: &Transport, isa: Isa) -> Lanes {
        Lanes {
            camera: (isa.shades_in_lanes() && t.camera.pinhole()).then(|| ShadeWidth::best(isa.at_most_avx2())),
            shade: isa.shades_in_lanes().then(|| ShadeWidth::best(isa)),
        }
    }
}

/// A worker thread's queues, reused by every wave it runs in every frame of the render.
#[derive(Default)]
pub struct WaveQueues {
    pub paths: PathQueue,
    pub shadow: ShadowQueue,
    kinds: shade::Kinds,
    occluded: Vec<bool>,
    slot_radiance: Vec<Vec3>,
    aov: aov::AovRecords,
}

/// What one wave (or a sum of waves) traced and how long each stage took.
#[derive(Clone, Copy, Default)]
struct WaveStats {
    counters: TraceCounters,
    camera: u64,
    extension: u64,
    shadow: u64,
    light: u64,
    stages: StageTimes,
}

impl WaveStats {
    fn sum(mut self, o: WaveStats) -> WaveStats {
        self.counters.add(&o.counters);
        self.camera += o.camera;
        self.extension += o.extension;
        self.shadow += o.shadow;
        self.light += o.light;
        self.stages.add(&o.stages);
        self
    }
}

/// Everything the waves of one render share: the parts of its render plan
/// ([`RenderPlan`](crate::integrator::plan::RenderPlan)) a wave reads, the settings of the
/// image part it renders (its cell and sample range), the scene's tree, and where it reports
/// progress (`progress` is told how many samples finished) and learns it must stop.
pub struct RenderJob<'a, 's> {
    pub transport: &'a Transport<'s>,
    pub effects: &'a Effects,
    pub lanes: Lanes,
    /// The plan's kept light-pass splats (path+light cells share them).
    pub splats: &'a KeptSplats,
    pub settings: &'a Settings,
    pub accel: &'a dyn Intersector,
    pub progress: &'a (dyn Fn(u64) + Sync),
    pub stop: &'a AtomicBool,
}

/// Each worker thread's queues, kept by a caller that renders many extents of one plan (the
/// viewer's bands) so that no render allocates them again.
pub struct WaveWorkers(Workers<WaveQueues>);

impl WaveWorkers {
    /// One set of queues per thread of the current rayon pool, allocated by the first wave.
    pub fn for_current_pool() -> Self {
        WaveWorkers(Workers::for_current_pool())
    }
}

/// Renders `job` with the wavefront integrator, adding each pixel's sums into `acc` (an
/// image of the job's settings' size) with the queues of `workers`. Gives up (`None`) once
/// the job's stop flag is set: no new wave starts, so a caller that wants the render to end
/// (Ctrl-C) waits at most one wave per thread, and the waves already done stay added. The
/// statistics' samples per pixel and invalid samples are `acc`'s in the settings' region,
/// earlier renders' included.
pub fn render_wavefront_into(job: &RenderJob, workers: &WaveWorkers, acc: &mut Accumulator) -> Option<RenderStats> {
    debug_assert_eq!((acc.width, acc.height), (job.settings.image.width, job.settings.image.height));
    render_frames(job, &workers.0, acc)
}

fn render_frames(job: &RenderJob, workers: &Workers<WaveQueues>, acc: &mut Accumulator) -> Option<RenderStats> {
    let start = Instant::now();
    let s = job.settings;
    let w = s.image.width;
    let region = s.region();
    let mut total = WaveStats::default();
    let mut active: Vec<u32> = (region.y..region.y + region.h)
        .flat_map(|y| (region.x..region.x + region.w).map(move |x| (y * w + x) as u32))
        .collect();
    // Forced on without -a, the bookkeeping runs with a tolerance no pixel meets.
    let adaptive = match s.sampling.adaptive {
        Some(a) => Some(a),
        None if job.effects.adaptive => Some((FORCED_ADAPTIVE_BATCH, f32::NEG_INFINITY)),
        None => None,
    };
    let (first, end) = s.sample_span();
    // path+light: each frame's iterations first trace their light subpaths, whose splats
    // join the camera paths' samples (a frame then holds as many iterations as its splat
    // images allow).
    let mut light =
        job.transport.caustics.as_ref().and_then(|_| LightPass::new(job.transport, job.accel, s, job.lanes.shade));
    let splat_batch = (SPLAT_BYTES / (w * s.image.height * std::mem::size_of::<Vec3>()).max(1)).clamp(1, 64) as u32;
    let mut splats = Vec::new();
    let mut n = first;
    while n < end && !active.is_empty() {
        let check = match adaptive {
            Some((b, _)) => (n / b + 1) * b,
            None => end,
        }
        .min(end);
        let mut batch = (check - n).min(WAVE_PATHS as u32);
        if let Some(light) = &mut light {
            batch = batch.min(splat_batch);
            // A cell's light pass is kept for the plan's next cells of the same samples.
            let kept = s.image.cell.is_some().then_some(job.splats);
            let c = light.trace(n, batch, &mut splats, kept);
            total.counters.add(&c.trace);
            total.light += c.light_rays;
            total.shadow += c.shadow;
            total.stages.light_paths = Some(total.stages.light_paths.unwrap_or(0.0) + c.seconds);
        }
        let per_wave = (WAVE_PATHS / batch as usize).max(1);
        let waves = wave_windows(&mut acc.pixels, &mut acc.aovs, &active, per_wave);
        let frame_splats = Splats { images: &splats, pixels: w * s.image.height };
        let frame = workers.run(waves, WaveStats::default, WaveStats::sum, |queues, (pixels, window)| {
            if job.stop.load(Ordering::Relaxed) {
                return WaveStats::default();
            }
            let wave = Wave { pixels, base: n, batch };
            let st = run_wave(job, &wave, queues, window, frame_splats);
            (job.progress)(wave.len() as u64);
            st
        });
        if job.stop.load(Ordering::Relaxed) {
            return None;
        }
        total = total.sum(frame);
        n += batch;
        if let Some((b, tol)) = adaptive
            && n.is_multiple_of(b)
            && n < end
        {
            active.retain(|&p| !acc.pixels[p as usize].converged(tol));
        }
    }
    let mut stats = RenderStats {
        camera_rays: total.camera,
        extension_rays: total.extension,
        light_rays: total.light,
        shadow_rays: total.shadow,
        counters: total.counters,
        stages: total.stages,
        ..RenderStats::default()
    };
    stats.render_s = start.elapsed().as_secs_f64();
    stats.invalid_samples = acc.invalid_samples_in(region);
    stats.samples_per_pixel = acc.samples_taken_in(region);
    Some(stats)
}

/// A frame's waves: each wave's pixels and the window of the image's sums (and first-hit
/// sums, when the render keeps them) from its first pixel to its last. `active` rises, so the
/// windows are disjoint and each wave's thread adds its pixels' sums into the image itself:
/// no per-frame buffer, no merge on one thread while the others wait.
fn wave_windows<'a>(
    sums: &'a mut [PixelSums],
    aovs: &'a mut [AovSums],
    active: &'a [u32],
    per_wave: usize,
) -> Vec<(&'a [u32], Window<'a>)> {
    debug_assert!(active.windows(2).all(|p| p[0] < p[1]), "active pixels rise");
    let keeps_aovs = !aovs.is_empty();
    let mut waves = Vec::with_capacity(active.len().div_ceil(per_wave));
    let (mut rest, mut rest_aovs, mut at) = (sums, aovs, 0usize);
    for pixels in active.chunks(per_wave) {
        let (first, last) = (pixels[0] as usize, pixels[pixels.len() - 1] as usize);
        let (_, from_first) = rest.split_at_mut(first - at);
        let (sums, after) = from_first.split_at_mut(last + 1 - first);
        let aovs = if keeps_aovs {
            let (_, from_first) = std::mem::take(&mut rest_aovs).split_at_mut(first - at);
            let (aovs, after) = from_first.split_at_mut(last + 1 - first);
            rest_aovs = after;
            aovs
        } else {
            &mut []
        };
        waves.push((pixels, Window { first: first as u32, sums, aovs }));
        (rest, at) = (after, last + 1);
    }
    waves
}

/// The image's pixel sums (and first-hit sums, empty when the render keeps none) from pixel
/// `first` on, for one wave's thread alone.
struct Window<'a> {
    first: u32,
    sums: &'a mut [PixelSums],
    aovs: &'a mut [AovSums],
}

/// Most memory a frame's splat images (path+light) take: at 320x240 a frame of 64
/// iterations, at 1920x1080 two.
const SPLAT_BYTES: usize = 64 << 20;

/// A frame's splat images, one per iteration (empty without light subpaths).
#[derive(Clone, Copy)]
struct Splats<'a> {
    images: &'a [Vec3],
    pixels: usize,
}

impl Splats<'_> {
    /// What iteration `k` of the frame splatted onto `pixel`.
    #[inline]
    fn at(&self, k: usize, pixel: u32) -> Vec3 {
        self.images.get(k * self.pixels + pixel as usize).copied().unwrap_or(Vec3::ZERO)
    }
}

/// One wave on one thread: generate, then the bounce loop until every path has finished,
/// then each pixel's samples (with what the frame's light subpaths splatted onto them),
/// summed in slot order, into the image's sums.
fn run_wave(job: &RenderJob, wave: &Wave, q: &mut WaveQueues, out: Window, splats: Splats) -> WaveStats {
    let (t, accel, s) = (&job.transport, job.accel, job.settings);
    let mut st = WaveStats::default();
    let n = wave.len();
    let clock = Instant::now();
    // Light subpaths' importance covers the whole pixel: camera rays are jittered over it
    // whatever the sample count (a count of 1 would aim at its centre).
    let spp = if t.caustics.is_some() { s.sampling.spp.max(2) } else { s.sampling.spp.max(1) };
    generate::generate(t, job.lanes.camera, &mut q.paths, wave, s.image.width, s.image.height, spp);
    st.camera = n as u64;
    let mut clock = lap(clock, &mut st.stages.generate);
    let aovs = !out.aovs.is_empty();
    let hits_in_lanes = aov_hits_in_lanes(t, job.lanes);
    if aovs {
        q.aov.start(n);
    }
    q.slot_radiance.clear();
    q.slot_radiance.resize(n, Vec3::ZERO);
    let mut first = true;
    while !q.paths.is_empty() {
        traverse::traverse(accel, &mut q.paths, &mut st.counters);
        if !first {
            st.extension += q.paths.len() as u64;
        }
        first = false;
        clock = lap(clock, &mut st.stages.traverse);
        if aovs {
            aov::record(t, &q.paths, &mut q.aov, hits_in_lanes);
            clock = lap(clock, &mut st.stages.aov);
        }
        let records = (aovs && hits_in_lanes).then_some(&mut q.aov);
        shade::shade(t, job.lanes, &mut q.paths, &mut q.shadow, &mut q.kinds, records);
        clock = lap(clock, &mut st.stages.shade);
        if t.rules.features.direct {
            shadow::shadow(t, accel, &q.shadow, &mut q.occluded, &mut q.paths.radiance, &mut st.counters);
            st.shadow += q.shadow.len() as u64;
            clock = lap(clock, &mut st.stages.shadow);
        }
        if t.rules.features.indirect {
            compact::compact(t, &mut q.paths, &mut q.slot_radiance);
            clock = lap(clock, &mut st.stages.compact);
        } else {
            // Every path ended at its first hit, still in slot order.
            std::mem::swap(&mut q.slot_radiance, &mut q.paths.radiance);
            q.paths.clear();
        }
    }
    let batch = wave.batch as usize;
    for (j, &pixel) in wave.pixels.iter().enumerate() {
        // The frame's samples of a pixel are summed first and then added to its sums, the
        // same order whatever frame or thread count.
        let mut frame = PixelSums::default();
        for (k, r) in q.slot_radiance[j * batch..(j + 1) * batch].iter().enumerate() {
            // One sample of a path+light pixel: its camera path and what that iteration's
            // light subpaths splatted onto it.
            frame.add(if splats.images.is_empty() { *r } else { *r + splats.at(k, pixel) });
        }
        out.sums[(pixel - out.first) as usize].merge(&frame);
        if aovs {
            let mut frame = AovSums::default();
            for r in &q.aov.samples[j * batch..(j + 1) * batch] {
                frame.add(r);
            }
            out.aovs[(pixel - out.first) as usize].merge(&frame);
        }
    }
    st
}

/// Whether shade records the output variables of the hits (the lanes reconstruct every group's
/// points, and every hit leaves its vertex): the AOV stage then records escaped rays only.
fn aov_hits_in_lanes(t: &Transport, lanes: Lanes) -> bool {
    lanes.shade.is_some() && !lanes::soa::whole_vertices(t) && (t.rules.features.direct || t.rules.features.indirect)
}

#[inline]
fn lap(since: Instant, into: &mut Option<f64>) -> Instant {
    let now = Instant::now();
    *into = Some(into.unwrap_or(0.0) + (now - since).as_secs_f64());
    now
}
