//! Shade for the Lambertian hits of a wave, eight paths at a time with AVX2 and sixteen with
//! AVX-512 (the diffuse kind's kernel; [`super::shade`] sorts the paths by kind first). What
//! is per path and irregular (the hit's fields, a textured surface's whole vertex, an
//! environment map's sample) is gathered or computed one lane at a time; the random numbers,
//! surface points, light samples, offsets, shadow-ray setup, MIS weights and the
//! continuation rays run lane-parallel: [`crate::integrator::area`]'s and
//! [`crate::integrator::light_ray`]'s branch-free per-sample functions in fixed loops over the
//! lanes that the compiler vectorises (8 or 16 square roots and divisions per instruction
//! instead of one). The functions are the ones the one-vertex-at-a-time code calls, so the
//! image is the same, bit for bit, as [`super::shade::shade_scalar`]'s.
//!
//! Any light, MIS, one-sided emitters, textures, vertex colours, relief maps, volumes and
//! hemisphere sampling run here.
//!
//! The kernel is compiled with AVX2 and FMA enabled (behind run-time detection; Rust never
//! contracts `a * b + c` into an FMA, so the bits do not change) and everything it calls is
//! `#[inline(always)]`: a helper left out of line would be compiled without AVX2.

// Lane loops run over lane indices by design: each reads and writes several arrays of one
// lane, the shape the compiler vectorises.
#![allow(clippy::needless_range_loop)]

use super::lane_width::{LaneKernel, ShadeWidth};
use super::one_path::{NO_VERTEX, emission_of};
use super::queues::{PathQueue, ShadowQueue, ShadowSlots};
use crate::geometry::offset::offset_origin;
use crate::geometry::{Hit, Ray};
use crate::integrator::area::{AreaLight, ShadingPoint, area_ray, cosine_ray, mis_weighted, triangle_ray};
use crate::integrator::light_ray::{LightPoint, diffuse_light_ray};
use crate::integrator::{DIM_DIRECT, DIM_ROULETTE, Transport, Vertex, orient};
use crate::lights::{EmissiveTriangles, Emitter, SampledLight, Sky};
use crate::sampling::rng8::Hasher;
use crate::sampling::{Frame, Sampler, SamplerKind, rng8, warp};
use crate::scene::surface::{interpolated_normal, sphere_point, triangle_point};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// [`super::shade::shade`] for the Lambertian hits listed in `idx` (paths that hit, whose
/// material is Lambertian), eight or sixteen at a time.
pub fn shade_diffuse(width: ShadeWidth, t: &Transport, q: &mut PathQueue, idx: &[u32], shadow: &mut ShadowQueue) {
    width.dispatch(Diffuse { t, q, idx, shadow })
}

/// [`shade_diffuse`]'s arguments, run at the chosen width.
struct Diffuse<'a, 's> {
    t: &'a Transport<'s>,
    q: &'a mut PathQueue,
    idx: &'a [u32],
    shadow: &'a mut ShadowQueue,
}

impl LaneKernel for Diffuse<'_, '_> {
    #[inline(always)]
    fn run<H: Hasher, const L: usize>(self, h: H) {
        let Diffuse { t, q, idx, shadow } = self;
        if whole_vertices(t) {
            shade_groups::<H, true, L>(h, t, q, idx, shadow)
        } else {
            shade_groups::<H, false, L>(h, t, q, idx, shadow)
        }
    }
}

/// Whether a kernel gathers whole vertices (`Transport::vertex`, one lane at a time): where
/// the surface has more than a position and normals to reconstruct. Elsewhere the kernels
/// reconstruct a group's points in lanes ([`surface_points`]).
#[inline(always)]
pub(super) fn whole_vertices(t: &Transport) -> bool {
    t.materials.textures.any()
        || t.scene.mesh.colors.is_some()
        || t.materials.layers.any_relief
        || (t.rules.features.non_diffuse && t.materials.layers.volumes)
}

/// The shading points of a group, one array per component.
pub(super) struct Points<const L: usize> {
    pub p: [[f32; L]; 3],
    pub e: [[f32; L]; 3],
    pub ng: [[f32; L]; 3],
    pub ns: [[f32; L]; 3],
    /// The ray hit the front of the surface (`orient`'s third value).
    pub front: [bool; L],
}

impl<const L: usize> Points<L> {
    #[inline(always)]
    pub fn set(&mut self, j: usize, s: &ShadingPoint) {
        for (a, v) in [(&mut self.p, s.p), (&mut self.e, s.p_error), (&mut self.ng, s.ng), (&mut self.ns, s.ns)] {
            a[0][j] = v.x;
            a[1][j] = v.y;
            a[2][j] = v.z;
        }
    }

