//! One interactive render: the state clients change, and the loop that renders it frame by
//! frame with the same wavefront integrator as an offline render. Any change bumps a
//! generation counter and stops the band being rendered (between waves); the loop shows a
//! quarter-resolution one-sample image at once, then refines the full-resolution image band
//! by band, 16 samples per pixel per pass (sample indices 0, 1, 2, ... of the offline render,
//! so the converged image is the offline one) until the samples-per-pixel cap. Every band of
//! a generation adds into one [`Canvas`] (one set of sums, worker queues kept from band to
//! band). Frames are published as the latest one only, while a view refines at most every
//! [`REFINE_GAP`](pacing::REFINE_GAP): a slow client skips frames, it never queues them.

use super::controls::Change;
use super::orbit::Orbit;
use super::pacing;
use glam::Vec3;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock};
use std::time::{Duration, Instant};
use wavepath::RouletteKind;
use wavepath::{Bvh, Intersector};
use wavepath::{Camera, Environment, Scene};
use wavepath::{Canvas, Film, Tonemap};
use wavepath::{Extent, RenderPlan};
use wavepath::{Settings, Shading};

/// One published image and the figures shown beside it.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Increases with every frame.
    pub seq: u64,
    /// The generation (camera and settings) it shows.
    pub generation: u64,
    /// Samples per pixel accumulated.
    pub spp: u32,
    /// The cap was reached: the image is final (compressed harder: it is sent once).
    pub converged: bool,
    /// The quarter-resolution first image of a generation.
    pub coarse: bool,
    /// The linear image (for saving).
    pub film: Arc<Film>,
    /// Figures as JSON (rays, Mrays/s, stage times, effects, the BVH boxes' outlines).
    pub info: serde_json::Value,
    /// See [`Frame::image`].
    encoded: OnceLock<Vec<u8>>,
}

/// What clients change and the loop renders.
#[derive(Clone, Debug)]
pub struct ViewState {
    pub generation: u64,
    pub orbit: Orbit,
    /// The file's camera (the reset target).
    pub home: Orbit,
    pub settings: Settings,
    pub environment: bool,
    pub bvh_depth: Option<u32>,
    pub stop: bool,
}

/// State, latest frame and the condition variables that wake the loop and the clients.
pub struct Session {
    pub state: Mutex<ViewState>,
    pub changed: Condvar,
    pub frame: Mutex<Option<Arc<Frame>>>,
    pub new_frame: Condvar,
    /// Set by every change: the band being rendered stops at its next wave.
    interrupt: AtomicBool,
}

/// Bands of rows are chosen so that one takes about this long: short enough to notice a
/// camera move quickly and show ten or more updates a second, long enough that the per-frame
/// costs stay small.
const BATCH_TARGET: Duration = Duration::from_millis(80);

/// Samples per pixel of one pass over the image (a band's batch).
const PASS_SAMPLES: u32 = 16;

impl Session {
    pub fn new(scene: &Scene, settings: Settings) -> Arc<Session> {
        let center = scene.bounds().map_or(Vec3::ZERO, |(lo, hi)| 0.5 * (lo + hi));
        let home = Orbit::new(scene.camera, center);
        let state =
            ViewState { generation: 1, orbit: home, home, settings, environment: true, bvh_depth: None, stop: false };
        Arc::new(Session {
            state: Mutex::new(state),
            changed: Condvar::new(),
            frame: Mutex::new(None),
            new_frame: Condvar::new(),
            interrupt: AtomicBool::new(false),
        })
    }

