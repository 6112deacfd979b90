//! Bidirectional transport: paths started at the lights as well as at the camera, joined
//! by every strategy — light tracing (a light vertex seen by the camera), light sampling,
//! connections between vertices of the two subpaths (BDPT), and merging a camera vertex
//! with the light vertices near it (vertex connection and merging, VCM) — each weighted by
//! multiple importance sampling so that a path's weights add to one.
//!
//! This is the reference form, one subpath at a time per thread, rows in parallel, as
//! [`recursive`](super::recursive) is for the path tracer. A render is a series of
//! iterations, one per sample index: first one light subpath per pixel (its vertices kept,
//! its camera hits splatted), then one camera subpath per pixel, which joins the light
//! subpath of the same (pixel, sample) and, for VCM, merges with all of that iteration's
//! light vertices. Splats are gathered per row and added in row order before the camera
//! pass, so the image does not depend on the thread count (nor on the cells it is cut into:
//! a cell traces every light subpath and keeps its own pixels). A pixel's sample is its camera
//! path plus what that iteration's light paths splatted onto it: iterations are
//! independent samples, and the pixel's variance is measured as for the path tracer.

pub mod caustics;
pub mod connect;
pub mod grid;
pub mod importance;
mod starts;
pub mod walk;

use super::lane_width::ShadeWidth;
use super::{Transport, Vertex};
use crate::accel::{Intersector, TraceCounters};
use crate::film::Accumulator;
use crate::geometry::Ray;
use crate::geometry::offset::offset_origin;
use crate::lights::emission::{Emission, SceneSphere};
use crate::lights::{SampledLight, Seen};
use crate::settings::Settings;
use crate::stats::RenderStats;
use connect::Join;
use glam::Vec3;
use grid::HashGrid;
use importance::Importance;
use rayon::prelude::*;
use std::f32::consts::{FRAC_1_PI, PI};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;
use walk::{LightVertex, PathState, Side, mis};

/// First vertex-stream depth of light subpaths: their numbers never meet a camera
/// subpath's (depths 0..max depth), whatever the depth.
const LIGHT_STREAMS: u32 = 1 << 20;
/// Light subpaths per batch of path+light's light pass (a fixed count, so the splats' order,
/// and with it the image, is the same for any thread count).
const LIGHT_CHUNK: usize = 1024;
/// Merge radius of the first iteration, as a fraction of the scene's bounding radius.
const RADIUS_FACTOR: f32 = 0.003;
/// How fast the merge radius shrinks: r_i = r_0 (i + 1)^((alpha - 1) / 2), which makes
/// merging consistent (bias and variance both vanish) for alpha in (0, 1).
const RADIUS_ALPHA: f32 = 0.75;

/// Which strategies run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Light tracing alone: light subpaths seen by the camera, and the emitters the camera
    /// sees directly; no weights.
    Light,
    /// Every connection strategy (BDPT).
    Bdpt,
    /// Connections and merges (VCM).
    Vcm,
    /// The path tracer's strategies (light sampling, BSDF hits) and light tracing, weighted
    /// among themselves: no connections between subpaths, no light vertices kept.
    PathLight,
}

impl Mode {
    /// The mode `--integrator` names, if it is a bidirectional one.
    pub fn of(kind: crate::settings::IntegratorKind) -> Option<Mode> {
        use crate::settings::IntegratorKind as K;
        match kind {
            K::Auto | K::Wavefront | K::Recursive => None,
            K::Light => Some(Mode::Light),
            K::Bdpt => Some(Mode::Bdpt),
            K::Vcm => Some(Mode::Vcm),
            K::PathLight => Some(Mode::PathLight),
        }
    }

    fn light_tracing_only(self) -> bool {
        self == Mode::Light
    }
    /// Camera vertices join light subpaths' vertices (and so those are kept).
    fn connects(self) -> bool {
        matches!(self, Mode::Bdpt | Mode::Vcm)
    }
    fn merges(self) -> bool {
        self == Mode::Vcm
    }
}

/// The multiple importance sampling factors of one iteration (they depend on its radius).
#[derive(Clone, Copy, Debug, Default)]
pub struct IterFactors {
    /// Merging's density over a connection's, squared (0 without merging).
    pub mis_vm: f32,
    /// A connection's density over merging's, squared (0 without merging).
    pub mis_vc: f32,
    /// 1 / (pi r^2 light paths): merging's density estimate.
    pub vm_normalization: f32,
    pub radius: f32,
}

impl IterFactors {
    /// The factors of an iteration whose merge radius is `radius` with `light_paths` light
    /// subpaths; `merges` false: connections alone (BDPT).
    pub fn new(radius: f32, light_paths: f32, merges: bool) -> IterFactors {
        let eta = PI * radius * radius * light_paths;
        IterFactors {
            mis_vm: if merges { mis(eta) } else { 0.0 },
            mis_vc: if merges { mis(1.0 / eta) } else { 0.0 },
            vm_normalization: 1.0 / eta,
            radius,
        }
    }
}

