//! Shade for the paths whose rays left the scene, eight at a time with AVX2 and sixteen with
//! AVX-512: what a camera ray sees of the environment, and the light from infinity a
//! BSDF-sampled ray finds, weighed by MIS against the infinite light's own samples
//! ([`Transport::arrival`]). The environment map's texel toward each ray is found in lanes
//! and started loading before the hits are shaded ([`look_ahead`]), and read one lane at a
//! time after them (radiance and density side by side: one load); the selection
//! between the cases, the constant sky, the map mixture's density and the power heuristic run in a loop
//! over the lanes that vectorises, through the functions the one-path code calls
//! ([`found_at_infinity`],
//! [`LightSet::background_with`](crate::lights::LightSet::background_with)), so each path
//! gets the same bits as from [`super::one_path::arrive`].
//!
//! An area light can stand in a ray's way to infinity: with one in the scene every escaped
//! path is shaded by the one-path code.

#![allow(clippy::needless_range_loop)]

use super::soa::{get, put};
use super::width::{LaneKernel, ShadeWidth};
use crate::integrator::Transport;
use crate::integrator::light_ray::found_at_infinity;
use crate::integrator::wavefront::one_path;
use crate::integrator::wavefront::queues::PathQueue;
use crate::lights::{LightSet, SampledLight};
use crate::sampling::rng8::Hasher;
use glam::Vec3;

/// Finds the environment map's texel toward each escaped path of `idx` (in lanes) and starts
/// loading it: `texels[k]` is path `idx[k]`'s texel index and the sine of its polar angle.
/// Empty where [`shade_escaped`] reads no texel. Done before the hits are shaded, so that
/// the texels (random reads all over a map of megabytes) arrive while they are: on an
/// environment-lit scan those reads held 46% of the lane kernel's samples, and reading them
/// after the hits took 3-4% off the shade stage.
pub fn look_ahead(width: ShadeWidth, t: &Transport, q: &PathQueue, idx: &[u32], texels: &mut Vec<(usize, f32)>) {
    texels.clear();
    if t.lights.area_arrivals || t.lights.set.infinite.map.is_none() {
        return;
    }
    width.dispatch(LookAhead { t, q, idx, texels })
}

/// [`look_ahead`]'s arguments, run at the chosen width.
struct LookAhead<'a, 's> {
    t: &'a Transport<'s>,
    q: &'a PathQueue,
    idx: &'a [u32],
    texels: &'a mut Vec<(usize, f32)>,
}

impl LaneKernel for LookAhead<'_, '_> {
    #[inline(always)]
    fn run<H: Hasher, const L: usize>(self, _: H) {
        let LookAhead { t, q, idx, texels } = self;
        let Some(m) = t.lights.set.infinite.map.as_deref() else { return };
        for chunk in idx.chunks(L) {
            let mut dir = [[0.0f32; L]; 3];
            for (j, &i) in chunk.iter().enumerate() {
                put(&mut dir, j, q.ray[i as usize].dir);
            }
            let mut index = [0usize; L];
            let mut sin_theta = [0.0f32; L];
            for j in 0..L {
                (index[j], sin_theta[j]) = m.index_of(get(&dir, j));
            }
            for j in 0..chunk.len() {
                m.prefetch(index[j]);
                texels.push((index[j], sin_theta[j]));
            }
        }
    }
}

/// Shades the escaped paths `idx`: `alive` cleared, the environment or the light from
/// infinity added. `texels`: [`look_ahead`]'s.
pub fn shade_escaped(width: ShadeWidth, t: &Transport, q: &mut PathQueue, idx: &[u32], texels: &[(usize, f32)]) {
    if t.lights.area_arrivals {
        for &i in idx {
            one_path::arrive(t, q, i as usize);
        }
        return;
    }
    width.dispatch(Escaped { t, q, idx, texels })
}

/// [`shade_escaped`]'s arguments, run at the chosen width.
struct Escaped<'a, 's> {
    t: &'a Transport<'s>,
    q: &'a mut PathQueue,
    idx: &'a [u32],
    texels: &'a [(usize, f32)],
}