    #[inline(always)]
    pub fn get(&self, j: usize) -> ShadingPoint {
        ShadingPoint { p: get(&self.p, j), p_error: get(&self.e, j), ng: get(&self.ng, j), ns: get(&self.ns, j) }
    }
}

impl<const L: usize> Default for Points<L> {
    fn default() -> Self {
        let z = [[0.0; L]; 3];
        Points { p: z, e: z, ng: z, ns: z, front: [false; L] }
    }
}

/// What the surface points of a group are reconstructed from: a triangle's corners (and
/// corner normals) and barycentrics, or a sphere and the ray's hit point on it.
pub(super) struct Surfaces<const L: usize> {
    corner: [[[f32; L]; 3]; 3],
    normal: [[[f32; L]; 3]; 3],
    u: [f32; L],
    v: [f32; L],
    center: [[f32; L]; 3],
    radius: [f32; L],
    hit: [[f32; L]; 3],
    dir: [[f32; L]; 3],
    triangle: [bool; L],
}

impl<const L: usize> Default for Surfaces<L> {
    fn default() -> Self {
        let z = [[0.0; L]; 3];
        Surfaces {
            corner: [z; 3],
            normal: [z; 3],
            u: [0.0; L],
            v: [0.0; L],
            center: z,
            radius: [0.0; L],
            hit: z,
            dir: z,
            triangle: [false; L],
        }
    }
}

#[inline(always)]
pub(super) fn put<const L: usize>(a: &mut [[f32; L]; 3], j: usize, v: Vec3) {
    a[0][j] = v.x;
    a[1][j] = v.y;
    a[2][j] = v.z;
}

#[inline(always)]
pub(super) fn get<const L: usize>(a: &[[f32; L]; 3], j: usize) -> Vec3 {
    Vec3::new(a[0][j], a[1][j], a[2][j])
}

impl<const L: usize> Surfaces<L> {
    /// Gathers lane `j`'s hit (prim `prim`, on `ray`); `normals` is the mesh's corner
    /// normals, looked up once per stage rather than once per corner.
    #[inline(always)]
    pub(super) fn set(&mut self, t: &Transport, normals: Option<&[Vec3]>, j: usize, ray: &Ray, hit: &Hit) {
        let mesh = &t.scene.mesh;
        let prim = hit.prim as usize;
        put(&mut self.dir, j, ray.dir);
        self.triangle[j] = prim < mesh.triangles.len();
        if self.triangle[j] {
            let ids = mesh.triangles[prim];
            for (k, &id) in ids.iter().enumerate() {
                put(&mut self.corner[k], j, mesh.positions[id as usize]);
            }
            if let Some(n) = normals {
                for (k, &id) in ids.iter().enumerate() {
                    put(&mut self.normal[k], j, n[id as usize]);
                }
            }
            (self.u[j], self.v[j]) = (hit.u, hit.v);
        } else {
            let s = &t.scene.spheres[prim - mesh.triangles.len()];
            put(&mut self.center, j, s.center);
            self.radius[j] = s.radius;
            put(&mut self.hit, j, ray.at(hit.t));
        }
    }

    /// Lane `j`'s shading point: both reconstructions (the same functions as
    /// `Scene::surface_point`), one kept, so all lanes run the same instructions; only the
    /// triangle's when the scene has no spheres (`SPHERES` false).
    #[inline(always)]
    fn point<const NORMALS: bool, const SPHERES: bool>(&self, j: usize) -> (ShadingPoint, bool) {
        let (u, v) = (self.u[j], self.v[j]);
        let c = &self.corner;
        let (tp, te, tn) = triangle_point(get(&c[0], j), get(&c[1], j), get(&c[2], j), u, v);
        let ts = if NORMALS {
            let n = &self.normal;
            interpolated_normal([get(&n[0], j), get(&n[1], j), get(&n[2], j)], u, v, tn)
        } else {
            tn
        };
        let (p, p_error, g, sh) = if SPHERES {
            let (sp, se, sn) = sphere_point(get(&self.center, j), self.radius[j], get(&self.hit, j));
            if self.triangle[j] { (tp, te, tn, ts) } else { (sp, se, sn, sn) }
        } else {
            (tp, te, tn, ts)
        };
        let (ng, ns, front) = orient(g, sh, get(&self.dir, j));
        (ShadingPoint { p, p_error, ng, ns }, front)
    }
}

/// Reconstructs the shading points of all lanes (lane-parallel).
#[inline(always)]
pub(super) fn surface_points<const L: usize>(s: &Surfaces<L>, normals: bool, spheres: bool, out: &mut Points<L>) {
    // Plain loops, no closures: a closure may be compiled out of line, without AVX2.
    match (normals, spheres) {
        (true, true) => points_of::<true, true, L>(s, out),
        (true, false) => points_of::<true, false, L>(s, out),
        (false, true) => points_of::<false, true, L>(s, out),
        (false, false) => points_of::<false, false, L>(s, out),
    }
}