/// The sphere around the scene's bounds (light from a direction starts on its disk).
pub fn scene_sphere(scene: &crate::scene::Scene) -> SceneSphere {
    match scene.bounds() {
        Some((lo, hi)) => SceneSphere { center: 0.5 * (lo + hi), radius: (0.5 * (hi - lo).length()).max(1e-6) },
        None => SceneSphere { center: Vec3::ZERO, radius: 1.0 },
    }
}

/// A choice among the scene's lights: each one's probability and their running sum.
#[derive(Clone, Debug)]
pub struct Picker {
    pick: Vec<f32>,
    cdf: Vec<f32>,
}

impl Picker {
    /// In proportion to `powers` (uniform when none has power).
    fn by_power(powers: &[f32]) -> Picker {
        let total: f32 = powers.iter().sum();
        let n = powers.len().max(1) as f32;
        let pick: Vec<f32> = powers.iter().map(|&p| if total > 0.0 { p / total } else { 1.0 / n }).collect();
        let cdf = pick
            .iter()
            .scan(0.0, |s, &p| {
                *s += p;
                Some(*s)
            })
            .collect();
        Picker { pick, cdf }
    }

    /// No light of `n` is ever chosen.
    fn none(n: usize) -> Picker {
        Picker { pick: vec![0.0; n], cdf: vec![0.0; n] }
    }

    /// Whether there is one light to choose, which every number then chooses.
    fn single(&self) -> bool {
        self.pick.len() == 1
    }

    /// The light `u` chooses: its index and probability (0 when nothing can be chosen).
    #[inline]
    fn choose(&self, u: f32) -> (usize, f32) {
        let x = u * self.cdf.last().copied().unwrap_or(0.0);
        let i = self.cdf.partition_point(|&c| c <= x).min(self.cdf.len().saturating_sub(1));
        (i, self.pick.get(i).copied().unwrap_or(0.0))
    }
}

/// One row's light subpaths (buffers kept from iteration to iteration).
#[derive(Default)]
struct LightRow {
    vertices: Vec<LightVertex>,
    /// `ends[x - 1]..ends[x]`: pixel x's subpath in `vertices` (from 0 for x = 0).
    ends: Vec<u32>,
    /// (pixel, value) of the row's light paths' camera connections.
    splats: Vec<(u32, Vec3)>,
    counts: Counts,
}

/// One row of a batched light pass (path+light): what its light subpaths splatted, as
/// (pixel, value), and what they cost. The paths in flight live in a [`LightBatch`] per
/// worker, not per row: a row's fresh buffers cost the pass a tenth of its time in page
/// faults.
#[derive(Default)]
struct CausticRow {
    splats: Vec<(u32, Vec3)>,
    counts: Counts,
    /// Thread-seconds this row's light subpaths took.
    seconds: f64,
}

/// One iteration's light subpaths, by row, and for merging their vertices in one list.
pub struct LightPaths<'r> {
    rows: &'r [LightRow],
    /// Merging: every vertex's position, its (row, index), and the grid over them.
    positions: Vec<Vec3>,
    index: Vec<(u32, u32)>,
    grid: Option<HashGrid>,
}

impl LightPaths<'_> {
    /// Pixel (x, y)'s light subpath.
    fn of(&self, x: usize, y: usize) -> &[LightVertex] {
        let row = &self.rows[y];
        let start = if x == 0 { 0 } else { row.ends[x - 1] as usize };
        &row.vertices[start..row.ends[x] as usize]
    }

    /// The vertex at position `i` of the merging list.
    fn vertex(&self, i: usize) -> &LightVertex {
        let (r, k) = self.index[i];
        &self.rows[r as usize].vertices[k as usize]
    }
}

/// Everything the strategies read.
pub struct Bidir<'t, 'a> {
    transport: &'t Transport<'a>,
    accel: &'t dyn Intersector,
    mode: Mode,
    camera: Importance,
    sphere: SceneSphere,
    /// Light choice for light samples (by power).
    lights: Picker,
    /// Light choice for light subpaths: by power too, among the emissive triangles alone in
    /// the path-and-light mode (the lights whose caustics the path tracer also finds).
    emitters: Picker,
    /// Most edges a full path may have.
    max_len: u32,
    /// Light subpaths per iteration (one per pixel where camera paths join their own).
    light_paths: f32,
    height: usize,
    iter: IterFactors,
    width: usize,
}

/// Light subpaths per iteration: one per pixel for the modes that join each camera path to
/// the light subpath of its pixel, the settings' share of the pixels otherwise.
fn light_path_count(mode: Mode, settings: &Settings) -> usize {
    let pixels = settings.image.width * settings.image.height;
    if mode.connects() {
        return pixels;
    }
    let per_pixel = settings.sampling.light_paths.unwrap_or(match mode {
        Mode::PathLight => PATH_LIGHT_SHARE,
        _ => 1.0,
    });
    ((pixels as f64 * per_pixel as f64).round() as usize).max(1)
}

