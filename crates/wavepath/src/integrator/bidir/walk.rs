//! Subpaths: a camera or light path's vertices, its throughput, and the three running
//! quantities from which the multiple importance sampling weight of every way of making the
//! full path is computed at a connection or a merge, in constant time.
//!
//! The quantities are those of Georgiev et al. 2012 ("Light transport simulation with
//! vertex connection and merging", its technical report's recursive form): at the vertex
//! `i` of a subpath, `d_vcm`, `d_vc` and `d_vm` hold the sums over the strategies that
//! would have drawn the vertices before `i` from the other side, each divided by this
//! side's densities, so a weight never takes a product of many densities (no overflow to
//! Inf, no 0/0). Densities are squared (the power heuristic). Solid angle converts to area
//! with the geometric normal's cosine everywhere, so both sides compute the same numbers
//! for one path and the weights of its strategies add to one.

use super::{Bidir, IterFactors};
use crate::bsdf::{Kind, Model, to_local};
use crate::geometry::Ray;
use crate::geometry::offset::offset_origin;
use crate::integrator::material::ShadingFrame;
use crate::integrator::{DIM_LOBE, Vertex};
use crate::sampling::Numbers;
use glam::Vec3;

/// The power heuristic's exponent applied to a density ratio.
#[inline(always)]
pub fn mis(x: f32) -> f32 {
    x * x
}

/// Which way a subpath carries its quantity: radiance from the camera, importance from the
/// lights (the adjoint, where shading normals and refraction scale differently).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Camera,
    Light,
}

/// A subpath as it grows.
#[derive(Clone, Copy, Debug)]
pub struct PathState {
    pub ray: Ray,
    pub throughput: Vec3,
    /// Edges so far (the vertex the ray reaches is this many + 1 from the start).
    pub len: u32,
    pub d_vcm: f32,
    pub d_vc: f32,
    pub d_vm: f32,
    /// The part of `d_vc` that only the path tracer's BSDF hits and light tracing make: what
    /// the path-and-light mode weighs the paths they share by (those whose vertex next to the
    /// light is a delta vertex: caustics).
    pub d_pl: f32,
    /// A light path from a light without a surface at a finite distance (directional): its
    /// first segment has no distance to convert by.
    pub infinite_start: bool,
    /// A light path from a CS184 point or spot light (no falloff): its first segment's
    /// throughput takes that segment's squared length.
    pub falloff_free: bool,
    /// The last vertex scattered by a delta lobe (mirror, smooth glass).
    pub after_delta: bool,
}

/// A vertex of a light subpath kept for connections and merges.
#[derive(Clone, Copy, Debug)]
pub struct LightVertex {
    pub v: Vertex,
    pub sh: ShadingFrame,
    /// Unit direction toward the vertex before this one (where the light came from).
    pub wo: Vec3,
    pub throughput: Vec3,
    /// Edges from the light.
    pub len: u32,
    pub d_vcm: f32,
    pub d_vc: f32,
    pub d_vm: f32,
    pub d_pl: f32,
}

impl LightVertex {
    /// (d_vcm, d_vc, d_vm), as the weights read them.
    #[inline]
    pub fn quantities(&self) -> [f32; 3] {
        [self.d_vcm, self.d_vc, self.d_vm]
    }

    /// The cosine at this vertex of a connection leaving along `w`, as the adjoint sees it:
    /// Veach's shading-normal correction |wo.ns| |w.ng| / |wo.ng| in place of |w.ns|, so that
    /// light tracing through interpolated normals agrees with the path tracer.
    #[inline]
    pub fn adjoint_cos(&self, w: Vec3) -> f32 {
        adjoint_cos(&self.v, self.wo, w)
    }
}

#[inline]
pub fn adjoint_cos(v: &Vertex, wo: Vec3, w: Vec3) -> f32 {
    let c = wo.dot(v.ns).abs() * w.dot(v.ng).abs() / wo.dot(v.ng).abs();
    if c.is_finite() { c } else { 0.0 }
}

/// A BSDF seen from both ends of one direction `w` (world) at a vertex: its value, the
/// density of sampling `w` from the path's incoming direction, and the reverse.
#[derive(Clone, Copy, Debug)]
pub struct Evaluated {
    pub f: Vec3,
    pub pdf_fwd: f32,
    pub pdf_rev: f32,
    /// |cos| of `w` about the shading normal.
    pub cos_shading: f32,
}

#[inline]
pub fn evaluate(sh: &ShadingFrame, w: Vec3) -> Evaluated {
    let local = to_local(&sh.frame, w);
    let (f, pdf_fwd) = sh.model.eval_pdf(sh.wo, local);
    let pdf_rev = sh.model.pdf(local, sh.wo);
    Evaluated { f, pdf_fwd, pdf_rev, cos_shading: local.z.abs() }
}