#[inline(always)]
fn points_of<const NORMALS: bool, const SPHERES: bool, const L: usize>(s: &Surfaces<L>, out: &mut Points<L>) {
    for j in 0..L {
        let (sp, front) = s.point::<NORMALS, SPHERES>(j);
        out.set(j, &sp);
        out.front[j] = front;
    }
}

/// A group's rays, one array per component.
pub(super) struct Rays<const L: usize> {
    o: [[f32; L]; 3],
    d: [[f32; L]; 3],
    tmax: [f32; L],
    g: [f32; L],
    /// A light sample's whole weight, throughput not applied (one array per component, as
    /// everything a lane loop reads or writes: the compiler leaves a loop over arrays of
    /// structures scalar).
    w: [[f32; L]; 3],
    pub valid: [bool; L],
}

impl<const L: usize> Default for Rays<L> {
    fn default() -> Self {
        let z = [[0.0; L]; 3];
        Rays { o: z, d: z, tmax: [0.0; L], g: [0.0; L], w: z, valid: [false; L] }
    }
}

impl<const L: usize> Rays<L> {
    #[inline(always)]
    pub fn set(&mut self, j: usize, r: &Ray) {
        for (a, v) in [(&mut self.o, r.origin), (&mut self.d, r.dir)] {
            a[0][j] = v.x;
            a[1][j] = v.y;
            a[2][j] = v.z;
        }
        self.tmax[j] = r.tmax;
    }

    #[inline(always)]
    pub fn set_weight(&mut self, j: usize, w: Vec3) {
        put(&mut self.w, j, w);
    }

    #[inline(always)]
    pub fn weight(&self, j: usize) -> Vec3 {
        get(&self.w, j)
    }

    #[inline(always)]
    pub fn ray(&self, j: usize) -> Ray {
        Ray { origin: get(&self.o, j), dir: get(&self.d, j), tmin: 0.0, tmax: self.tmax[j] }
    }
}

/// `u` where `used`, else 0.5 (a lane whose sample is not taken computes on a harmless value).
#[inline(always)]
fn unused_half<const L: usize>(u: [f32; L], used: &[bool; L]) -> [f32; L] {
    let mut out = [0.5; L];
    for j in 0..L {
        if used[j] {
            out[j] = u[j];
        }
    }
    out
}

/// The shadow rays toward light `l` of all lanes (lane-parallel).
#[inline(always)]
fn area_rays<const L: usize>(pts: &Points<L>, l: &AreaLight, ua: &[f32; L], ub: &[f32; L], out: &mut Rays<L>) {
    for j in 0..L {
        let r = area_ray(&pts.get(j), l, ua[j], ub[j]);
        out.set(j, &r.ray);
        out.g[j] = r.g;
        out.valid[j] = r.valid;
    }
}

/// The continuation rays of all lanes (lane-parallel).
#[inline(always)]
fn cosine_rays<const L: usize>(pts: &Points<L>, ua: &[f32; L], ub: &[f32; L], out: &mut Rays<L>) {
    for j in 0..L {
        let r = cosine_ray(&pts.get(j), ua[j], ub[j]);
        out.set(j, &r);
    }
}

/// What a group's direct-light functions read (light samples of every kind, hemisphere
/// probes): the transport, the paths, and the group's vertices, shading points and streams.
#[derive(Clone, Copy)]
struct GroupLight<'a, 's, H, const L: usize> {
    h: H,
    t: &'a Transport<'s>,
    q: &'a PathQueue,
    g: &'a Group<L>,
    pts: &'a Points<L>,
    rng: &'a [Sampler; L],
}