/// `path+light`'s light subpaths per pixel and sample: on the harness's `spheres-box` a
/// quarter gives the least error for the time among 1/8, 1/4 and 1/2 (docs/decisions.md,
/// "path+light: light tracing for caustics only").
const PATH_LIGHT_SHARE: f32 = 0.25;

/// Why bidirectional transport cannot render `transport`'s scene under `settings`, in one
/// line; `None` when it can.
pub fn unsupported(transport: &Transport, settings: &Settings) -> Option<String> {
    let name = settings.execution.integrator.name();
    if !transport.camera.pinhole() {
        return Some(format!(
            "{name} connects light paths to a pinhole camera; this camera has a lens or is orthographic (use --integrator path)"
        ));
    }
    if Mode::of(settings.execution.integrator).is_some_and(|m| m.connects())
        && settings.sampling.light_paths.is_some_and(|r| r != 1.0)
    {
        return Some(format!(
            "{name} joins each camera path to the light subpath of its own pixel, one per pixel: --light-paths is for light and path+light"
        ));
    }
    if settings.sampling.adaptive.is_some() {
        return Some(format!(
            "{name} splats light paths onto other pixels, so a pixel's own samples do not measure its error: adaptive sampling (-a) needs --integrator path"
        ));
    }
    if transport.lights.set.lights.iter().any(|l| matches!(l, SampledLight::Infinite(_))) {
        return Some(format!(
            "{name} does not yet start light paths at light from infinity (an environment or hemisphere light); use --integrator path"
        ));
    }
    if transport.materials.layers.volumes {
        return Some(format!("{name} does not yet carry light through absorbing volumes; use --integrator path"));
    }
    if !transport.rules.accumulate {
        return Some(format!(
            "{name} counts every bounce up to the depth; the last bounce alone (-o 0) needs --integrator path"
        ));
    }
    None
}

impl<'t, 'a> Bidir<'t, 'a> {
    fn new(transport: &'t Transport<'a>, accel: &'t dyn Intersector, settings: &Settings, mode: Mode) -> Option<Self> {
        let (w, h) = (settings.image.width, settings.image.height);
        let camera = Importance::new(&transport.camera, w, h)?;
        let sphere = scene_sphere(transport.scene);
        let powers: Vec<f32> = transport.lights.set.lights.iter().map(|l| l.power(&sphere)).collect();
        let lights = Picker::by_power(&powers);
        let emitters =
            if mode == Mode::PathLight { caustics::emitters(&transport.lights.set, &sphere) } else { lights.clone() };
        Some(Bidir {
            transport,
            accel,
            mode,
            camera,
            sphere,
            lights,
            emitters,
            max_len: transport.rules.max_depth + 1,
            light_paths: light_path_count(mode, settings) as f32,
            height: h,
            iter: IterFactors::default(),
            width: w,
        })
    }

    /// The factors of iteration (sample index) `i`.
    fn at_iteration(&mut self, i: u32) {
        let r0 = RADIUS_FACTOR * self.sphere.radius;
        let radius = r0 * ((i + 1) as f32).powf(0.5 * (RADIUS_ALPHA - 1.0));
        self.iter = IterFactors::new(radius, self.light_paths, self.mode.merges());
    }

    /// A light for a light sample chosen with `u`: its index and probability.
    #[inline]
    fn pick_light(&self, u: f32) -> (usize, f32) {
        self.lights.choose(u)
    }

    fn camera_pos(&self) -> Vec3 {
        self.transport.camera.camera.position
    }

    /// Traces light subpath `pixel` (the pixel whose camera path joins it, where they join;
    /// its index among the iteration's otherwise) of iteration `sample`: its stored
    /// vertices go to `out`, its splats (pixel, value) to `splats`.
    fn light_path(
        &self,
        pixel: u32,
        sample: u32,
        out: &mut Vec<LightVertex>,
        splats: &mut Vec<(u32, Vec3)>,
        st: &mut Counts,
    ) {
        let Some(mut state) = self.start_light_path(pixel, sample) else { return };
        let mut first_delta = false;
        let mut joins = Vec::new();
        loop {
            st.light_rays += 1;
            let Some(hit) = self.accel.closest_hit(&state.ray, &mut st.trace) else { break };
            let at = At { pixel, sample, hit };
            let more = self.light_vertex(&mut state, &mut first_delta, at, out, &mut joins);
            for j in joins.drain(..) {
                st.shadow += 1;
                if !self.accel.any_hit(&j.ray, &mut st.trace) {
                    splats.push((j.pixel, j.value));
                }
            }
            if !more {
                break;
            }
        }
    }