    /// Applies `changes` (already validated) as one new generation. `focus` needs the
    /// accelerator to find the distance to what a pixel sees.
    pub fn apply(&self, changes: &[Change], accel: &dyn Intersector) {
        let mut guard = self.state.lock().unwrap();
        let st = &mut *guard;
        for &c in changes {
            let (s, orbit) = (&mut st.settings, &mut st.orbit);
            match c {
                Change::Orbit(yaw, pitch) => orbit.orbit(yaw, pitch),
                Change::Pan(dx, dy) => orbit.pan(dx, dy),
                Change::Zoom(f) => orbit.zoom(f),
                Change::Reset => *orbit = st.home,
                Change::Focus(x, y) => {
                    let cam = s.image.camera(&orbit.camera);
                    let ray = cam.generate_ray(x, 1.0 - y);
                    if let Some(h) = accel.closest_hit(&ray, &mut Default::default()) {
                        // The lens focuses at a distance along the view axis.
                        orbit.camera.focal_distance = (h.t * ray.dir.dot(-cam.c2w.z_axis)).max(1e-6);
                    }
                }
                Change::Spp(n) => s.sampling.spp = n,
                Change::LightSamples(n) => s.sampling.light_samples = n,
                Change::MaxDepth(m) => s.paths.max_depth = m,
                Change::Shading(sh) => s.paths.shading = sh,
                Change::Roulette(p) => {
                    s.paths.roulette.continue_prob = p;
                    s.paths.roulette.kind = RouletteKind::Fixed;
                }
                Change::Hemisphere(h) => s.paths.hemisphere = h,
                Change::LensRadius(r) => orbit.camera.lens_radius = r,
                Change::FocalDistance(d) => orbit.camera.focal_distance = d,
                Change::Environment(on) => st.environment = on,
                Change::BvhDepth(d) => st.bvh_depth = d,
                Change::Resolution(w, h) => (s.image.width, s.image.height) = (w, h),
            }
        }
        st.generation += 1;
        self.interrupt.store(true, Ordering::Relaxed);
        self.changed.notify_all();
    }

    /// Asks the loop to stop after its current batch.
    pub fn stop(&self) {
        self.state.lock().unwrap().stop = true;
        self.interrupt.store(true, Ordering::Relaxed);
        self.changed.notify_all();
        self.new_frame.notify_all();
    }

    pub fn stopped(&self) -> bool {
        self.state.lock().unwrap().stop
    }

    /// The latest frame newer than `after`, waiting up to `timeout` for one.
    pub fn frame_after(&self, after: u64, timeout: Duration) -> Option<Arc<Frame>> {
        let guard = self.frame.lock().unwrap();
        let (guard, _) = self
            .new_frame
            .wait_timeout_while(guard, timeout, |f| f.as_ref().is_none_or(|f| f.seq <= after) && !self.stopped())
            .unwrap();
        guard.as_ref().filter(|f| f.seq > after).cloned()
    }

    fn publish(&self, frame: Frame) {
        *self.frame.lock().unwrap() = Some(Arc::new(frame));
        self.new_frame.notify_all();
    }

