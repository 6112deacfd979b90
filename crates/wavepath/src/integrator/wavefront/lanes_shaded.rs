//! Shade for the hits on every material but the Lambertian one (glossy, metallic-roughness,
//! conductors, mirror, glass, the layered glTF model), eight or sixteen paths at a time: each
//! lane arrives one at a time ([`one_path::arrive`]: the vertex, its emission and the light
//! its ray found), the group's random numbers are drawn in lanes, as many dimensions as the
//! group's materials read ([`Transport::shaded_numbers`]), and the vertices leave by model.
//! The numbers are the vertex streams' own ([`Drawn`]), so the rays are those of the
//! one-path kernel, bit for bit.
//!
//! Drawing the numbers was the largest part of shading these kinds one path at a time
//! (Sobol's Owen scrambling and index shuffling, per dimension and per vertex). The models
//! with a branch-free sample (`LaneModel`) then leave their vertices in lanes
//! ([`super::lanes_glossy`]), sorted out of the group by model: those that mix a diffuse lobe
//! with a GGX one (metallic-roughness, specular-glossiness, Phong), the layered glTF model
//! (clearcoat, sheen, transmission) and the rough conductor where their light samples or
//! hemisphere probes are drawn ahead, mirror and glass always (they take no light samples).
//! Vertices whose numbers are not all drawn ahead leave one lane at a time with the one-path
//! code ([`one_path::leave`]).

#![allow(clippy::needless_range_loop)]

use super::Features;
use super::ShadeWidth;
use super::lanes::Rays;
use super::lanes_glossy::{self, ModelGroup};
use super::one_path;
use super::queues::{PathQueue, ShadowQueue};
use crate::bsdf::{Dielectric, Glossy, Kind, Layered, Microfacet, Mirror, Model, Pbr, to_local};
use crate::cpu::{Avx2, Avx512};
use crate::integrator::{DIM_DIRECT, Transport, Vertex};
use crate::sampling::numbers::Drawn;
use crate::sampling::{Frame, Sampler, SamplerKind, rng8};