    /// path+light's light subpaths `paths` of iteration `sample` as a small wavefront: their
    /// starts drawn `lanes` at a time (one by one without), all
    /// their rays of one bounce traced together through the intersector's batch interface,
    /// the paths whose first hit scatters diffusely (most of them: light tracing draws only
    /// the caustics) ended at their hit's material, before any vertex is made. The same paths,
    /// vertices and splats as [`light_path`](Self::light_path), the splats of a bounce after
    /// those of the one before.
    fn caustic_paths(
        &self,
        paths: std::ops::Range<usize>,
        sample: u32,
        lanes: Option<ShadeWidth>,
        batch: &mut LightBatch,
        splats: &mut Vec<(u32, Vec3)>,
        st: &mut Counts,
    ) {
        batch.clear();
        match lanes {
            Some(width) => width.dispatch(starts::Starts { b: self, paths, sample, out: &mut batch.states }),
            None => {
                for pixel in paths {
                    if let Some(state) = self.start_light_path(pixel as u32, sample) {
                        batch.states.push((state, pixel as u32, false));
                    }
                }
            }
        }
        let materials = &self.transport.materials;
        while !batch.states.is_empty() {
            batch.rays.clear();
            batch.rays.extend(batch.states.iter().map(|(s, _, _)| s.ray));
            batch.hits.resize(batch.rays.len(), None);
            self.accel.closest_hits(&batch.rays, &mut batch.hits, &mut st.trace);
            st.light_rays += batch.rays.len() as u64;
            let mut keep = 0;
            for k in 0..batch.states.len() {
                let Some(hit) = batch.hits[k] else { continue };
                let (mut state, pixel, mut first_delta) = batch.states[k];
                if state.len == 0
                    && materials.models[materials.material_of(hit.prim)].kind() == crate::bsdf::Kind::Diffuse
                {
                    continue;
                }
                let at = At { pixel, sample, hit };
                if self.light_vertex(&mut state, &mut first_delta, at, &mut Vec::new(), &mut batch.joins) {
                    batch.states[keep] = (state, pixel, first_delta);
                    keep += 1;
                }
            }
            batch.states.truncate(keep);
            // The bounce's camera connections, in the order their vertices came.
            if !batch.joins.is_empty() {
                batch.rays.clear();
                batch.rays.extend(batch.joins.iter().map(|j| j.ray));
                batch.occluded.resize(batch.rays.len(), false);
                self.accel.any_hits_packets(&batch.rays, &mut batch.occluded, &mut st.trace);
                st.shadow += batch.joins.len() as u64;
                let free = batch.joins.iter().zip(&batch.occluded).filter(|(_, o)| !**o);
                splats.extend(free.map(|(j, _)| (j.pixel, j.value)));
                batch.joins.clear();
            }
        }
    }

    /// The start of light subpath `pixel` of iteration `sample`: a light chosen by power, a
    /// point and direction on it; `None` where it emits nothing that way.
    fn start_light_path(&self, pixel: u32, sample: u32) -> Option<PathState> {
        let rng = self.transport.streams.sampler(pixel, sample, LIGHT_STREAMS);
        let choice = if self.emitters.single() { 0.0 } else { rng.at(0).next_f32() };
        let (a, b) = rng.at(1).next_2d();
        let (c, d) = rng.at(2).next_2d();
        let e = rng.at(3).next_f32();
        self.start_with(choice, [a, b, c, d, e])
    }

    /// [`start_light_path`](Self::start_light_path) from its numbers: `choice` chooses the
    /// light (unread where there is one to choose), `u` the point and direction on it.
    #[inline]
    fn start_with(&self, choice: f32, u: [f32; 5]) -> Option<PathState> {
        let lights = &self.transport.lights.set.lights;
        if lights.is_empty() {
            return None;
        }
        let (i, pick) = self.emitters.choose(choice);
        if pick <= 0.0 || pick.is_nan() {
            return None;
        }
        let em = lights[i].emit(u, &self.sphere)?;
        Some(self.start_from(&em, pick))
    }

    /// A light subpath leaving its light as `em` says, the light chosen with probability
    /// `pick`: its first ray and its running quantities.
    #[inline]
    fn start_from(&self, em: &Emission, pick: f32) -> PathState {
        let emission_pdf_w = em.pdf_pos * em.pdf_dir * pick;
        let direct_pdf_a = em.pdf_pos * pick;
        let d_vc = if em.delta_pos || em.delta_dir { 0.0 } else { mis(em.cos / emission_pdf_w) };
        let origin = if em.normal == Vec3::ZERO || em.delta_dir {
            em.pos
        } else {
            offset_origin(em.pos, em.pos_error, em.normal, em.dir)
        };
        PathState {
            ray: Ray { origin, dir: em.dir, tmin: 0.0, tmax: f32::INFINITY },
            throughput: em.weight / pick,
            len: 0,
            d_vcm: mis(direct_pdf_a / emission_pdf_w),
            d_vc,
            d_vm: d_vc * self.iter.mis_vc,
            d_pl: d_vc,
            infinite_start: em.delta_dir,
            falloff_free: em.falloff_free,
            after_delta: false,
        }
    }