/// The samples of emissive-triangle light `li` (`e`) of a group, from dimension `dim` on: the
/// triangle and its point picked one lane at a time, the rest lane-parallel
/// ([`triangle_ray`]); pushed path-major as the area lights' are.
#[inline(always)]
fn emissive_rays<H: Hasher, const L: usize>(
    gl: GroupLight<'_, '_, H, L>,
    e: &EmissiveTriangles,
    li: usize,
    mut dim: u32,
    pending: &mut Vec<Rays<L>>,
    shadow: &mut ShadowQueue,
) {
    let GroupLight { h, t, q, g, pts, rng } = gl;
    let ns = t.lights.set.samples_for(li, t.rules.light_samples);
    let margin = t.lights.shadow_margins[li];
    let mut inv = [[0.0; L]; 3];
    for j in 0..L {
        put(&mut inv, j, g.vertex[j].albedo * FRAC_1_PI / ns as f32);
    }
    if pending.len() < ns as usize {
        pending.resize_with(ns as usize, Rays::default);
    }
    for p in pending.iter_mut().take(ns as usize) {
        let (ua, ub) = rng8::next_2d_lanes(h, rng, dim);
        let uc = rng8::next_f32_lanes(h, rng, dim + 1);
        dim += 2;
        // The picks first (independent searches), then each picked triangle's fields into
        // lanes, then the points of all lanes at once: picking, reading and sampling one lane
        // at a time made each lane wait on its own chain of loads.
        let mut picked = [usize::MAX; L];
        for j in 0..g.n {
            if g.direct[j] {
                picked[j] = e.pick(uc[j]).unwrap_or(usize::MAX);
            }
        }
        let mut tri = Emitters::<L>::default();
        let mut corners = [[[0.0; L]; 3]; 3];
        for j in 0..g.n {
            if picked[j] != usize::MAX {
                let t = e.triangle(picked[j]);
                tri.set(j, t);
                put(&mut corners[0], j, t.a);
                put(&mut corners[1], j, t.e1);
                put(&mut corners[2], j, t.e2);
            }
        }
        let mut point = [[0.0; L]; 3];
        let (mut bu, mut bv) = ([0.0; L], [0.0; L]);
        for j in 0..L {
            (bu[j], bv[j]) = warp::uniform_triangle(ua[j], ub[j]);
            let [a, e1, e2] = [get(&corners[0], j), get(&corners[1], j), get(&corners[2], j)];
            put(&mut point, j, Emitter::point_at(a, e1, e2, bu[j], bv[j]));
        }
        let mut le = [[0.0; L]; 3];
        for j in 0..g.n {
            if picked[j] != usize::MAX {
                put(&mut le, j, e.emitted(picked[j], bu[j], bv[j]));
            }
        }
        // Into a local first: a loop writing through the queue's buffer is left scalar (its
        // stores might alias what it reads, for all the compiler knows).
        let mut out = Rays::<L>::default();
        for j in 0..L {
            let r =
                triangle_ray(&pts.get(j), &tri.get(j), get(&point, j), get(&le, j), get(&inv, j), margin, ns, g.mis[j]);
            out.set(j, &r.ray);
            out.set_weight(j, r.weight);
            out.valid[j] = r.valid;
        }
        *p = out;
    }
    push_samples(q, g, &pending[..ns as usize], true, shadow);
}

/// What [`triangle_ray`] reads of the emissive triangles a group's samples picked, one array
/// per component (a lane that picked none keeps an invalid one).
pub(super) struct Emitters<const L: usize> {
    n: [[f32; L]; 3],
    inv_density: [f32; L],
    one_sided: [bool; L],
    valid: [bool; L],
}

impl<const L: usize> Default for Emitters<L> {
    fn default() -> Self {
        Emitters { n: [[0.0; L]; 3], inv_density: [0.0; L], one_sided: [false; L], valid: [false; L] }
    }
}

impl<const L: usize> Emitters<L> {
    #[inline(always)]
    pub fn set(&mut self, j: usize, e: &Emitter) {
        put(&mut self.n, j, e.n);
        self.inv_density[j] = e.inv_density;
        self.one_sided[j] = e.one_sided;
        self.valid[j] = e.valid;
    }

    /// Lane `j`'s triangle as far as a sample's direction and density go (no corners).
    #[inline(always)]
    pub fn get(&self, j: usize) -> Emitter {
        Emitter {
            a: Vec3::ZERO,
            e1: Vec3::ZERO,
            e2: Vec3::ZERO,
            n: get(&self.n, j),
            valid: self.valid[j],
            inv_density: self.inv_density[j],
            one_sided: self.one_sided[j],
        }
    }
}

/// A group's samples of one light ([`LightPoint`]), one array per component.
#[derive(Clone, Copy)]
pub(super) struct LightPoints<const L: usize> {
    wi: [[f32; L]; 3],
    weight: [[f32; L]; 3],
    pdf: [f32; L],
    target: [[f32; L]; 3],
    finite: [bool; L],
    valid: [bool; L],
}

impl<const L: usize> Default for LightPoints<L> {
    fn default() -> Self {
        let z = [[0.0; L]; 3];
        LightPoints { wi: z, weight: z, pdf: [0.0; L], target: z, finite: [false; L], valid: [false; L] }
    }
}

impl<const L: usize> LightPoints<L> {
    #[inline(always)]
    pub fn set(&mut self, j: usize, l: &LightPoint) {
        put(&mut self.wi, j, l.wi);
        put(&mut self.weight, j, l.weight);
        self.pdf[j] = l.pdf;
        put(&mut self.target, j, l.target);
        self.finite[j] = l.finite;
        self.valid[j] = l.valid;
    }

