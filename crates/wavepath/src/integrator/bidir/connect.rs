//! The strategies that join a camera subpath to light: a light subpath's vertex seen by
//! the camera (light tracing), a camera vertex seen by a light sample, two subpaths'
//! vertices joined by a segment (connection), and a camera vertex gathering the light
//! vertices near it (merging). Each returns its contribution already weighted.

use super::walk::{LightVertex, PathState, evaluate, mis};
use super::{Bidir, IterFactors, Mode};
use crate::accel::TraceCounters;
use crate::geometry::Ray;
use crate::geometry::offset::{offset_origin, shadow_tmax};
use crate::integrator::material::ShadingFrame;
use crate::integrator::{Vertex, light_numbers};
use crate::lights::emission::Illumination;
use crate::sampling::Numbers;
use glam::Vec3;

/// A light vertex seen by the camera: the pixel it lands on, the weighted contribution to
/// that pixel's sum, and the ray from the camera to it, which must be free for it to count.
/// Its rays all start at the camera, so a bounce's joins traced together go in packets.
#[derive(Clone, Copy, Debug)]
pub struct Join {
    pub pixel: u32,
    pub value: Vec3,
    pub ray: Ray,
}

/// Whether the segment from surface point `v` toward `q` (error bound `q_error`) is free.
fn unoccluded(b: &Bidir, v: &Vertex, q: Vec3, q_error: Vec3, counters: &mut TraceCounters) -> bool {
    let origin = offset_origin(v.p, v.p_error, v.ng, q - v.p);
    let Some(dir) = (q - origin).try_normalize() else { return false };
    let tmax = shadow_tmax(origin, q, q_error);
    tmax > 0.0 && !b.accel.any_hit(&Ray { origin, dir, tmin: 0.0, tmax }, counters)
}

impl Bidir<'_, '_> {
    /// Light tracing: the light vertex `lv` seen by the camera, if nothing is in between
    /// (the join's ray, which the caller traces: one at a time, or a bounce's joins as one
    /// batch).
    pub fn camera_join(&self, lv: &LightVertex) -> Option<Join> {
        let pr = self.camera.project(lv.v.p)?;
        let w = pr.to_camera;
        if !lv.v.consistent(w) {
            return None;
        }
        let e = evaluate(&lv.sh, w);
        if e.f == Vec3::ZERO {
            return None;
        }
        let cos_geo = w.dot(lv.v.ng).abs();
        let dist2 = pr.dist * pr.dist;
        let camera_pdf_w = self.camera.pdf_w(pr.cos_camera);
        let camera_pdf_a = camera_pdf_w * cos_geo / dist2;
        let weight = match self.mode {
            Mode::Light => 1.0,
            Mode::PathLight => pl_camera_weight(lv.d_pl, camera_pdf_a, self.light_paths, e.pdf_rev),
            _ => camera_weight(lv.quantities(), camera_pdf_a, self.light_paths, e.pdf_rev, &self.iter),
        };
        // The film's importance per pixel area, W = pdf_w: the contribution is
        // throughput f cos W / dist^2 over the light paths drawn per pixel sample.
        let c = lv.throughput * e.f * (weight * lv.adjoint_cos(w) * camera_pdf_w / (dist2 * self.light_paths));
        if !c.is_finite() || c == Vec3::ZERO {
            return None;
        }
        let target_error = lv.v.p_error;
        let origin = self.camera_pos();
        let dir = (lv.v.p - origin) / pr.dist;
        let tmax = shadow_tmax(origin, lv.v.p, target_error);
        Some(Join { pixel: pr.pixel as u32, value: c, ray: Ray { origin, dir, tmin: 0.0, tmax } })
    }

    /// A light sample of the camera vertex `v` (the next event), weighted against reaching
    /// the light by the BSDF, by light paths and by merging.
    pub fn connect_to_light(
        &self,
        state: &PathState,
        v: &Vertex,
        sh: &ShadingFrame,
        mut rng: impl Numbers,
        counters: &mut TraceCounters,
    ) -> Vec3 {
        let (i, pick) = self.pick_light(rng.next_f32());
        let light = &self.transport.lights.set.lights[i];
        let u = light_numbers(&mut rng, light);
        let Some(il) = light.illuminate(v.p, u, &self.sphere) else { return Vec3::ZERO };
        if !v.consistent(il.wi) {
            return Vec3::ZERO;
        }
        let e = evaluate(sh, il.wi);
        if e.f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let cos_geo = il.wi.dot(v.ng).abs();
        let weight = if self.mode == Mode::PathLight {
            pl_light_sample_weight(&il, pick, e.pdf_fwd)
        } else {
            light_sample_weight(state.quantities(), &il, pick, cos_geo, e.pdf_fwd, e.pdf_rev, &self.iter)
        };
        let c = il.radiance * e.f * (weight * e.cos_shading / (pick * il.direct_pdf_w));
        if !c.is_finite() || c == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let free = match il.target {
            Some(q) => unoccluded(self, v, q, light.point_error(), counters),
            None => {
                let origin = offset_origin(v.p, v.p_error, v.ng, il.wi);
                !self.accel.any_hit(&Ray { origin, dir: il.wi, tmin: 0.0, tmax: f32::INFINITY }, counters)
            }
        };
        if free { c } else { Vec3::ZERO }
    }

