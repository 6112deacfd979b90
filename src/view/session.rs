//! One interactive render: the state clients change, and the loop that renders it frame by
//! frame with the same wavefront integrator as an offline render. Any change bumps a
//! generation counter and stops the band being rendered (between waves); the loop shows a
//! quarter-resolution one-sample image at once, then refines the full-resolution image band
//! by band, 16 samples per pixel per pass (sample indices 0, 1, 2, ... of the offline render,
//! so the converged image is the offline one) until the samples-per-pixel cap. Every band of
//! a generation adds into one [`Canvas`] (one set of sums, worker queues kept from band to
//! band). Frames are published as the latest one only, while a view refines at most every
//! [`REFINE_GAP`](pacing::REFINE_GAP): a slow client skips frames, it never queues them.
//!
//! A frame shows the picture or one output variable of the same canvas ([`Look`]), mapped
//! for display ([`aov_view`]); with a denoiser, the picture's frames can be denoised by a
//! thread of their own (fed the canvas's albedo and normal), paced by
//! [`pacing::denoise_due`] so that it never stalls the refinement, and always on the final
//! image.

use super::controls::{Change, show_name};
use super::orbit::Orbit;
use super::pacing;
use glam::Vec3;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock};
use std::time::{Duration, Instant};
use wavepath::RouletteKind;
use wavepath::{Aov, AovImage, AovSet, Aux, Denoiser};
use wavepath::{Bvh, Intersector};
use wavepath::{Camera, Environment, Scene};
use wavepath::{Canvas, Film, Tonemap};
use wavepath::{Extent, RenderPlan};
use wavepath::{Settings, Shading};

/// Why a client may not denoise: the one line a refused request gets, and the page's
/// tooltip on its disabled box.
pub const NO_DENOISER: &str = "denoise: this viewer has no Open Image Denoise: `pip install pyoidn` into the \
    environment of python3 and restart wavepath view, or start it with --oidn PATH";

/// What the image shows of the render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Look {
    /// The picture (`None`) or one output variable.
    pub show: Option<Aov>,
    /// The picture's frames are denoised.
    pub denoise: bool,
}

impl Look {
    /// The render must keep first-hit sums: a first-hit variable is shown, or the denoiser is
    /// fed albedo and normal. The variance comes from the pixel sums every render keeps.
    pub fn first_hits(self) -> bool {
        self.denoise || self.show.is_some_and(|a| a != Aov::Variance)
    }
}

/// Every first-hit variable: a canvas that keeps first-hit sums keeps them all.
fn first_hit_set() -> AovSet {
    AovSet::NONE.with(Aov::Albedo).with(Aov::Normal).with(Aov::Depth).with(Aov::Position)
}

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
    /// What it shows: the picture (`None`) or an output variable.
    pub show: Option<Aov>,
    /// The picture, denoised.
    pub denoised: bool,
    /// The linear image (for saving): the picture, or the variable's values (a one-channel
    /// variable in every channel).
    pub film: Arc<Film>,
    /// The image as displayed: the picture, or the variable mapped into [0, 1].
    pub display: Arc<Film>,
    /// `display` is a colour, sRGB-encoded as the picture is (else its values are the bytes:
    /// normals, depth, position, false colour).
    pub srgb: bool,
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
    /// What the frames show.
    pub look: Look,
    /// The generation's render keeps first-hit sums.
    pub first_hits: bool,
}

/// State, latest frame and the condition variables that wake the loop and the clients.
pub struct Session {
    pub state: Mutex<ViewState>,
    pub changed: Condvar,
    pub frame: Mutex<Option<Arc<Frame>>>,
    pub new_frame: Condvar,
    /// Set by every change: the band being rendered stops at its next wave.
    interrupt: AtomicBool,
    /// Set by [`stop`](Self::stop) (read without the state's lock).
    stopping: AtomicBool,
    /// The scene's bounds: the position variable is shown across them.
    bounds: Option<(Vec3, Vec3)>,
    pub denoiser: Option<Arc<Denoiser>>,
    /// The denoising thread's inbox and the condition variable that wakes it.
    denoise_slot: Mutex<DenoiseSlot>,
    denoise_wake: Condvar,
}

/// The denoiser's inbox: at most one image waiting, and when its last run ended and how long
/// it took.
#[derive(Default)]
struct DenoiseSlot {
    job: Option<DenoiseJob>,
    busy: bool,
    last: Option<(Instant, f64)>,
    quit: bool,
}