    /// A light subpath arrives at its hit `at`: the vertex kept (`out`) and joined to the
    /// camera (`joins`, traced by the caller) as the mode asks, then the next direction;
    /// `false` ends the subpath.
    /// `first_delta`: its first vertex scattered by a delta lobe (path+light's caustics).
    fn light_vertex(
        &self,
        state: &mut PathState,
        first_delta: &mut bool,
        at: At,
        out: &mut Vec<LightVertex>,
        joins: &mut Vec<Join>,
    ) -> bool {
        let v = self.transport.vertex(&state.ray, &at.hit);
        state.arrive(&v, at.hit.t);
        if !state.throughput.is_finite() {
            return false;
        }
        let sh = self.transport.shading(&v, state.ray.dir);
        // The path-and-light mode traces caustics: light paths whose first vertex is a
        // delta vertex, joined to the camera at every later vertex that is not one.
        let caustic = state.len >= 2 && *first_delta;
        if sh.kind != crate::bsdf::Kind::Delta && (caustic || self.mode != Mode::PathLight) {
            let lv = LightVertex {
                v,
                sh,
                wo: -state.ray.dir,
                throughput: state.throughput,
                len: state.len,
                d_vcm: state.d_vcm,
                d_vc: state.d_vc,
                d_vm: state.d_vm,
                d_pl: state.d_pl,
            };
            if state.len < self.max_len {
                joins.extend(self.camera_join(&lv));
            }
            if self.mode.connects() {
                out.push(lv);
            }
        }
        if state.len + 2 > self.max_len {
            return false;
        }
        let caustics_only = self.mode == Mode::PathLight && state.len == 1;
        if caustics_only && sh.kind == crate::bsdf::Kind::Diffuse {
            return false;
        }
        let rng = self.transport.streams.sampler(at.pixel, at.sample, LIGHT_STREAMS + state.len);
        if !self.scatter(state, &v, &sh, rng, Side::Light) || (caustics_only && !state.after_delta) {
            return false;
        }
        *first_delta |= state.len == 1 && state.after_delta;
        true
    }

    /// The light a camera subpath's segment `ray` (reaching `hit` at vertex `v`, or nothing)
    /// finds, weighted against the strategies that draw the same light point from the
    /// light's side. As the path tracer counts it: an area light wherever the segment crosses
    /// it (area lights are not geometry), an emissive triangle that is a light where the
    /// segment hits it, and the emission of a surface that is no light (an emissive quad
    /// beside an area light) only after a delta bounce, at full weight.
    fn found_light(&self, state: &PathState, ray: &Ray, hit: Option<(&crate::geometry::Hit, &Vertex)>) -> Vec3 {
        let weight = |direct_pdf_a: f32, emission_pdf_w: f32| match self.mode {
            // Light tracing shares only the paths that reach the light from a delta vertex.
            Mode::PathLight => {
                let pl = if state.after_delta { state.d_pl } else { 0.0 };
                connect::pl_hit_weight(state.d_vcm, pl, direct_pdf_a, emission_pdf_w)
            }
            _ => connect::hit_weight(state.quantities(), direct_pdf_a, emission_pdf_w),
        };
        let seen = match hit {
            Some((h, _)) => Seen::Hit { t: h.t, emitter: None },
            None => Seen::Miss,
        };
        let emission = hit.map_or(Vec3::ZERO, |(_, v)| v.emission);
        let (mut l, mut area_found, mut owned) = (Vec3::ZERO, false, false);
        for (i, light) in self.transport.lights.set.lights.iter().enumerate() {
            // The light sample's choice of this light, and the light subpath's.
            let (pick, emit) = (self.lights.pick[i], self.emitters.pick[i]);
            match light {
                SampledLight::Area { normal, area, .. } => {
                    if let Some((le, _)) = light.radiance_pdf(ray.origin, *normal, ray.dir, seen) {
                        area_found = true;
                        l += le * weight(pick / area, emit / area * -ray.dir.dot(*normal) * FRAC_1_PI);
                    }
                }
                SampledLight::Emissive(e) if emission != Vec3::ZERO => {
                    if let Some((a, w)) = hit.and_then(|(h, _)| e.emission_pdfs(h.prim, -ray.dir)) {
                        owned = true;
                        l += emission * weight(pick * a, emit * w);
                    }
                }
                _ => {}
            }
        }
        if !owned && !area_found && state.after_delta {
            l += emission;
        }
        if l.is_finite() { l } else { Vec3::ZERO }
    }