    #[inline(always)]
    pub fn get(&self, j: usize) -> LightPoint {
        LightPoint {
            wi: get(&self.wi, j),
            weight: get(&self.weight, j),
            pdf: self.pdf[j],
            target: get(&self.target, j),
            finite: self.finite[j],
            valid: self.valid[j],
        }
    }

    /// The samples of the light from infinity without a map for every lane in `take` about
    /// the normals `n`, from the numbers `(ua, ub)`: all lanes at once
    /// ([`Sky::sample_cosine`]); the density is the one MIS reads.
    #[inline(always)]
    pub fn sky(inf: Sky, n: &[[f32; L]; 3], ua: &[f32; L], ub: &[f32; L], take: &[bool; L]) -> Self {
        let mut out = LightPoints::default();
        for j in 0..L {
            let n = get(n, j);
            let (wi, weight, valid) = inf.sample_cosine(n, [ua[j], ub[j]]);
            let pdf = inf.pdf_with(n, wi, 0.0, false);
            out.set(j, &LightPoint { wi, weight, pdf, target: Vec3::ZERO, finite: false, valid: valid & take[j] });
        }
        out
    }
}

impl<const L: usize> LightPoints<L> {
    /// The samples of a point, spot or directional light (`SampledLight::sample`, and
    /// `sample_pdf`'s infinite density where `mis`) at the points `p` of every lane in `take`:
    /// all lanes at once, the same operations lane by lane (`try_normalize` spelled out; a
    /// spot's `powf` one lane at a time); `None` for any other light.
    #[inline(always)]
    pub fn delta(light: &SampledLight, p: &[[f32; L]; 3], mis: &[bool; L], take: &[bool; L]) -> Option<Self> {
        let (position, intensity, spot) = match *light {
            SampledLight::Point { position, intensity } => (position, intensity, None),
            SampledLight::Spot { position, axis, cos_cutoff, exponent, intensity } => {
                (position, intensity, Some((axis, cos_cutoff, exponent)))
            }
            SampledLight::Directional { to_light, radiance } => {
                let mut out = LightPoints::default();
                for j in 0..L {
                    let pdf = if mis[j] { f32::INFINITY } else { 0.0 };
                    let l = LightPoint {
                        wi: to_light,
                        weight: radiance,
                        pdf,
                        target: Vec3::ZERO,
                        finite: false,
                        valid: take[j],
                    };
                    out.set(j, &l);
                }
                return Some(out);
            }
            _ => return None,
        };
        let mut out = LightPoints::default();
        let mut cos = [0.0f32; L];
        for j in 0..L {
            let d = position - get(p, j);
            let rcp = d.length_recip();
            let wi = d * rcp;
            let mut valid = take[j] & rcp.is_finite() & (rcp > 0.0);
            if let Some((axis, cos_cutoff, _)) = spot {
                cos[j] = (-wi).dot(axis);
                // As `sample`'s rejection (`c < cos_cutoff`), NaN included.
                let outside = cos[j] < cos_cutoff;
                valid &= !outside;
            }
            let pdf = if mis[j] { f32::INFINITY } else { 0.0 };
            out.set(j, &LightPoint { wi, weight: intensity, pdf, target: position, finite: true, valid });
        }
        if let Some((_, _, exponent)) = spot
            && exponent > 0.0
        {
            for j in 0..L {
                if out.valid[j] {
                    put(&mut out.weight, j, intensity * cos[j].max(0.0).powf(exponent));
                }
            }
        }
        Some(out)
    }
}

/// A light's samples of a group (`samples`, sample-major, each with its whole weight) into the
/// shadow queue path-major, throughput applied: every candidate is stored and the cursor moves
/// past the valid ones only (`check`: and whose ray's direction is [`Vertex::consistent`]).
#[inline(always)]
fn push_samples<const L: usize>(
    q: &PathQueue,
    g: &Group<L>,
    samples: &[Rays<L>],
    check: bool,
    shadow: &mut ShadowQueue,
) {
    let ShadowSlots { ray: rs, weight: ws, owner: os } = shadow.open(g.n * samples.len());
    let mut w = 0;
    for j in 0..g.n {
        if !g.direct[j] {
            continue;
        }
        let (i, tp) = (g.path[j], q.throughput[g.path[j]]);
        let v = &g.vertex[j];
        for p in samples {
            let r = p.ray(j);
            rs[w] = r;
            ws[w] = p.weight(j) * tp;
            os[w] = i as u32;
            w += (p.valid[j] && (!check || v.consistent(r.dir))) as usize;
        }
    }
    shadow.commit(w);
}