    /// The camera vertex `v` joined to the light vertex `lv` by one segment.
    pub fn connect_vertices(
        &self,
        state: &PathState,
        v: &Vertex,
        sh: &ShadingFrame,
        lv: &LightVertex,
        counters: &mut TraceCounters,
    ) -> Vec3 {
        let d = lv.v.p - v.p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        let w = d / dist;
        if !(dist2 > 0.0 && dist2.is_finite() && v.consistent(w) && lv.v.consistent(-w)) {
            return Vec3::ZERO;
        }
        let ec = evaluate(sh, w);
        if ec.f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let el = evaluate(&lv.sh, -w);
        if el.f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let (cos_camera, cos_light) = (w.dot(v.ng).abs(), w.dot(lv.v.ng).abs());
        let camera_pdf_a = ec.pdf_fwd * cos_light / dist2;
        let light_pdf_a = el.pdf_fwd * cos_camera / dist2;
        let weight = connection_weight(
            state.quantities(),
            lv.quantities(),
            camera_pdf_a,
            light_pdf_a,
            ec.pdf_rev,
            el.pdf_rev,
            &self.iter,
        );
        let g = ec.cos_shading * lv.adjoint_cos(-w) / dist2;
        let c = lv.throughput * ec.f * el.f * (weight * g);
        if !c.is_finite() || c == Vec3::ZERO {
            return Vec3::ZERO;
        }
        if unoccluded(self, v, lv.v.p, lv.v.p_error, counters) { c } else { Vec3::ZERO }
    }

    /// Merging: the light vertices within the radius of camera vertex `v`, each weighted
    /// against the connections that make the same path, density-estimated over the disk.
    pub fn merge(&self, state: &PathState, v: &Vertex, sh: &ShadingFrame, light: &super::LightPaths) -> Vec3 {
        let Some(grid) = &light.grid else { return Vec3::ZERO };
        let mut sum = Vec3::ZERO;
        grid.query(v.p, &light.positions, |i| {
            let lv = light.vertex(i);
            if lv.len + state.len > self.max_len || lv.v.ng.dot(v.ng) <= 0.0 {
                return;
            }
            let e = evaluate(sh, lv.wo);
            if e.f == Vec3::ZERO || !v.consistent(lv.wo) {
                return;
            }
            let weight = merge_weight(state.quantities(), lv.quantities(), e.pdf_fwd, e.pdf_rev, &self.iter);
            let c = lv.throughput * e.f * weight;
            if c.is_finite() {
                sum += c;
            }
        });
        sum * self.iter.vm_normalization
    }
}

// The weights, each from the two subpaths' running quantities at the join and the
// densities of the join itself (Georgiev et al. 2012, the technical report's section on
// the recursive form); `cam` and `light` are the subpaths' (d_vcm, d_vc, d_vm). Each is 1 / (sum over the path's strategies of (their density /
// this one's)^2); a strategy's terms are zero where it cannot make the path.

/// A camera subpath (`cam`) whose last segment found a light point drawn (by light sampling and
/// by light paths) with densities `direct_pdf_a` (area) and `emission_pdf_w` (area x
/// solid angle), light choice included.
#[inline]
pub fn hit_weight(cam: [f32; 3], direct_pdf_a: f32, emission_pdf_w: f32) -> f32 {
    let w_camera = mis(direct_pdf_a) * cam[0] + mis(emission_pdf_w) * cam[1];
    1.0 / (1.0 + w_camera)
}