    /// The camera subpath of (x, y, sample), joined to light: what it adds to the pixel.
    fn camera_path(&self, x: u32, y: u32, sample: u32, light: &LightPaths, st: &mut Counts) -> Vec3 {
        let (w, h) = (self.width, self.height);
        let pixel = y * w as u32 + x;
        let key = self.transport.streams.path_key(pixel, sample);
        // Always jittered over the pixel (the light paths' importance covers the whole
        // pixel), whatever the sample count.
        let ray = self.transport.camera.ray(x, y, w, h, self.transport.streams.pattern.vertex(key, 0), 2);
        let cos = self.camera.cos_of(ray.dir);
        let camera_pdf_w = self.camera.pdf_w(cos);
        let mut state = PathState {
            ray,
            throughput: Vec3::ONE,
            len: 0,
            d_vcm: mis(self.light_paths / camera_pdf_w),
            d_vc: 0.0,
            d_vm: 0.0,
            d_pl: 0.0,
            infinite_start: false,
            falloff_free: false,
            after_delta: false,
        };
        let own = if self.mode.connects() { light.of(x as usize, y as usize) } else { &[] };
        let mut l = Vec3::ZERO;
        loop {
            if state.len == 0 {
                st.camera += 1;
            } else {
                st.extension += 1;
            }
            let Some(hit) = self.accel.closest_hit(&state.ray, &mut st.trace) else {
                if state.len == 0 {
                    l += self.transport.lights.set.background;
                } else if !self.mode.light_tracing_only() {
                    // The segment may cross an area light on its way out.
                    state.len += 1;
                    l += state.throughput * self.found_light(&state, &state.ray, None);
                }
                break;
            };
            let v = self.transport.vertex(&state.ray, &hit);
            let ray = state.ray;
            state.arrive(&v, hit.t);
            if state.len == 1 {
                l += state.throughput * v.emission;
            } else if !self.mode.light_tracing_only() {
                l += state.throughput * self.found_light(&state, &ray, Some((&hit, &v)));
            }
            if self.mode.light_tracing_only() || state.len >= self.max_len {
                break;
            }
            let sh = self.transport.shading(&v, ray.dir);
            let rng = self.transport.streams.sampler(pixel, sample, state.len - 1);
            if sh.kind != crate::bsdf::Kind::Delta {
                if state.len < self.max_len && !self.transport.lights.set.lights.is_empty() {
                    st.shadow += 1;
                    let c = self.connect_to_light(&state, &v, &sh, rng.at(super::DIM_DIRECT), &mut st.trace);
                    l += state.throughput * c;
                }
                for lv in own.iter().filter(|lv| lv.len + state.len < self.max_len) {
                    st.shadow += 1;
                    l += state.throughput * self.connect_vertices(&state, &v, &sh, lv, &mut st.trace);
                }
                if self.mode.merges() {
                    l += state.throughput * self.merge(&state, &v, &sh, light);
                }
            }
            if !self.scatter(&mut state, &v, &sh, rng, Side::Camera) {
                break;
            }
        }
        l
    }
}

/// Where a light subpath's ray landed: the subpath (its index and iteration) and the hit.
#[derive(Clone, Copy)]
struct At {
    pixel: u32,
    sample: u32,
    hit: crate::geometry::Hit,
}

/// The light subpaths of a batched light pass in flight (buffers kept from batch to batch):
/// each one's state, index and whether its first vertex was a delta vertex; their rays and
/// hits of one bounce.
#[derive(Default)]
struct LightBatch {
    states: Vec<(PathState, u32, bool)>,
    rays: Vec<Ray>,
    hits: Vec<Option<crate::geometry::Hit>>,
    /// The bounce's camera connections, and which of them are blocked.
    joins: Vec<Join>,
    occluded: Vec<bool>,
}

impl LightBatch {
    fn clear(&mut self) {
        self.states.clear();
        self.rays.clear();
        self.hits.clear();
        self.joins.clear();
        self.occluded.clear();
    }
}

#[derive(Clone, Copy, Default)]
struct Counts {
    trace: TraceCounters,
    camera: u64,
    extension: u64,
    shadow: u64,
    light_rays: u64,
}

impl Counts {
    fn add(&mut self, o: &Counts) {
        self.trace.add(&o.trace);
        self.camera += o.camera;
        self.extension += o.extension;
        self.shadow += o.shadow;
        self.light_rays += o.light_rays;
    }
}

/// path+light's light side beside the wavefront's camera side: the light subpaths of a run
/// of iterations, their camera connections splatted into one image per iteration.
pub struct LightPass<'t, 'a> {
    bidir: Bidir<'t, 'a>,
    /// Rows of every iteration of a run, iteration-major (kept from run to run).
    rows: Vec<CausticRow>,
    /// Rows per iteration, and light subpaths per iteration.
    per: usize,
    n_light: usize,
    /// The width light subpaths start at (one at a time without).
    lanes: Option<ShadeWidth>,
}