/// What a lane's gather leaves for the lane-parallel part.
struct Group<const L: usize> {
    /// Path index of each lane.
    path: [usize; L],
    /// Lanes in use (the first `n`).
    n: usize,
    /// Each lane's vertex; where the gather leaves the whole vertex out (`WHOLE` false) only
    /// its albedo and material: the lane's point is in the group's [`Points`].
    vertex: [Vertex; L],
    /// The lane takes light samples / a continuation ray (as `Transport::direct_rays` and
    /// `Transport::scatter` decide).
    direct: [bool; L],
    cont: [bool; L],
    /// The lane's light samples are weighted by MIS (`Transport::diffuse_mis`).
    mis: [bool; L],
    depth: [u32; L],
}

/// The Lambertian paths `idx`, eight at a time; the random numbers are drawn eight streams
/// at a time (with `h`). `WHOLE`: gather whole vertices (see [`whole_vertices`]).
#[inline(always)]
fn shade_groups<H: Hasher, const WHOLE: bool, const L: usize>(
    h: H,
    t: &Transport,
    q: &mut PathQueue,
    idx: &[u32],
    shadow: &mut ShadowQueue,
) {
    let sees_emission = t.rules.counts_emission();
    let arrivals = t.rules.features.non_diffuse || t.rules.mis;
    let mut pts = Points::<L>::default();
    let mut rays = Rays::<L>::default();
    let mut surf = Surfaces::<L>::default();
    let corner_normals = t.scene.mesh.normals.as_deref();
    let normals = corner_normals.is_some();
    let spheres = !t.scene.spheres.is_empty();
    let mut pending: Vec<Rays<L>> = Vec::new();
    let hashed = t.streams.pattern.kind == SamplerKind::Independent;
    let mut g = Group {
        path: [0; L],
        n: 0,
        vertex: [NO_VERTEX; L],
        direct: [false; L],
        cont: [false; L],
        mis: [false; L],
        depth: [0; L],
    };
    for chunk in idx.chunks(L) {
        let mut keys = [0u64; L];
        g.direct = [false; L];
        g.cont = [false; L];
        g.n = chunk.len();
        // Gather, one path at a time.
        for (j, &pi) in chunk.iter().enumerate() {
            let i = pi as usize;
            g.path[j] = i;
            q.alive[i] = false;
            let depth = q.depth[i];
            g.depth[j] = depth;
            let hit = q.hit[i].expect("the diffuse queue holds hits only");
            let ray = q.ray[i];
            let emission = if WHOLE {
                let v = t.vertex(&ray, &hit);
                if t.rules.features.non_diffuse && t.materials.layers.volumes {
                    q.throughput[i] *= t.materials.layers.absorbed(&v, hit.t);
                }
                g.vertex[j] = v;
                v.emission
            } else {
                let m = t.materials.material_of(hit.prim);
                surf.set(t, corner_normals, j, &ray, &hit);
                g.vertex[j].albedo = t.materials.albedo[m];
                g.vertex[j].material = m as u32;
                emission_of(t, m, &ray, &hit)
            };
            // Most hits find no light: nothing is added (adding the zero cost the camera
            // rays' hits a stalled reload of the emission each).
            if t.rules.features.emission && depth == 0 && sees_emission && emission != Vec3::ZERO {
                q.radiance[i] += emission;
            }
            if arrivals && depth > 0 {
                let found = t.arrival_at_hit(q.bounce[i], &ray, &hit, emission, depth);
                if found != Vec3::ZERO {
                    q.radiance[i] += q.throughput[i] * found;
                }
            }
            if !t.rules.features.direct && !t.rules.features.indirect {
                continue;
            }
            // The lane's stream (`Transport::vertex_sampler`) is hashed for all lanes below.
            keys[j] = q.key[i];
            let albedo = g.vertex[j].albedo;
            g.direct[j] = t.rules.features.direct && t.rules.counts_direct(depth) && albedo * FRAC_1_PI != Vec3::ZERO;
            g.cont[j] = t.rules.features.indirect && t.rules.diffuse_continues(depth) && albedo != Vec3::ZERO;
            g.mis[j] = t.rules.diffuse_mis(depth);
        }
        if !g.direct.iter().chain(&g.cont).any(|&b| b) {
            continue;
        }
        let mut bounces = [0u32; L];
        for j in 0..L {
            bounces[j] = g.depth[j] + 1;
        }
        let mut rng = rng8::vertex_lanes(h, t.streams.pattern, &keys, &bounces);
        if !hashed {
            // Lanes that draw nothing take an active lane's stream, so that `rng8` sees
            // streams of one pattern (Sobol's are drawn for all lanes at once).
            let active = (0..g.n).find(|&j| g.direct[j] || g.cont[j]).unwrap_or(0);
            for j in 0..L {
                if !(j < g.n && (g.direct[j] || g.cont[j])) {
                    rng[j] = rng[active];
                }
            }
        }
        if WHOLE {
            for j in 0..L {
                pts.set(j, &g.vertex[j].shading_point());
            }
        } else {
            // Only into `pts`: what follows reads a lane's point there, and the lanes' vertices
            // (albedo and material only) are not relief-mapped, so `Vertex::consistent` reads
            // no normal of theirs (copying the points back lane by lane was 8% of the stage).
            surface_points(&surf, normals, spheres, &mut pts);
        }
        if t.rules.features.direct && g.direct.iter().any(|&d| d) {
            direct_light(GroupLight { h, t, q: &*q, g: &g, pts: &pts, rng: &rng }, &mut pending, shadow);
        }
        if t.rules.features.indirect && g.cont.iter().any(|&c| c) {
            let (ua, ub) = rng8::next_2d_lanes(h, &rng, 0);
            let (ua, ub) = (unused_half(ua, &g.cont), unused_half(ub, &g.cont));
            let rr = if t.rules.features.roulette { rng8::next_f32_lanes(h, &rng, DIM_ROULETTE) } else { [0.0; L] };
            cosine_rays(&pts, &ua, &ub, &mut rays);
            for j in 0..g.n {
                let r = rays.ray(j);
                if !(g.cont[j] && g.vertex[j].consistent(r.dir)) {
                    continue;
                }
                let depth = g.depth[j];
                let bounce = t.diffuse_bounce(&pts.get(j), &r, depth);
                super::one_path::go_on(t, q, g.path[j], depth, r, g.vertex[j].albedo, bounce, || rr[j]);
            }
        }
    }
}