    /// Renders until [`stop`](Self::stop): the viewer's one render thread.
    pub fn run(&self, mut scene: Scene, bvh: &Bvh) {
        let environment = scene.env.clone();
        let never = AtomicBool::new(false);
        let mut seq = 0u64;
        let mut shown = 0u64;
        // The generation's sums, and its image as last published: a band's rows are the
        // means of its pixels' sums, rows the first pass has not reached yet the coarse image.
        let mut canvas: Option<Canvas> = None;
        let mut film = Film::new(1, 1);
        // The generation's render plan, built once and reused by every band of every pass.
        let mut plan: Option<RenderPlan> = None;
        // Samples every pixel has (completed passes); the current pass renders band `band` of
        // `bands`, and has taken `pass_s` seconds so far.
        let mut taken = 0u32;
        let (mut band, mut bands, mut pass_s) = (0usize, 1usize, 0.0f64);
        let mut totals = Totals::default();
        // The generation and time of the last frame published.
        let mut published = None;
        loop {
            // Cleared before the state is read: a change after this point stops the next band.
            self.interrupt.store(false, Ordering::Relaxed);
            let st = {
                let guard = self.state.lock().unwrap();
                let done = |s: &ViewState| {
                    s.generation == shown
                        && (taken >= s.settings.sampling.spp || s.settings.paths.shading == Shading::Normals)
                };
                let guard = self.changed.wait_while(guard, |s| !s.stop && done(s)).unwrap();
                if guard.stop {
                    return;
                }
                guard.clone()
            };
            let s = &st.settings;
            let (width, height) = (s.image.width, s.image.height);
            let fresh = st.generation != shown;
            if fresh {
                // The scene changes with the generation: the old plan (which reads it) goes
                // first. Only the camera's pose and lens are written into it: each plan fits
                // the camera to its own image size.
                plan = None;
                scene.camera = st.orbit.camera;
                scene.set_environment(if st.environment { environment.clone() } else { Environment::None });
                shown = st.generation;
                (taken, band, pass_s) = (0, 0, 0.0);
                totals = Totals::default();
                // A coarse image at once: a quarter of the resolution, one sample, a one-off
                // render with its own settings (and so its own fit of the camera).
                let (w, h) = ((width / 4).max(1), (height / 4).max(1));
                let mut quick = s.clone();
                quick.image.width = w;
                quick.image.height = h;
                quick.sampling.spp = 1;
                quick.sampling.adaptive = None;
                quick.sampling.sample_range = None;
                let t = Instant::now();
                let quick_out = wavepath::render_with_progress(&scene, bvh, &quick, &|_| {});
                let quick_s = t.elapsed();
                // The plan of every pass: the full resolution's camera, all samples at once
                // per pixel (no adaptive batches).
                let mut full = s.clone();
                full.sampling.adaptive = None;
                full.sampling.sample_range = None;
                let p = plan.insert(RenderPlan::new(&scene, &full));
                let mut upscaled = None;
                if let Ok(out) = quick_out {
                    // The first pass's bands from this one-sample image's time (16x fewer
                    // pixels, PASS_SAMPLES x fewer samples).
                    let estimate = quick_s.as_secs_f64() * 16.0 * PASS_SAMPLES.min(s.sampling.spp) as f64;
                    bands = ((estimate / BATCH_TARGET.as_secs_f64()).round() as usize).clamp(1, height);
                    totals.add(&out.stats, quick_s);
                    seq += 1;
                    let info = Self::info(&st, p, bvh, &totals, 0, (w, h));
                    let f = frame(seq, shown, out.film, 0, false, true, info);
                    upscaled = Some(f.film.clone());
                    self.publish(f);
                    published = Some((shown, Instant::now()));
                }
                // After the coarse image is out: the full-resolution image, the coarse one
                // scaled up where the first pass has not been.
                film = Film::new(width, height);
                if let Some(c) = upscaled {
                    for (y, row) in film.pixels.chunks_exact_mut(width).enumerate() {
                        let cy = (y * c.height / height).min(c.height - 1);
                        for (x, px) in row.iter_mut().enumerate() {
                            *px = c.get((x * c.width / width).min(c.width - 1), cy);
                        }
                    }
                }
                if s.paths.shading == Shading::Normals {
                    // Normals have no samples to accumulate: one full image and done.
                    if let Ok(out) = wavepath::render_plan(p, bvh, Extent::WHOLE, &|_| {}, &never) {
                        seq += 1;
                        let info = Self::info(&st, p, bvh, &totals, s.sampling.spp, (width, height));
                        self.publish(frame(seq, shown, out.film, s.sampling.spp, true, false, info));
                    }
                    taken = s.sampling.spp;
                    canvas = None;
                } else {
                    // Allocated after the coarse image is out (its sums are tens of MB). Its
                    // queues belong to this thread's rayon pool, where its bands run.
                    match canvas.as_mut().filter(|c| (c.sums().width, c.sums().height) == (width, height)) {
                        Some(c) => c.clear(),
                        None => canvas = Some(Canvas::new(width, height)),
                    }
                }
                continue;
            }
            let (Some(p), Some(c)) = (plan.as_ref(), canvas.as_mut()) else { continue };
            // One band of rows, the pass's samples for each of its pixels at once (as an
            // offline render takes them: a pixel's samples side by side in a wave trace
            // coherent rays; two samples per pixel over the whole image run 28% slower).
            let end = (taken + PASS_SAMPLES).min(s.sampling.spp);
            let (y0, y1) = (band * height / bands, (band + 1) * height / bands);
            let cell = wavepath::Cell { x: 0, y: y0, w: width, h: y1 - y0 };
            let extent = Extent { cell: Some(cell), samples: Some((taken, end)) };
            let t = Instant::now();
            let stats = match c.render(p, bvh, extent, &|_| {}, &self.interrupt) {
                Ok(stats) => stats,
                // A change stopped the band: the next turn starts its generation.
                Err(e) if e.downcast_ref::<wavepath::Interrupted>().is_some() => continue,
                Err(_) => {
                    taken = s.sampling.spp;
                    continue;
                }
            };
            pass_s += t.elapsed().as_secs_f64();
            totals.add(&stats, t.elapsed());
            let sums = &c.sums().pixels;
            let rows = y0 * width..y1 * width;
            for (px, sum) in film.pixels[rows.clone()].iter_mut().zip(&sums[rows]) {
                *px = sum.mean();
            }
            band += 1;
            if band == bands {
                // The pass is complete: the next one's bands take about the target time each.
                taken = end;
                band = 0;
                bands = ((pass_s / BATCH_TARGET.as_secs_f64()).round() as usize).clamp(1, height);
                pass_s = 0.0;
            }
            // A refining frame waits for its turn ([`pacing`]; the band's rows stay in `film`
            // for the next one), and a newer generation makes it stale: skip publishing it.
            let converged = taken >= s.sampling.spp;
            if !pacing::hold(published, shown, converged, Instant::now()).is_zero()
                || self.state.lock().unwrap().generation != shown
            {
                continue;
            }
            seq += 1;
            let info = Self::info(&st, p, bvh, &totals, taken, (width, height));
            self.publish(frame(seq, shown, film.clone(), taken, converged, false, info));
            published = Some((shown, Instant::now()));
        }
    }