/// What a light pass traced.
#[derive(Clone, Copy, Default)]
pub struct LightPassCounts {
    pub trace: TraceCounters,
    /// Rays from the lights and between light vertices.
    pub light_rays: u64,
    /// Connections to the camera.
    pub shadow: u64,
    /// Thread-seconds the light subpaths took (summed over the rows, as the wavefront's stages).
    pub seconds: f64,
}

impl<'t, 'a> LightPass<'t, 'a> {
    /// The light side of a path+light render of `settings` (whole image), its subpaths
    /// started `lanes` at a time; `None` where the camera cannot be inverted ([`unsupported`]
    /// says why first).
    pub fn new(
        transport: &'t Transport<'a>,
        accel: &'t dyn Intersector,
        settings: &Settings,
        lanes: Option<ShadeWidth>,
    ) -> Option<Self> {
        let bidir = Bidir::new(transport, accel, settings, Mode::PathLight)?;
        let n_light = light_path_count(Mode::PathLight, settings);
        let per = n_light.div_ceil(LIGHT_CHUNK);
        Some(LightPass { bidir, rows: Vec::new(), per, n_light, lanes })
    }

    /// Traces the light subpaths of iterations `first..first + count` (batches of each in
    /// parallel) and writes what they splat into `splats`, one image per iteration: each
    /// image's sums added in batch order, the same bits for any thread count, and the same
    /// light subpaths as the one-path form's. With `kept`, iterations it holds are not traced
    /// again, and those traced are kept there for the next extent of the plan.
    pub fn trace(
        &mut self,
        first: u32,
        count: u32,
        splats: &mut Vec<Vec3>,
        kept: Option<&KeptSplats>,
    ) -> LightPassCounts {
        let (w, h) = (self.bidir.width, self.bidir.height);
        splats.clear();
        splats.resize(count as usize * w * h, Vec3::ZERO);
        let iterations = first..first + count;
        if let Some(kept) = kept
            && kept.add_into(iterations.clone(), splats, w * h)
        {
            return LightPassCounts::default();
        }
        let per = self.per;
        if self.rows.len() < per * count as usize {
            self.rows.resize_with(per * count as usize, CausticRow::default);
        }
        let (b, n_light, lanes) = (&self.bidir, self.n_light, self.lanes);
        let rows = &mut self.rows[..per * count as usize];
        rows.par_iter_mut().enumerate().for_each_init(LightBatch::default, |batch, (k, row)| {
            let (sample, y) = (first + (k / per) as u32, k % per);
            row.splats.clear();
            row.counts = Counts::default();
            let clock = Instant::now();
            let paths = y * LIGHT_CHUNK..((y + 1) * LIGHT_CHUNK).min(n_light);
            b.caustic_paths(paths, sample, lanes, batch, &mut row.splats, &mut row.counts);
            row.seconds = clock.elapsed().as_secs_f64();
        });
        let mut out = LightPassCounts::default();
        for (k, row) in rows.iter().enumerate() {
            let image = &mut splats[(k / per) * w * h..][..w * h];
            for &(p, c) in &row.splats {
                image[p as usize] += c;
            }
            out.trace.add(&row.counts.trace);
            out.light_rays += row.counts.light_rays;
            out.shadow += row.counts.shadow;
            out.seconds += row.seconds;
        }
        if let Some(kept) = kept {
            let lists = rows.chunks(per).map(|its| its.iter().flat_map(|r| r.splats.iter().copied()).collect());
            kept.keep(iterations, lists);
        }
        out
    }
}

/// What the light subpaths of recent iterations splatted, (pixel, value) in the order the
/// images add them, kept by a render plan for its next extents: the viewer's bands of a pass
/// share one light pass instead of each tracing all the image's light subpaths (a cell needs
/// every one). Only iterations from the latest run's first on are kept, so a renderer that
/// moves forward through its samples holds at most one frame's (sparse: only caustics splat).
#[derive(Debug, Default)]
pub struct KeptSplats(std::sync::Mutex<std::collections::BTreeMap<u32, Vec<(u32, Vec3)>>>);

impl KeptSplats {
    /// Adds iterations `its`' splats into their images (`pixels` each, zero before) when every
    /// one is kept; `false` (nothing added) otherwise.
    fn add_into(&self, its: std::ops::Range<u32>, images: &mut [Vec3], pixels: usize) -> bool {
        let kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if !its.clone().all(|i| kept.contains_key(&i)) {
            return false;
        }
        for (k, i) in its.enumerate() {
            let image = &mut images[k * pixels..][..pixels];
            for &(p, c) in &kept[&i] {
                image[p as usize] += c;
            }
        }
        true
    }

    /// Keeps `lists`, the splats of iterations `its`, dropping those of earlier iterations.
    fn keep(&self, its: std::ops::Range<u32>, lists: impl Iterator<Item = Vec<(u32, Vec3)>>) {
        let mut kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        kept.retain(|&i, _| i >= its.start);
        kept.extend(its.zip(lists));
    }
}