/// The direct-light rays of a group (as `Transport::direct_rays`, throughput applied), light
/// by light: each light's rays sample-major (lane-parallel), pushed path-major, so the rays
/// of one point sit together in the queue, where the shadow stage traces them as one packet,
/// and each path still adds its own in the order the one-path code makes them.
#[inline(always)]
fn direct_light<H: Hasher, const L: usize>(
    gl: GroupLight<'_, '_, H, L>,
    pending: &mut Vec<Rays<L>>,
    shadow: &mut ShadowQueue,
) {
    let GroupLight { h, t, q, g, pts, rng } = gl;
    if t.rules.hemisphere {
        hemisphere_probes(gl, pending, shadow);
        return;
    }
    let mut dim = DIM_DIRECT;
    for (li, light) in t.lights.set.lights.iter().enumerate() {
        let ns = t.lights.set.samples_for(li, t.rules.light_samples);
        if let SampledLight::Emissive(e) = light {
            emissive_rays(gl, e, li, dim, pending, shadow);
            dim += t.light_dims(li);
            continue;
        }
        let (Some(al), SampledLight::Area { radiance, .. }) = (&t.lights.area_lights[li], light) else {
            light_rays(gl, light, li, dim, pending, shadow);
            dim += t.light_dims(li);
            continue;
        };
        let mut c = [[0.0; L]; 3];
        for j in 0..L {
            put(&mut c, j, g.vertex[j].albedo * FRAC_1_PI / ns as f32 * *radiance);
        }
        if pending.len() < ns as usize {
            pending.resize_with(ns as usize, Rays::default);
        }
        for p in pending.iter_mut().take(ns as usize) {
            let (ua, ub) = rng8::next_2d_lanes(h, rng, dim);
            let (ua, ub) = (unused_half(ua, &g.direct), unused_half(ub, &g.direct));
            dim += 1;
            // Into a local first (see `emissive_rays`).
            let mut out = Rays::<L>::default();
            area_rays(pts, al, &ua, &ub, &mut out);
            for j in 0..L {
                out.set_weight(j, get(&c, j) * mis_weighted(out.g[j], ns, g.mis[j]));
            }
            *p = out;
        }
        push_samples(q, g, &pending[..ns as usize], true, shadow);
    }
}