impl LaneKernel for Escaped<'_, '_> {
    #[inline(always)]
    fn run<H: Hasher, const L: usize>(self, _: H) {
        escaped_groups::<L>(self.t, self.q, self.idx, self.texels)
    }
}

#[inline(always)]
fn escaped_groups<const L: usize>(t: &Transport, q: &mut PathQueue, idx: &[u32], texels: &[(usize, f32)]) {
    let sees_emission = t.rules.counts_emission();
    let arrivals = t.rules.features.non_diffuse || t.rules.mis;
    let set = &t.lights.set;
    let map = set.infinite.map.as_deref();
    let has_map = map.is_some();
    // The constants the lane loop reads, copied out (registers, not loads through a
    // reference): the light a BSDF sample finds and how many samples it takes at a vertex
    // (`mis`: there is one), what camera rays see, and light from infinity after delta bounces.
    let (found, ns) = match t.lights.infinite.map(|i| (i, &set.lights[i])) {
        Some((i, SampledLight::Infinite(inf))) => (inf.sky(), set.samples_for(i, t.rules.light_samples) as f32),
        _ => (set.infinite.sky(), 0.0),
    };
    let mis = t.lights.infinite.is_some();
    let (background, sky) = (set.background, set.infinite.sky());
    for (c, chunk) in idx.chunks(L).enumerate() {
        let mut dir = [[0.0f32; L]; 3];
        let mut n = [[0.0f32; L]; 3];
        let mut pdf = [0.0f32; L];
        let mut mapped = [[0.0f32; L]; 3];
        let mut mapped_pdf = [0.0f32; L];
        // The lane sees the environment (a camera ray) / finds light after a bounce / that
        // light counts at its depth.
        let mut camera = [false; L];
        let mut arrives = [false; L];
        let mut counts = [false; L];
        for (j, &pi) in chunk.iter().enumerate() {
            let i = pi as usize;
            q.alive[i] = false;
            let depth = q.depth[i];
            let d = q.ray[i].dir;
            let b = q.bounce[i];
            put(&mut dir, j, d);
            put(&mut n, j, b.n);
            pdf[j] = b.pdf;
            camera[j] = t.rules.features.environment && depth == 0 && sees_emission;
            arrives[j] = arrivals && depth > 0;
            counts[j] = t.rules.accumulate || depth == t.rules.max_depth;
        }
        if !(0..chunk.len()).any(|j| camera[j] || arrives[j]) {
            continue;
        }
        if let Some(m) = map {
            // The texels toward every lane, found (and started loading) ahead, then one read
            // per lane that needs it.
            let texels = &texels[c * L..c * L + chunk.len()];
            for j in 0..chunk.len() {
                let found = arrives[j] && pdf[j] != 0.0 && counts[j];
                if camera[j] || found {
                    let (index, sin_theta) = texels[j];
                    let (l, p) = m.at_index(index, sin_theta);
                    put(&mut mapped, j, l);
                    if found && pdf[j] != f32::INFINITY && mis {
                        mapped_pdf[j] = p;
                    }
                }
            }
        }
        let mut l = [[0.0f32; L]; 3];
        for j in 0..L {
            let (d, m) = (get(&dir, j), get(&mapped, j));
            let weighed = if mis {
                found_at_infinity(found, ns, get(&n, j), pdf[j], d, m, mapped_pdf[j], has_map)
            } else {
                Vec3::ZERO
            };
            // As `Transport::arrival` for a ray that left the scene.
            let arrived = if pdf[j] == 0.0 || !counts[j] {
                Vec3::ZERO
            } else if pdf[j] == f32::INFINITY {
                sky.radiance_with(d, m, has_map)
            } else {
                weighed
            };
            put(&mut l, j, if camera[j] { LightSet::background_with(background, m, has_map) } else { arrived });
        }
        for (j, &pi) in chunk.iter().enumerate() {
            if camera[j] || arrives[j] {
                let i = pi as usize;
                q.radiance[i] += q.throughput[i] * get(&l, j);
            }
        }
    }
}