/// A picture to denoise and the frame it becomes.
struct DenoiseJob {
    generation: u64,
    look: Look,
    film: Film,
    albedo: Film,
    normal: Film,
    spp: u32,
    converged: bool,
    info: serde_json::Value,
}

/// The image of a generation as it stands, for [`Session::present`].
struct Current<'a> {
    /// The output variables of a set from the sums so far (`None`: the render keeps none).
    aovs: Option<&'a dyn Fn(AovSet) -> Vec<AovImage>>,
    picture: &'a Film,
    /// Rows of the full-resolution image the first pass has reached: the others of a variable
    /// come from `coarse` scaled up.
    rows: usize,
    /// The coarse image's output variables.
    coarse: &'a [AovImage],
    spp: u32,
    converged: bool,
    is_coarse: bool,
}

/// Bands of rows are chosen so that one takes about this long: short enough to notice a
/// camera move quickly and show ten or more updates a second, long enough that the per-frame
/// costs stay small.
const BATCH_TARGET: Duration = Duration::from_millis(80);

/// Bands of a pass expected to take `seconds` in all: each about [`BATCH_TARGET`]. Under
/// path+light the pass's first band traces the light subpaths of the whole image and the
/// plan keeps what they splatted for the others (`RenderPlan::kept_splats`); each band
/// tracing them again took the harness's spheres-box, 320x240 to 64 spp, 7.2-7.7 s against
/// 2.07 s offline.
fn band_count(seconds: f64, height: usize) -> usize {
    ((seconds / BATCH_TARGET.as_secs_f64()).round() as usize).clamp(1, height)
}

/// Samples per pixel of one pass over the image (a band's batch).
const PASS_SAMPLES: u32 = 16;

impl Session {
    /// A session showing `look` first (denoising only with a `denoiser`).
    pub fn new(scene: &Scene, settings: Settings, denoiser: Option<Arc<Denoiser>>, mut look: Look) -> Arc<Session> {
        let bounds = scene.bounds();
        let center = bounds.map_or(Vec3::ZERO, |(lo, hi)| 0.5 * (lo + hi));
        let home = Orbit::new(scene.camera, center);
        look.denoise &= denoiser.is_some();
        let state = ViewState {
            generation: 1,
            orbit: home,
            home,
            settings,
            environment: true,
            bvh_depth: None,
            stop: false,
            look,
            first_hits: look.first_hits(),
        };
        Arc::new(Session {
            state: Mutex::new(state),
            changed: Condvar::new(),
            frame: Mutex::new(None),
            new_frame: Condvar::new(),
            interrupt: AtomicBool::new(false),
            stopping: AtomicBool::new(false),
            bounds,
            denoiser,
            denoise_slot: Mutex::new(DenoiseSlot::default()),
            denoise_wake: Condvar::new(),
        })
    }