/// Renders the samples `settings` asks for with bidirectional transport `mode` into `acc`
/// (the whole image: [`unsupported`] says what it refuses). `None` once `stop` is set
/// (checked between iterations).
pub fn render_bidir_into(
    transport: &Transport,
    settings: &Settings,
    accel: &dyn Intersector,
    mode: Mode,
    progress: &(dyn Fn(u64) + Sync),
    stop: &AtomicBool,
    acc: &mut Accumulator,
) -> anyhow::Result<Option<RenderStats>> {
    if let Some(why) = unsupported(transport, settings) {
        anyhow::bail!(why);
    }
    let start = Instant::now();
    let (w, h) = (settings.image.width, settings.image.height);
    let Some(mut bidir) = Bidir::new(transport, accel, settings, mode) else {
        anyhow::bail!("{}: the camera cannot be inverted", settings.execution.integrator.name());
    };
    let mut counts = Counts::default();
    let (mut light_s, mut camera_s, mut grid_s) = (0.0, 0.0, 0.0);
    let (first, end) = settings.sample_span();
    // A cell (`-p`, a tile of a split, the viewer's band) traces every light subpath, as
    // the whole image does, and keeps what lands in it: its pixels get the same sums, bit
    // for bit, as in a render of the whole image.
    let region = settings.region();
    // Light subpaths in chunks of a row's width (a row of pixels each, where camera paths
    // join the light subpath of their own pixel).
    let n_light = light_path_count(mode, settings);
    let mut rows: Vec<LightRow> = (0..n_light.div_ceil(w)).map(|_| LightRow::default()).collect();
    let mut splat = vec![Vec3::ZERO; w * h];
    for sample in first..end {
        if stop.load(Ordering::Relaxed) {
            return Ok(None);
        }
        bidir.at_iteration(sample);
        let b = &bidir;
        let t0 = Instant::now();
        rows.par_iter_mut().enumerate().for_each(|(y, row)| {
            row.vertices.clear();
            row.ends.clear();
            row.splats.clear();
            row.counts = Counts::default();
            for i in y * w..((y + 1) * w).min(n_light) {
                b.light_path(i as u32, sample, &mut row.vertices, &mut row.splats, &mut row.counts);
                row.ends.push(row.vertices.len() as u32);
            }
        });
        light_s += t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let mut light = LightPaths { rows: &rows, positions: Vec::new(), index: Vec::new(), grid: None };
        for row in &rows {
            counts.add(&row.counts);
        }
        if mode.merges() {
            for (r, row) in rows.iter().enumerate() {
                light.positions.extend(row.vertices.iter().map(|v| v.v.p));
                light.index.extend((0..row.vertices.len() as u32).map(|k| (r as u32, k)));
            }
            light.grid = Some(HashGrid::new(&light.positions, bidir.iter.radius));
        }
        grid_s += t1.elapsed().as_secs_f64();
        // This iteration's splats, added in row order: the same sums for any thread count.
        splat.fill(Vec3::ZERO);
        for row in &rows {
            for &(p, c) in &row.splats {
                splat[p as usize] += c;
            }
        }
        let b = &bidir;
        let t2 = Instant::now();
        let camera_counts: Vec<Counts> = acc
            .pixels
            .par_chunks_mut(w)
            .enumerate()
            .filter(|(y, _)| *y >= region.y && *y < region.y + region.h)
            .map(|(y, row)| {
                let mut st = Counts::default();
                for (x, out) in row.iter_mut().enumerate().skip(region.x).take(region.w) {
                    // One sample of the pixel: its camera path and what this iteration's
                    // light paths splatted onto it (independent across iterations, so the
                    // pixel's sample variance stays the variance of its estimate).
                    let l = b.camera_path(x as u32, y as u32, sample, &light, &mut st);
                    out.add(l + splat[y * w + x]);
                }
                progress(region.w as u64);
                st
            })
            .collect();
        camera_s += t2.elapsed().as_secs_f64();
        for st in &camera_counts {
            counts.add(st);
        }
    }
    let mut stats = RenderStats {
        counters: counts.trace,
        camera_rays: counts.camera,
        extension_rays: counts.extension,
        light_rays: counts.light_rays,
        shadow_rays: counts.shadow,
        ..Default::default()
    };
    stats.stages.light_paths = Some(light_s);
    stats.stages.camera_paths = Some(camera_s);
    if mode.merges() {
        stats.stages.merge_grid = Some(grid_s);
    }
    stats.render_s = start.elapsed().as_secs_f64();
    stats.invalid_samples = acc.invalid_samples_in(settings.region());
    stats.samples_per_pixel = acc.samples_taken_in(settings.region());
    Ok(Some(stats))
}