impl PathState {
    /// (d_vcm, d_vc, d_vm), as the weights read them.
    #[inline]
    pub fn quantities(&self) -> [f32; 3] {
        [self.d_vcm, self.d_vc, self.d_vm]
    }

    /// Accounts for the segment just traced to `v` (at distance `t`): the densities of the
    /// vertex it reached convert from solid angle to area there.
    #[inline]
    pub fn arrive(&mut self, v: &Vertex, t: f32) {
        self.arrive_at(self.ray.dir.dot(v.ng).abs(), t);
    }

    /// [`arrive`](Self::arrive) at a vertex whose geometric normal is at `cos` to the
    /// segment.
    #[inline]
    pub fn arrive_at(&mut self, cos: f32, t: f32) {
        if self.len > 0 || !self.infinite_start {
            self.d_vcm *= mis(t * t);
        }
        let inv = 1.0 / mis(cos);
        self.d_vcm *= inv;
        self.d_vc *= inv;
        self.d_vm *= inv;
        self.d_pl *= inv;
        if self.len == 0 && self.falloff_free {
            self.throughput *= t * t;
        }
        self.len += 1;
        if !(self.d_vcm.is_finite() && self.d_vc.is_finite() && self.d_vm.is_finite()) {
            // A grazing arrival (cos ~ 0) makes the other side's strategies certain: this
            // side's weight goes to zero rather than to NaN.
            self.d_vcm = f32::MAX;
            self.d_vc = if self.d_vc == 0.0 { 0.0 } else { f32::MAX };
            self.d_vm = if self.d_vm == 0.0 { 0.0 } else { f32::MAX };
            if !self.d_pl.is_finite() {
                self.d_pl = f32::MAX;
            }
        }
    }
}

impl PathState {
    /// Accounts for the direction the subpath leaves its vertex by: `cos_out` its |cos| to
    /// the geometric normal, `pdf` its density (solid angle; a delta lobe's probability),
    /// `pdf_rev` the density of the opposite sampling (from the leaving direction back
    /// along the arriving one).
    #[inline]
    pub fn leave(&mut self, cos_out: f32, pdf: f32, pdf_rev: f32, delta: bool, f: &IterFactors) {
        if delta {
            // A delta vertex: neither side can join or merge here, its densities cancel.
            self.d_vcm = 0.0;
            self.d_vc *= mis(cos_out);
            self.d_vm *= mis(cos_out);
            self.d_pl *= mis(cos_out);
        } else {
            let r = mis(cos_out / pdf);
            // Only the first vertex's own term (light tracing on the camera's side, light
            // sampling on the light's) is one of the path-and-light strategies.
            let first = if self.len == 1 { self.d_vcm } else { 0.0 };
            self.d_pl = r * (self.d_pl * mis(pdf_rev) + first);
            self.d_vc = r * (self.d_vc * mis(pdf_rev) + self.d_vcm + f.mis_vm);
            self.d_vm = r * (self.d_vm * mis(pdf_rev) + self.d_vcm * f.mis_vc + 1.0);
            self.d_vcm = mis(1.0 / pdf);
        }
    }
}

impl Bidir<'_, '_> {
    /// Samples the direction leaving `v` (shaded as `sh`, reached along `state.ray`) and
    /// updates `state` for the next segment; `false` ends the subpath.
    pub fn scatter(&self, state: &mut PathState, v: &Vertex, sh: &ShadingFrame, rng: impl Numbers, side: Side) -> bool {
        let (a, b) = rng.at(0).next_2d();
        let c = rng.at(DIM_LOBE).next_f32();
        let Some(s) = sh.model.sample(sh.wo, [a, b, c]) else { return false };
        if s.weight == Vec3::ZERO || s.pdf.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return false;
        }
        let wi = sh.frame.to_world(s.wi);
        if !v.consistent(wi) {
            return false;
        }
        let cos_out = wi.dot(v.ng).abs();
        let mut weight = s.weight;
        if side == Side::Light {
            // Veach's correction, and no radiance compression through a refracting surface:
            // importance is not scaled by 1 / eta^2.
            let wo = sh.frame.to_world(sh.wo);
            weight *= adjoint_cos(v, wo, wi) / s.wi.z.abs().max(f32::MIN_POSITIVE);
            if let Model::Dielectric(d) = sh.model
                && s.wi.z * sh.wo.z < 0.0
            {
                weight *= d.eta * d.eta;
            }
        }
        state.after_delta = s.delta || sh.kind == Kind::Delta;
        let pdf_rev = if state.after_delta { 0.0 } else { sh.model.pdf(s.wi, sh.wo) };
        state.leave(cos_out, s.pdf, pdf_rev, state.after_delta, &self.iter);
        state.throughput *= weight;
        if !state.throughput.is_finite() || state.throughput == Vec3::ZERO {
            return false;
        }
        let origin = offset_origin(v.p, v.p_error, v.ng, wi);
        state.ray = Ray { origin, dir: wi, tmin: 0.0, tmax: f32::INFINITY };
        true
    }
}