    /// Applies `changes` (already validated) as one new generation, unless they only change
    /// the look and the generation's canvas can show it. `focus` needs the accelerator to
    /// find the distance to what a pixel sees.
    pub fn apply(&self, changes: &[Change], accel: &dyn Intersector) {
        let mut guard = self.state.lock().unwrap();
        let st = &mut *guard;
        let mut restart = false;
        for &c in changes {
            let (s, orbit) = (&mut st.settings, &mut st.orbit);
            restart |= !matches!(c, Change::Show(_) | Change::Denoise(_));
            match c {
                Change::Show(a) => st.look.show = a,
                Change::Denoise(on) => st.look.denoise = on,
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
        // Keeping first-hit sums costs render time, so a render keeps them only while the
        // look needs them. Showing a first-hit variable or denoising when the generation's
        // canvas keeps none restarts refinement with one that does; a look the canvas can
        // show (another variable, the picture again) only shows the same sums another way,
        // and the sums stay kept until the next restart (which keeps them only if needed).
        if restart || (st.look.first_hits() && !st.first_hits) {
            st.generation += 1;
            st.first_hits = st.look.first_hits();
            self.interrupt.store(true, Ordering::Relaxed);
        }
        self.changed.notify_all();
    }

    /// Asks the loop to stop after its current batch.
    pub fn stop(&self) {
        self.state.lock().unwrap().stop = true;
        self.stopping.store(true, Ordering::Relaxed);
        self.interrupt.store(true, Ordering::Relaxed);
        self.changed.notify_all();
        self.new_frame.notify_all();
    }

    pub fn stopped(&self) -> bool {
        self.stopping.load(Ordering::Relaxed)
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

    /// Publishes `frame` as the latest, numbered after the one before.
    fn publish(&self, mut frame: Frame) {
        let mut latest = self.frame.lock().unwrap();
        frame.seq = latest.as_ref().map_or(1, |f| f.seq + 1);
        *latest = Some(Arc::new(frame));
        self.new_frame.notify_all();
    }

    /// Renders until [`stop`](Self::stop): the viewer's render thread, and beside it, with a
    /// denoiser, the denoising thread.
    pub fn run(&self, scene: Scene, bvh: &Bvh) {
        /// Tells the denoising thread to end, also when the render thread panics.
        struct Quit<'a>(&'a Session);
        impl Drop for Quit<'_> {
            fn drop(&mut self) {
                self.0.denoise_slot.lock().unwrap_or_else(|e| e.into_inner()).quit = true;
                self.0.denoise_wake.notify_all();
            }
        }
        std::thread::scope(|threads| {
            if let Some(d) = &self.denoiser {
                threads.spawn(move || self.denoise_loop(d));
            }
            let _quit = Quit(self);
            self.render_loop(scene, bvh);
        });
    }

    /// Denoises the images the render thread hands over, one at a time, and publishes each
    /// if its view and look are still the ones shown.
    fn denoise_loop(&self, d: &Denoiser) {
        loop {
            let job = {
                let slot = self.denoise_slot.lock().unwrap();
                let mut slot = self.denoise_wake.wait_while(slot, |s| s.job.is_none() && !s.quit).unwrap();
                if slot.quit {
                    return;
                }
                slot.busy = true;
                slot.job.take().expect("a job")
            };
            let t = Instant::now();
            let aux = Aux { albedo: Some(&job.albedo), normal: Some(&job.normal), prefilter: true };
            let out = d.denoise(&job.film, aux);
            let secs = t.elapsed().as_secs_f64();
            {
                let mut slot = self.denoise_slot.lock().unwrap();
                slot.busy = false;
                slot.last = Some((Instant::now(), secs));
            }
            let mut info = job.info;
            info["denoise_s"] = secs.into();
            let (film, denoised) = match out {
                Ok(f) => (f, true),
                Err(e) => {
                    info["note"] = format!("denoising failed: {e:#}").into();
                    (job.film, false)
                }
            };
            // Under the state's lock: a change of view or look after this check re-presents
            // the image after this frame.
            let st = self.state.lock().unwrap();
            if st.generation == job.generation && st.look == job.look && !st.stop {
                let film = Arc::new(film);
                self.publish(Frame {
                    seq: 0,
                    generation: job.generation,
                    spp: job.spp,
                    converged: job.converged,
                    coarse: false,
                    show: None,
                    denoised,
                    display: film.clone(),
                    film,
                    srgb: true,
                    info,
                    encoded: OnceLock::new(),
                });
            }
        }
    }

    /// Publishes the image `cur` of the generation of `st` as `st.look` shows it, or hands
    /// it to the denoiser; false when nothing went out (a refining image the denoiser is not
    /// due for: a later band's image goes instead).
    fn present(&self, st: &ViewState, cur: Current<'_>, mut info: serde_json::Value) -> bool {
        let (w, h) = (cur.picture.width, cur.picture.height);
        let picture = |info: serde_json::Value| {
            let film = Arc::new(cur.picture.clone());
            Frame {
                seq: 0,
                generation: st.generation,
                spp: cur.spp,
                converged: cur.converged,
                coarse: cur.is_coarse,
                show: None,
                denoised: false,
                display: film.clone(),
                film,
                srgb: true,
                info,
                encoded: OnceLock::new(),
            }
        };
        let Some(aovs) = cur.aovs else {
            if st.look.show.is_some() {
                info["note"] = "normals shading keeps no output variables: the picture is shown".into();
            }
            self.publish(picture(info));
            return true;
        };
        if let Some(aov) = st.look.show {
            let Some((data, mut display, srgb, how)) = aov_view(aov, &aovs(aov_set(aov)), self.bounds) else {
                info["note"] = format!("the render keeps no {}", aov.name()).into();
                self.publish(picture(info));
                return true;
            };
            // Rows the first pass has not reached: the coarse image's, scaled up.
            if cur.rows < h
                && let Some((_, small, _, _)) = aov_view(aov, cur.coarse, self.bounds)
            {
                fill_rows(&mut display, &small, cur.rows);
            }
            info["display"] = how.into();
            self.publish(Frame {
                seq: 0,
                generation: st.generation,
                spp: cur.spp,
                converged: cur.converged,
                coarse: cur.is_coarse,
                show: Some(aov),
                denoised: false,
                film: Arc::new(data),
                display: Arc::new(display),
                srgb,
                info,
                encoded: OnceLock::new(),
            });
            return true;
        }
        // The denoised picture once every pixel has a pass's samples (the coarse image and
        // the first pass's rows are shown as they are).
        if st.look.denoise && self.denoiser.is_some() && !cur.is_coarse && cur.spp > 0 {
            let mut slot = self.denoise_slot.lock().unwrap();
            if !cur.converged && (slot.busy || slot.job.is_some() || !pacing::denoise_due(slot.last, Instant::now())) {
                return false;
            }
            let images = aovs(AovSet::NONE.with(Aov::Albedo).with(Aov::Normal));
            let film_of = |a: Aov| images.iter().find(|i| i.aov == a).map_or_else(|| Film::new(w, h), |i| i.to_film());
            // The final image replaces a refining one still waiting.
            slot.job = Some(DenoiseJob {
                generation: st.generation,
                look: st.look,
                film: cur.picture.clone(),
                albedo: film_of(Aov::Albedo),
                normal: film_of(Aov::Normal),
                spp: cur.spp,
                converged: cur.converged,
                info,
            });
            self.denoise_wake.notify_all();
            return true;
        }
        if st.look.denoise {
            info["note"] = "denoised once the first pass has covered the image".into();
        }
        self.publish(picture(info));
        true
    }

    /// The render loop.
    fn render_loop(&self, mut scene: Scene, bvh: &Bvh) {
        let environment = scene.env.clone();
        let never = AtomicBool::new(false);
        let mut shown = 0u64;
        // The generation's sums, and its picture as last published: a band's rows are the
        // means of its pixels' sums, rows the first pass has not reached yet the coarse image.
        let mut canvas: Option<Canvas> = None;
        let mut film = Film::new(1, 1);
        // The coarse image's output variables (those its look showed).
        let mut coarse_aovs: Vec<AovImage> = Vec::new();
        // The generation's render plan, built once and reused by every band of every pass.
        let mut plan: Option<RenderPlan> = None;
        // Samples every pixel has (completed passes); the current pass renders band `band` of
        // `bands`, and has taken `pass_s` seconds so far; the first pass has reached `rows`.
        let mut taken = 0u32;
        let (mut band, mut bands, mut pass_s, mut rows) = (0usize, 1usize, 0.0f64, 0usize);
        let mut totals = Totals::default();
        // The generation and time of the last frame published.
        let mut published = None;
        // The look the final image was last presented in.
        let mut final_look: Option<Look> = None;
        let finished = |s: &ViewState, taken: u32| {
            taken >= s.settings.sampling.spp || s.settings.paths.shading == Shading::Normals
        };
        loop {
            // Cleared before the state is read: a change after this point stops the next band.
            self.interrupt.store(false, Ordering::Relaxed);
            let st = {
                let guard = self.state.lock().unwrap();
                let done = |s: &ViewState| s.generation == shown && finished(s, taken) && final_look == Some(s.look);
                let guard = self.changed.wait_while(guard, |s| !s.stop && done(s)).unwrap();
                if guard.stop {
                    return;
                }
                guard.clone()
            };
            let s = &st.settings;
            let (width, height) = (s.image.width, s.image.height);
            let normals = s.paths.shading == Shading::Normals;
            if st.generation != shown {
                // The scene changes with the generation: the old plan (which reads it) goes
                // first. Only the camera's pose and lens are written into it: each plan fits
                // the camera to its own image size.
                plan = None;
                scene.camera = st.orbit.camera;
                scene.set_environment(if st.environment { environment.clone() } else { Environment::None });
                shown = st.generation;
                (taken, band, pass_s, rows) = (0, 0, 0.0, 0);
                totals = Totals::default();
                final_look = None;
                // A coarse image at once: a quarter of the resolution, one sample, a one-off
                // render with its own settings (and so its own fit of the camera), keeping the
                // variable shown if any.
                let (w, h) = ((width / 4).max(1), (height / 4).max(1));
                let mut quick = s.clone();
                quick.image.width = w;
                quick.image.height = h;
                quick.image.aovs = match st.look.show {
                    Some(a) if !normals => aov_set(a),
                    _ => AovSet::NONE,
                };
                quick.sampling.spp = 1;
                quick.sampling.adaptive = None;
                quick.sampling.sample_range = None;
                let t = Instant::now();
                let quick_out = wavepath::render_with_progress(&scene, bvh, &quick, &|_| {});
                let quick_s = t.elapsed();
                // The plan of every pass: the full resolution's camera, all samples at once
                // per pixel (no adaptive batches), first hits recorded when the look needs
                // them (the canvas then keeps their sums).
                let mut full = s.clone();
                full.sampling.adaptive = None;
                full.sampling.sample_range = None;
                let keep = st.first_hits && !normals;
                full.image.aovs = if keep { first_hit_set() } else { AovSet::NONE };
                let p = plan.insert(RenderPlan::new(&scene, &full));
                let mut upscaled = None;
                coarse_aovs.clear();
                if let Ok(out) = quick_out {
                    // The first pass's bands from this one-sample image's time (16x fewer
                    // pixels, PASS_SAMPLES x fewer samples).
                    let estimate = quick_s.as_secs_f64() * 16.0 * PASS_SAMPLES.min(s.sampling.spp) as f64;
                    bands = band_count(estimate, height);
                    totals.add(&out.stats, quick_s);
                    let info = self.info(&st, p, bvh, &totals, 0, (w, h));
                    let images = |set: AovSet| out.aovs.iter().filter(|i| set.contains(i.aov)).cloned().collect();
                    let cur = Current {
                        aovs: (!normals).then_some(&images as &dyn Fn(AovSet) -> Vec<AovImage>),
                        picture: &out.film,
                        rows: h,
                        coarse: &[],
                        spp: 0,
                        converged: false,
                        is_coarse: true,
                    };
                    self.present(&st, cur, info);
                    published = Some((shown, Instant::now()));
                    upscaled = Some(out.film);
                    coarse_aovs = out.aovs;
                }
                // After the coarse image is out: the full-resolution image, the coarse one
                // scaled up where the first pass has not been.
                film = Film::new(width, height);
                if let Some(c) = &upscaled {
                    fill_rows(&mut film, c, 0);
                }
                if normals {
                    // Normals have no samples to accumulate: one full image and done.
                    if let Ok(out) = wavepath::render_plan(p, bvh, Extent::WHOLE, &|_| {}, &never) {
                        film = out.film;
                        let info = self.info(&st, p, bvh, &totals, s.sampling.spp, (width, height));
                        let cur = Current {
                            aovs: None,
                            picture: &film,
                            rows: height,
                            coarse: &[],
                            spp: s.sampling.spp,
                            converged: true,
                            is_coarse: false,
                        };
                        self.present(&st, cur, info);
                    }
                    taken = s.sampling.spp;
                    canvas = None;
                    final_look = Some(st.look);
                } else {
                    // Allocated after the coarse image is out (its sums are tens of MB). Its
                    // queues belong to this thread's rayon pool, where its bands run. One that
                    // keeps first-hit sums only when this generation's look needs them.
                    let fits = |c: &Canvas| {
                        (c.sums().width, c.sums().height) == (width, height) && c.sums().aovs.is_empty() != keep
                    };
                    match canvas.as_mut().filter(|c| fits(c)) {
                        Some(c) => c.clear(),
                        None => {
                            // The old sums go before the new ones are allocated.
                            drop(canvas.take());
                            canvas = Some(if keep {
                                Canvas::with_aovs(width, height, first_hit_set())
                            } else {
                                Canvas::new(width, height)
                            });
                        }
                    }
                }
                continue;
            }
            let Some(p) = plan.as_ref() else { continue };
            if finished(&st, taken) {
                // The look changed on the final image: the same image shown the new way.
                let info = self.info(&st, p, bvh, &totals, taken, (width, height));
                let images = canvas.as_ref().map(|c| move |set: AovSet| c.aov_images(set));
                let cur = Current {
                    aovs: images.as_ref().map(|f| f as &dyn Fn(AovSet) -> Vec<AovImage>),
                    picture: &film,
                    rows: height,
                    coarse: &[],
                    spp: taken,
                    converged: true,
                    is_coarse: false,
                };
                self.present(&st, cur, info);
                final_look = Some(st.look);
                continue;
            }
            let Some(c) = canvas.as_mut() else { continue };
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
            let span = y0 * width..y1 * width;
            for (px, sum) in film.pixels[span.clone()].iter_mut().zip(&sums[span]) {
                *px = sum.mean();
            }
            rows = rows.max(y1);
            band += 1;
            if band == bands {
                // The pass is complete: the next one's bands take about the target time each.
                taken = end;
                band = 0;
                bands = band_count(pass_s, height);
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
            let info = self.info(&st, p, bvh, &totals, taken, (width, height));
            let c: &Canvas = c;
            let images = |set: AovSet| c.aov_images(set);
            let cur = Current {
                aovs: Some(&images),
                picture: &film,
                rows,
                coarse: &coarse_aovs,
                spp: taken,
                converged,
                is_coarse: false,
            };
            if self.present(&st, cur, info) {
                published = Some((shown, Instant::now()));
                if converged {
                    final_look = Some(st.look);
                }
            }
        }
    }

    /// The figures of a frame; the effects are the generation's (its plan's).
    fn info(
        &self,
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
                "show": show_name(st.look.show), "denoise": st.look.denoise,
            },
            // The generation's render keeps first-hit sums (costs render time).
            "first_hits": st.first_hits,
            "denoiser": match &self.denoiser {
                Some(d) => serde_json::json!({"available": true, "library": d.library().display().to_string()}),
                None => serde_json::json!({"available": false, "help": NO_DENOISER}),
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

impl Frame {
    /// PNG: every frame is lossless.
    pub fn mime(&self) -> &'static str {
        "image/png"
    }

    /// The encoded image. The first thread that asks (a client's) encodes it, never the
    /// render thread, and a frame no client asks for is never encoded.
    pub fn image(&self) -> &[u8] {
        self.encoded.get_or_init(|| encode(&self.display, self.converged, self.srgb))
    }

    /// The displayed image as a PNG file's bytes (compressed as a saved image is).
    pub fn display_png(&self) -> Vec<u8> {
        encode(&self.display, true, self.srgb)
    }

    /// What the frame shows, for file names and figures: "picture", "denoised" or the
    /// variable's name.
    pub fn label(&self) -> &'static str {
        match (self.show, self.denoised) {
            (Some(a), _) => a.name(),
            (None, true) => "denoised",
            (None, false) => show_name(None),
        }
    }
}

/// A PNG of `film`: sRGB-encoded (`srgb`) or its values taken as the bytes' fractions. A
/// frame's encoding takes a core from the render on a small machine, so refining frames are
/// compressed fast: at 640x480 on 2 cores (loaded) fast PNG took 7.5 ms a frame where JPEG
/// (quality 85) took 23 ms, for 290 KB instead of 60 KB (docs/decisions.md, "Interactive
/// viewer"). The converged frame, sent once, is compressed as a saved image is.
fn encode(film: &Film, last: bool, srgb: bool) -> Vec<u8> {
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    let (w, h) = (film.width, film.height);
    // Bytes from a table over [0, 1] in 4096 steps (a power per channel and pixel would cost
    // more than the encoding).
    let table: Vec<u8> = (0..=4096)
        .map(|i| {
            let l = i as f32 / 4096.0;
            if srgb { Tonemap::Srgb.byte(l) } else { (l * 255.0 + 0.5) as u8 }
        })
        .collect();
    let byte = |l: f32| table[(if l.is_nan() { 0.0 } else { l.clamp(0.0, 1.0) } * 4096.0) as usize];
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

/// Rows `from..` of `film` from `small` scaled up (nearest pixel).
fn fill_rows(film: &mut Film, small: &Film, from: usize) {
    let (width, height) = (film.width, film.height);
    if small.width == 0 || small.height == 0 || width == 0 {
        return;
    }
    for (y, row) in film.pixels.chunks_exact_mut(width).enumerate().skip(from) {
        let cy = (y * small.height / height).min(small.height - 1);
        for (x, px) in row.iter_mut().enumerate() {
            *px = small.get((x * small.width / width).min(small.width - 1), cy);
        }
    }
}

/// The variables the view of `aov` reads (a position's misses are told by its depth).
fn aov_set(aov: Aov) -> AovSet {
    let set = AovSet::NONE.with(aov);
    if aov == Aov::Position { set.with(Aov::Depth) } else { set }
}

/// An output variable of `images` as the viewer shows it: its values as a film (what an
/// .exr save writes), the image displayed (values in [0, 1]), whether that is a colour to
/// sRGB-encode, and how it was mapped (shown beside the image). `None` when `images` lacks
/// it.
/// - albedo: as it is, a colour like the picture;
/// - normal: n/2 + 1/2 per component (a miss's zero normal is mid grey);
/// - depth: grey from the frame's nearest hit (white) to its farthest (dark grey, 0.1); no
///   hit black;
/// - position: x, y, z across the scene's bounding box as red, green, blue; no hit black;
/// - variance: the standard error of the pixel's mean (the square root of the variance of
///   the mean, averaged over the channels) in false colour (black, red, yellow, white) up to
///   the frame's 99th percentile.
fn aov_view(aov: Aov, images: &[AovImage], bounds: Option<(Vec3, Vec3)>) -> Option<(Film, Film, bool, String)> {
    let find = |a: Aov| images.iter().find(|i| i.aov == a);
    let data = find(aov)?.to_film();
    let map = |f: &dyn Fn(Vec3) -> Vec3| Film {
        width: data.width,
        height: data.height,
        pixels: data.pixels.iter().map(|&p| f(p)).collect(),
    };
    let finite = |x: f32| if x.is_finite() { x } else { 0.0 };
    let (display, srgb, how) = match aov {
        Aov::Albedo => (map(&|p| p), true, "albedo as it is".to_string()),
        Aov::Normal => (map(&|n| n * 0.5 + Vec3::splat(0.5)), false, "normal n as n/2 + 1/2".to_string()),
        Aov::Depth => {
            let hits = || data.pixels.iter().map(|p| finite(p.x)).filter(|&d| d > 0.0);
            let (near, far) = (hits().fold(f32::MAX, f32::min), hits().fold(0.0f32, f32::max));
            let span = (far - near).max(1e-6);
            let grey = |d: f32| if d > 0.0 { 0.1 + 0.9 * ((far - d) / span).clamp(0.0, 1.0) } else { 0.0 };
            let how = format!(
                "depth from {near:.4} (white) to {far:.4} (dark grey), the frame's nearest and farthest hits; black: no hit"
            );
            (map(&|d| Vec3::splat(grey(finite(d.x)))), false, how)
        }
        Aov::Position => {
            let depth = find(Aov::Depth).map(|d| d.to_film());
            let (lo, hi) = bounds.unwrap_or((Vec3::ZERO, Vec3::ONE));
            let size = (hi - lo).max(Vec3::splat(1e-6));
            let pixels = data
                .pixels
                .iter()
                .enumerate()
                .map(|(i, &p)| {
                    let hit = depth.as_ref().is_none_or(|d| d.pixels[i].x > 0.0);
                    if hit && p.is_finite() { ((p - lo) / size).clamp(Vec3::ZERO, Vec3::ONE) } else { Vec3::ZERO }
                })
                .collect();
            let how = format!(
                "position across the scene's bounds [{:.3}, {:.3}] x [{:.3}, {:.3}] x [{:.3}, {:.3}] as RGB; black: no hit",
                lo.x, hi.x, lo.y, hi.y, lo.z, hi.z
            );
            (Film { width: data.width, height: data.height, pixels }, false, how)
        }
        Aov::Variance => {
            let sigma = |v: Vec3| finite(((v.x + v.y + v.z) / 3.0).max(0.0).sqrt());
            let mut nonzero: Vec<f32> = data.pixels.iter().map(|&v| sigma(v)).filter(|&x| x > 0.0).collect();
            let top = if nonzero.is_empty() {
                0.0
            } else {
                let k = ((nonzero.len() - 1) as f64 * 0.99) as usize;
                *nonzero.select_nth_unstable_by(k, f32::total_cmp).1
            };
            let scale = if top > 0.0 { 1.0 / top } else { 0.0 };
            let heat = |t: f32| Vec3::new(3.0 * t, 3.0 * t - 1.0, 3.0 * t - 2.0).clamp(Vec3::ZERO, Vec3::ONE);
            let how =
                format!("standard error of the mean, black-red-yellow-white up to {top:.4} (the 99th percentile)");
            (map(&|v| heat(sigma(v) * scale)), false, how)
        }
    };
    Some((data, display, srgb, how))
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