/// Hemisphere sampling's probes of a group (`Transport::direct_rays` under `-H`): uniform
/// directions weighted by the Lambertian value and cosine, in lanes; the sine and cosine of
/// each probe's azimuth one lane at a time. Pushed path-major.
#[inline(always)]
fn hemisphere_probes<H: Hasher, const L: usize>(
    gl: GroupLight<'_, '_, H, L>,
    pending: &mut Vec<Rays<L>>,
    shadow: &mut ShadowQueue,
) {
    let GroupLight { h, t, q, g, pts, rng } = gl;
    let n = t.rules.direct_per_vertex as usize;
    let mut scale = [[0.0; L]; 3];
    for j in 0..L {
        put(&mut scale, j, g.vertex[j].albedo * FRAC_1_PI / (warp::UNIFORM_HEMISPHERE_PDF * n as f32));
    }
    if pending.len() < n {
        pending.resize_with(n, Rays::default);
    }
    for (k, p) in pending.iter_mut().take(n).enumerate() {
        let (z, b) = rng8::next_2d_lanes(h, rng, DIM_DIRECT + k as u32);
        let (mut sin, mut cos) = ([0.0f32; L], [1.0f32; L]);
        for j in 0..g.n {
            if g.direct[j] {
                (sin[j], cos[j]) = (std::f32::consts::TAU * b[j]).sin_cos();
            }
        }
        let z = unused_half(z, &g.direct);
        // Into a local first (see `emissive_rays`).
        let mut out = Rays::<L>::default();
        for j in 0..L {
            let s = pts.get(j);
            let local = warp::uniform_hemisphere_at(z[j], (sin[j], cos[j]));
            let wi = Frame::new(s.ns).to_world(local);
            let origin = offset_origin(s.p, s.p_error, s.ng, wi);
            out.set(j, &Ray { origin, dir: wi, tmin: 0.0, tmax: f32::INFINITY });
            out.set_weight(j, get(&scale, j) * local.z);
            out.valid[j] = g.direct[j];
        }
        *p = out;
    }
    // `check`: a probe below the geometric surface (a relief map's normal) is dropped.
    push_samples(q, g, &pending[..n], true, shadow);
}

/// The samples of light `li` (`light`: the light from infinity, point, spot and directional
/// lights, an area light under the course's pdf) of a group, from dimension `dim` on: the
/// light from infinity without a map and the delta lights sampled in all lanes at once, any
/// other light one lane at a time (`SampledLight::sample_pdf`: the map's table, a
/// normalisation); then the MIS weights and shadow rays of all lanes ([`diffuse_light_ray`]).
/// Pushed path-major.
#[inline(always)]
fn light_rays<H: Hasher, const L: usize>(
    gl: GroupLight<'_, '_, H, L>,
    light: &SampledLight,
    li: usize,
    mut dim: u32,
    pending: &mut Vec<Rays<L>>,
    shadow: &mut ShadowQueue,
) {
    let GroupLight { h, t, q, g, pts, rng } = gl;
    let ns = t.lights.set.samples_for(li, t.rules.light_samples);
    let margin = t.lights.shadow_margins[li];
    let sky = match light {
        SampledLight::Infinite(inf) if inf.map.is_none() => Some(inf.sky()),
        _ => None,
    };
    // A delta light's samples are the same for each of its (one) sample and read no numbers.
    let delta = LightPoints::delta(light, &pts.p, &g.mis, &g.direct);
    let mut inv = [[0.0; L]; 3];
    let mut bumped = [false; L];
    for j in 0..L {
        put(&mut inv, j, g.vertex[j].albedo * FRAC_1_PI / ns as f32);
        bumped[j] = g.vertex[j].bumped;
    }
    if pending.len() < ns as usize {
        pending.resize_with(ns as usize, Rays::default);
    }
    for p in pending.iter_mut().take(ns as usize) {
        let (ua, ub) = if delta.is_none() { rng8::next_2d_lanes(h, rng, dim) } else { ([0.5; L], [0.5; L]) };
        dim += 1;
        let ls = match (sky, delta) {
            (_, Some(ls)) => ls,
            (Some(inf), None) => LightPoints::sky(inf, &pts.ns, &ua, &ub, &g.direct),
            (None, None) => {
                let mut ls = LightPoints::<L>::default();
                for j in 0..g.n {
                    if g.direct[j] {
                        let (s, u) = (pts.get(j), [ua[j], ub[j], 0.0]);
                        ls.set(
                            j,
                            &LightPoint::of(if g.mis[j] {
                                light.sample_pdf(s.p, s.ns, u)
                            } else {
                                light.sample(s.p, s.ns, u).map(|l| (l, 0.0))
                            }),
                        );
                    }
                }
                ls
            }
        };
        // Into a local first (see `emissive_rays`).
        let mut out = Rays::<L>::default();
        for j in 0..L {
            let (s, l) = (pts.get(j), ls.get(j));
            // `Vertex::consistent` of the sample's direction.
            let consistent = !bumped[j] | ((l.wi.dot(s.ng) > 0.0) == (l.wi.dot(s.ns) > 0.0));
            let r = diffuse_light_ray(&s, &l, get(&inv, j), margin, ns, g.mis[j], consistent);
            out.set(j, &r.ray);
            out.set_weight(j, r.weight);
            out.valid[j] = r.valid;
        }
        *p = out;
    }
    push_samples(q, g, &pending[..ns as usize], false, shadow);
}