/// A light sample `il` (light chosen with probability `pick`) of the camera vertex whose
/// BSDF draws its direction with density `pdf_fwd` and the path's arriving direction from
/// it with `pdf_rev`; `cos_geo`: |cos| of the direction at the vertex.
#[inline]
pub fn light_sample_weight(
    cam: [f32; 3],
    il: &Illumination,
    pick: f32,
    cos_geo: f32,
    pdf_fwd: f32,
    pdf_rev: f32,
    f: &IterFactors,
) -> f32 {
    let w_light = if il.delta { 0.0 } else { mis(pdf_fwd / (pick * il.direct_pdf_w)) };
    let w_camera = mis(il.emission_pdf_w * cos_geo / (il.direct_pdf_w * il.cos_light))
        * (f.mis_vm + cam[0] + cam[1] * mis(pdf_rev));
    1.0 / (w_light + 1.0 + w_camera)
}

/// A camera vertex (`cam`) joined to a light vertex (`light`): `camera_pdf_a` is the camera
/// vertex's BSDF density of the light vertex (area), `light_pdf_a` the light vertex's of
/// the camera vertex; `camera_pdf_rev`, `light_pdf_rev` each vertex's density (solid
/// angle) of its own subpath's arriving direction, from the joining one.
#[inline]
pub fn connection_weight(
    cam: [f32; 3],
    light: [f32; 3],
    camera_pdf_a: f32,
    light_pdf_a: f32,
    camera_pdf_rev: f32,
    light_pdf_rev: f32,
    f: &IterFactors,
) -> f32 {
    let w_light = mis(camera_pdf_a) * (f.mis_vm + light[0] + light[1] * mis(light_pdf_rev));
    let w_camera = mis(light_pdf_a) * (f.mis_vm + cam[0] + cam[1] * mis(camera_pdf_rev));
    1.0 / (w_light + 1.0 + w_camera)
}

/// Light tracing: a light vertex (`light`) seen by the camera, which draws it with density
/// `camera_pdf_a` (area, per pixel area of the film) among `light_paths` light subpaths;
/// `pdf_rev`: the vertex's density of its arriving direction from the camera's.
#[inline]
pub fn camera_weight(light: [f32; 3], camera_pdf_a: f32, light_paths: f32, pdf_rev: f32, f: &IterFactors) -> f32 {
    let w_light = mis(camera_pdf_a / light_paths) * (f.mis_vm + light[0] + light[1] * mis(pdf_rev));
    1.0 / (w_light + 1.0)
}

/// A camera vertex (`cam`) merged with a light vertex (`light`) on it: the camera vertex's BSDF
/// density of the light's arriving direction `pdf_fwd`, and of its own arriving direction
/// from that one `pdf_rev`.
#[inline]
pub fn merge_weight(cam: [f32; 3], light: [f32; 3], pdf_fwd: f32, pdf_rev: f32, f: &IterFactors) -> f32 {
    let w_light = light[0] * f.mis_vc + light[2] * mis(pdf_fwd);
    let w_camera = cam[0] * f.mis_vc + cam[2] * mis(pdf_rev);
    1.0 / (w_light + 1.0 + w_camera)
}

// The path-and-light mode's weights. Light tracing shares only the caustics seen directly with
// the path tracer's strategies (camera, a diffusely scattering vertex, delta vertices, the
// light), which only BSDF hits also make; every other path is the path tracer's alone.
// `pl`: the subpath's `d_pl`, nonzero only on such a path's prefix.

/// [`hit_weight`] among the path-and-light strategies: light sampling and, on a caustic seen
/// directly, light tracing.
#[inline]
pub fn pl_hit_weight(d_vcm: f32, pl: f32, direct_pdf_a: f32, emission_pdf_w: f32) -> f32 {
    1.0 / (1.0 + mis(direct_pdf_a) * d_vcm + mis(emission_pdf_w) * pl)
}

/// [`light_sample_weight`] among the path-and-light strategies: against BSDF hits alone (a
/// light-sampled path ends in a diffuse vertex, which light tracing does not share).
#[inline]
pub fn pl_light_sample_weight(il: &Illumination, pick: f32, pdf_fwd: f32) -> f32 {
    let w_light = if il.delta { 0.0 } else { mis(pdf_fwd / (pick * il.direct_pdf_w)) };
    1.0 / (w_light + 1.0)
}

/// [`camera_weight`] among the path-and-light strategies: a caustic's light vertex (reached
/// through delta vertices only) against the camera's BSDF hit on the light.
#[inline]
pub fn pl_camera_weight(pl: f32, camera_pdf_a: f32, light_paths: f32, pdf_rev: f32) -> f32 {
    1.0 / (mis(camera_pdf_a / light_paths) * pl * mis(pdf_rev) + 1.0)
}
