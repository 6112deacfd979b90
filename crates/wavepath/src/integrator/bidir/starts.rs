//! The starts of path+light's light subpaths, a group of paths at a time: every path of the
//! group draws its numbers together ([`rng8`]'s lane forms, the same bits as each path's own
//! stream), then the group takes its points and directions on the emissive triangles in
//! lanes. One path at a time, the starts were half the light side's time outside the BVH
//! (docs/decisions.md, "path+light: the light side's cost per vertex").
//! Each lane computes exactly what [`Bidir::start_light_path`] computes, operation for
//! operation, so the subpaths are the same bits either way (tested).

#![allow(clippy::needless_range_loop)]

use super::walk::PathState;
use super::{Bidir, LIGHT_STREAMS};
use crate::integrator::lane_width::LaneKernel;
use crate::lights::emission::Emission;
use crate::lights::{EmissiveTriangles, SampledLight};
use crate::sampling::rng8::{self, Hasher};
use crate::sampling::warp::{self, Frame};
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};
use std::ops::Range;

/// The starts of light subpaths `paths` of iteration `sample`, pushed to `out` as (state,
/// path, first vertex a delta vertex) in path order; those that emit nothing are left out.
pub struct Starts<'b, 't, 'a> {
    pub b: &'b Bidir<'t, 'a>,
    pub paths: Range<usize>,
    pub sample: u32,
    pub out: &'b mut Vec<(PathState, u32, bool)>,
}

impl LaneKernel for Starts<'_, '_, '_> {
    #[inline(always)]
    fn run<H: Hasher, const L: usize>(self, h: H) {
        let Starts { b, paths, sample, out } = self;
        let streams = &b.transport.streams;
        let single = b.emitters.single();
        // One light to choose, and it is the emissive triangles: the group's emission in
        // lanes. Otherwise (several emissive lights) each path's light first, one at a time.
        let lights = &b.transport.lights.set.lights;
        let triangles = match lights.first() {
            Some(SampledLight::Emissive(e)) if single => Some(e),
            _ => None,
        };
        let mut first = paths.start;
        while first < paths.end {
            let n = (paths.end - first).min(L);
            // Lanes past the last path repeat it: a group's streams are all of one pattern.
            let mut keys = [0u64; L];
            for j in 0..L {
                keys[j] = streams.path_key((first + j.min(n - 1)) as u32, sample);
            }
            let rng = rng8::vertex_lanes(h, streams.pattern, &keys, &[LIGHT_STREAMS + 1; L]);
            let choice = if single { [0.0; L] } else { rng8::next_f32_lanes(h, &rng, 0) };
            let u01 = rng8::next_2d_lanes(h, &rng, 1);
            let u23 = rng8::next_2d_lanes(h, &rng, 2);
            let u4 = rng8::next_f32_lanes(h, &rng, 3);
            match triangles {
                Some(e) => {
                    let (_, pick) = b.emitters.choose(0.0);
                    if pick > 0.0 {
                        emit_lanes::<L>(b, e, pick, n, [u01.0, u01.1, u23.0, u23.1, u4], first, out);
                    }
                }
                None => {
                    for j in 0..n {
                        let u = [u01.0[j], u01.1[j], u23.0[j], u23.1[j], u4[j]];
                        if let Some(state) = b.start_with(choice[j], u) {
                            out.push((state, (first + j) as u32, false));
                        }
                    }
                }
            }
            first += n;
        }
    }
}

/// The first `n` lanes' starts on the emissive triangles `e` (chosen with probability
/// `pick`), from their numbers `u` (as [`SampledLight::emit`] reads them); lane `j` is path
/// `first + j`. The triangle of each lane is looked up one lane at a time, the rest runs in
/// loops over the lanes (selects only, no branches: they vectorise).
#[inline(always)]
fn emit_lanes<const L: usize>(
    b: &Bidir,
    e: &EmissiveTriangles,
    pick: f32,
    n: usize,
    u: [[f32; L]; 5],
    first: usize,
    out: &mut Vec<(PathState, u32, bool)>,
) {
    // Per lane: its triangle, and which side of it emits (a two-sided emitter's side from
    // the first direction number, which is then reused).
    let mut ok = [false; L];
    let mut tri = [0usize; L];
    let (mut a, mut e1, mut e2, mut nrm) = ([Vec3::ZERO; L], [Vec3::ZERO; L], [Vec3::ZERO; L], [Vec3::ZERO; L]);
    let (mut inv_density, mut two_sided, mut du) = ([1.0f32; L], [false; L], [0.0f32; L]);
    for j in 0..n {
        let Some(i) = e.pick(u[4][j]) else { continue };
        let t = e.triangle(i);
        ok[j] = t.valid;
        tri[j] = i;
        (a[j], e1[j], e2[j], inv_density[j], two_sided[j]) = (t.a, t.e1, t.e2, t.inv_density, !t.one_sided);
        let u2 = u[2][j];
        (nrm[j], du[j]) = match t.one_sided {
            true => (t.n, u2),
            false if u2 < 0.5 => (t.n, 2.0 * u2),
            false => (-t.n, 2.0 * u2 - 1.0),
        };
    }
    let (mut pos, mut bary) = ([Vec3::ZERO; L], [(0.0f32, 0.0f32); L]);
    let (mut dir, mut cos) = ([Vec3::ZERO; L], [0.0f32; L]);
    for j in 0..L {
        let (bu, bv) = warp::uniform_triangle(u[0][j], u[1][j]);
        bary[j] = (bu, bv);
        pos[j] = a[j] + bu * e1[j] + bv * e2[j];
        let local = warp::cosine_hemisphere(du[j].min(1.0 - f32::EPSILON), u[3][j]);
        dir[j] = Frame::new(nrm[j]).to_world(local);
        cos[j] = local.z;
    }
    let pos_error = e.point_error();
    for j in 0..n {
        if !(ok[j] && cos[j] > 0.0) {
            continue;
        }
        let le = e.emitted(tri[j], bary[j].0, bary[j].1);
        let pdf_pos = 1.0 / inv_density[j];
        let (mut pdf_dir, mut weight) = (cos[j] * FRAC_1_PI, le * (PI / pdf_pos));
        if two_sided[j] {
            pdf_dir *= 0.5;
            weight *= 2.0;
        }
        let em = Emission {
            pos: pos[j],
            pos_error,
            normal: nrm[j],
            dir: dir[j],
            weight,
            pdf_pos,
            pdf_dir,
            cos: cos[j],
            delta_pos: false,
            delta_dir: false,
            falloff_free: false,
        };
        if !em.usable() {
            continue;
        }
        let state = b.start_from(&em, pick);
        out.push((state, (first + j) as u32, false));
    }
}