/// Shades the paths `idx` (hits on non-Lambertian materials), `L` at a time; `table` is
/// scratch for the numbers drawn ahead.
pub fn shade_shaded<F: Features>(
    width: ShadeWidth,
    t: &Transport,
    q: &mut PathQueue,
    idx: &[u32],
    shadow: &mut ShadowQueue,
    table: &mut Vec<[f32; 2]>,
) {
    match width {
        // SAFETY: the tokens prove the CPU has the instruction sets the kernels enable.
        ShadeWidth::Sixteen(avx512) => unsafe { shade_avx512::<F>(avx512, t, q, idx, shadow, table) },
        // SAFETY: as above.
        ShadeWidth::Eight(avx2) => unsafe { shade_avx2::<F>(avx2, t, q, idx, shadow, table) },
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn shade_avx2<F: Features>(
    avx: Avx2,
    t: &Transport,
    q: &mut PathQueue,
    idx: &[u32],
    shadow: &mut ShadowQueue,
    table: &mut Vec<[f32; 2]>,
) {
    shade_groups::<F, 8>(avx, t, q, idx, shadow, table)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
fn shade_avx512<F: Features>(
    avx: Avx512,
    t: &Transport,
    q: &mut PathQueue,
    idx: &[u32],
    shadow: &mut ShadowQueue,
    table: &mut Vec<[f32; 2]>,
) {
    shade_groups::<F, 16>(avx.avx2, t, q, idx, shadow, table)
}

#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn shade_groups<F: Features, const L: usize>(
    avx: Avx2,
    t: &Transport,
    q: &mut PathQueue,
    idx: &[u32],
    shadow: &mut ShadowQueue,
    table: &mut Vec<[f32; 2]>,
) {
    let layout = &t.shaded_numbers;
    let dims = layout.len();
    table.resize(L * dims, [0.0; 2]);
    let hashed = t.streams.pattern.kind == SamplerKind::Independent;
    let glossy_lanes = lanes_glossy::takes(t);
    let mut pbr = ModelGroup::<Pbr, L>::new();
    let mut phong = ModelGroup::<Glossy, L>::new();
    let mut conductor = ModelGroup::<Microfacet, L>::new();
    let mut mirror = ModelGroup::<Mirror, L>::new();
    let mut glass = ModelGroup::<Dielectric, L>::new();
    let mut layered = ModelGroup::<Layered, L>::new();
    let mut pending: Vec<Rays<L>> = Vec::new();
    for chunk in idx.chunks(L) {
        let mut vertex: [Option<Vertex>; L] = [None; L];
        let mut vertex_input = [0u64; L];
        let mut patterned = [Sampler::default(); L];
        let mut first = None;
        // Whether a lane reads light samples (a glossy vertex whose direct light counts):
        // else only the continuation, lobe and roulette numbers are drawn.
        let mut lights = false;
        for (j, &pi) in chunk.iter().enumerate() {
            let i = pi as usize;
            let Some(v) = one_path::arrive::<F>(t, q, i) else { continue };
            let depth = q.depth[i];
            vertex_input[j] = Sampler::vertex_input(q.key[i], depth + 1);
            if !hashed {
                patterned[j] = t.streams.vertex_sampler(q.key[i], depth);
            }
            lights |= F::DIRECT
                && t.rules.counts_direct(depth)
                && t.materials.models[v.material as usize].kind() == Kind::Glossy;
            first.get_or_insert(j);
            vertex[j] = Some(v);
        }
        let Some(first) = first else { continue };
        let rng = if hashed {
            rng8::for_vertex_lanes(avx, &vertex_input)
        } else {
            // Lanes without a vertex take an active lane's stream, so that the numbers are
            // drawn for streams of one pattern (Sobol's eight at a time).
            for j in 0..L {
                if vertex[j].is_none() {
                    patterned[j] = patterned[first];
                }
            }
            patterned
        };
        let drawn = if lights { dims } else { dims.min(DIM_DIRECT as usize) };
        for d in 0..drawn {
            if layout.one_d[d] {
                let a = rng8::next_f32_lanes(avx, &rng, d as u32);
                for j in 0..L {
                    table[j * dims + d][0] = a[j];
                }
            } else {
                let (a, b) = rng8::next_2d_lanes(avx, &rng, d as u32);
                for j in 0..L {
                    table[j * dims + d] = [a[j], b[j]];
                }
            }
        }
        (pbr.n, phong.n, conductor.n, mirror.n, glass.n, layered.n) = (0, 0, 0, 0, 0, 0);
        for (j, &pi) in chunk.iter().enumerate() {
            let Some(v) = &vertex[j] else { continue };
            // Delta kinds take no light samples, so they leave in lanes whatever the rules;
            // the glossy ones where their light samples are drawn ahead.
            let in_lanes = match t.materials.models[v.material as usize] {
                Model::Mirror(_) | Model::Dielectric(_) => true,
                Model::Pbr(_) | Model::Glossy(_) | Model::Microfacet(_) | Model::Layered(_) => glossy_lanes,
                Model::Lambert(_) => false,
            };
            if in_lanes {
                let i = pi as usize;
                let taken = match t.model_at(v) {
                    Model::Pbr(m) => pbr.push(i, j, v, m),
                    Model::Glossy(m) => phong.push(i, j, v, m),
                    Model::Microfacet(m) => conductor.push(i, j, v, m),
                    Model::Mirror(m) => mirror.push(i, j, v, m),
                    Model::Dielectric(m) => glass.push(i, j, v, m),
                    // Seen from the direction the path arrives along (`Transport::shading`).
                    Model::Layered(_) => {
                        let cos_o = to_local(&Frame::new(v.ns), -q.ray[i].dir).z;
                        layered.push(i, j, v, t.materials.layers.at(t, v, cos_o))
                    }
                    Model::Lambert(_) => false,
                };
                if taken {
                    continue;
                }
            }
            let numbers =
                Drawn { stream: rng[j], table: &table[j * dims..j * dims + drawn], one_d: &layout.one_d, dim: 0 };
            one_path::leave::<F>(t, q, pi as usize, v, numbers, shadow);
        }
        if pbr.n > 0 {
            lanes_glossy::leave::<F, Pbr, L>(t, q, &pbr, table, dims, &rng, &mut pending, shadow);
        }
        if phong.n > 0 {
            lanes_glossy::leave::<F, Glossy, L>(t, q, &phong, table, dims, &rng, &mut pending, shadow);
        }
        if conductor.n > 0 {
            lanes_glossy::leave::<F, Microfacet, L>(t, q, &conductor, table, dims, &rng, &mut pending, shadow);
        }
        if mirror.n > 0 {
            lanes_glossy::leave::<F, Mirror, L>(t, q, &mirror, table, dims, &rng, &mut pending, shadow);
        }
        if glass.n > 0 {
            lanes_glossy::leave::<F, Dielectric, L>(t, q, &glass, table, dims, &rng, &mut pending, shadow);
        }
        if layered.n > 0 {
            lanes_glossy::leave::<F, Layered, L>(t, q, &layered, table, dims, &rng, &mut pending, shadow);
        }
    }
}