    /// The figures of a frame; the effects are the generation's (its plan's).
    fn info(
        st: &ViewState,
        plan: &RenderPlan,
        bvh: &Bvh,
        t: &Totals,
        spp: u32,
        (w, h): (usize, usize),
    ) -> serde_json::Value {
        let effects = plan.effects();
        // The camera of the image shown: the plan's at full size, the coarse image's own fit
        // (of the same scene camera) at a quarter of it.
        let image = wavepath::ImageSettings { width: w, height: h, ..plan.settings().image };
        let camera = image.camera(&plan.scene().camera);
        let boxes = st.bvh_depth.map(|d| outlines(bvh, &camera, d)).unwrap_or_default();
        serde_json::json!({
            "spp": spp,
            "spp_cap": st.settings.sampling.spp,
            "width": w,
            "height": h,
            "rays": t.rays,
            "render_s": t.seconds,
            "mrays_per_s": if t.seconds > 0.0 { t.rays as f64 / t.seconds / 1e6 } else { 0.0 },
            "stages": t.stages,
            "effects": effects.on.iter().map(|e| serde_json::json!({"name": e.name, "reason": e.reason})).collect::<Vec<_>>(),
            "settings": {
                "l": st.settings.sampling.light_samples, "m": st.settings.paths.max_depth,
                "shading": format!("{:?}", st.settings.paths.shading).to_lowercase(),
                "rr": st.settings.paths.roulette.continue_prob, "hemisphere": st.settings.paths.hemisphere,
                "lens": st.orbit.camera.lens_radius, "focal": st.orbit.camera.focal_distance,
                "env": st.environment, "bvh": st.bvh_depth,
            },
            "bvh_boxes": boxes,
        })
    }
}

/// Rays, seconds and stage times of the current generation so far.
#[derive(Default)]
struct Totals {
    rays: u64,
    seconds: f64,
    stages: std::collections::BTreeMap<String, f64>,
}

impl Totals {
    fn add(&mut self, st: &wavepath::RenderStats, dt: Duration) {
        self.rays += st.total_rays();
        self.seconds += dt.as_secs_f64();
        if let Ok(serde_json::Value::Object(m)) = serde_json::to_value(st.stages) {
            for (k, v) in m {
                if let Some(x) = v.as_f64() {
                    *self.stages.entry(k).or_default() += x;
                }
            }
        }
    }
}

/// A frame of `film`; its image is encoded when a client first asks for it.
fn frame(
    seq: u64,
    generation: u64,
    film: Film,
    spp: u32,
    converged: bool,
    coarse: bool,
    info: serde_json::Value,
) -> Frame {
    Frame { seq, generation, spp, converged, coarse, film: Arc::new(film), info, encoded: OnceLock::new() }
}

impl Frame {
    /// PNG: every frame is lossless.
    pub fn mime(&self) -> &'static str {
        "image/png"
    }

    /// The encoded image. The first thread that asks (a client's) encodes it, never the
    /// render thread, and a frame no client asks for is never encoded.
    pub fn image(&self) -> &[u8] {
        self.encoded.get_or_init(|| encode(&self.film, self.converged))
    }
}

/// A PNG of `film`, sRGB. A frame's encoding takes a core from the render on a small
/// machine, so refining frames are compressed fast: at 640x480 on 2 cores (loaded) fast
/// PNG took 7.5 ms a frame where JPEG (quality 85) took 23 ms, for 290 KB instead of 60 KB
/// (docs/decisions.md, "Interactive viewer"). The converged frame, sent once, is compressed
/// as a saved image is.
fn encode(film: &Film, last: bool) -> Vec<u8> {
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    let (w, h) = (film.width, film.height);
    // sRGB bytes from a table over [0, 1] in 4096 steps (a power per channel and pixel would
    // cost more than the encoding).
    let table: Vec<u8> = (0..=4096).map(|i| Tonemap::Srgb.byte(i as f32 / 4096.0)).collect();
    let byte = |l: f32| table[(l.clamp(0.0, 1.0) * 4096.0) as usize];
    let mut rgb = Vec::with_capacity(w * h * 3);
    // The film's first row is the image's bottom one.
    for row in film.pixels.chunks_exact(w.max(1)).rev() {
        for p in row {
            rgb.extend([byte(p.x), byte(p.y), byte(p.z)]);
        }
    }
    let mut image = Vec::new();
    let compression = if last { CompressionType::Default } else { CompressionType::Fast };
    let encoder = PngEncoder::new_with_quality(&mut image, compression, FilterType::Adaptive);
    let _ = image::ImageEncoder::write_image(encoder, &rgb, w as u32, h as u32, image::ExtendedColorType::Rgb8);
    image
}

/// The boxes of the BVH at `depth` projected onto the image of `cam` (fitted to it): each
/// box as its 12 edges, segments (x0, y0, x1, y1) in [0, 1]^2 (top-left origin), edges
/// behind the camera dropped. At most 4096 boxes.
fn outlines(bvh: &Bvh, cam: &Camera, depth: u32) -> Vec<[f32; 4]> {
    let (tx, ty) = ((cam.hfov_deg.to_radians() * 0.5).tan(), (cam.vfov_deg.to_radians() * 0.5).tan());
    let project = |p: Vec3| -> Option<(f32, f32)> {
        let d = cam.c2w.transpose() * (p - cam.position);
        (d.z < -1e-6).then(|| (0.5 + d.x / (-d.z * 2.0 * tx), 0.5 - d.y / (-d.z * 2.0 * ty)))
    };
    let mut out = Vec::new();
    for (lo, hi) in bvh.boxes_at_depth(depth).into_iter().take(4096) {
        let corner = |i: usize| Vec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][(i >> 1) & 1], [lo.z, hi.z][(i >> 2) & 1]);
        for (a, b) in [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)] {
            if let (Some(p), Some(q)) = (project(corner(a)), project(corner(b))) {
                out.push([p.0, p.1, q.0, q.1]);
            }
        }
    }
    out
}
