//! Shade for the hits on every material but the Lambertian one (glossy, metallic-roughness,
//! conductors, mirror, glass, the layered glTF model), eight or sixteen paths at a time: each
//! lane arrives one at a time ([`one_path::arrive_as`]: its emission and the light its ray
//! found), the group's vertices are reconstructed in lanes (one lane at a time where the
//! surface has textures, colours, relief or volumes), the group's random numbers are drawn in lanes, as many dimensions as the
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

use super::lane_width::{LaneKernel, ShadeWidth};
use super::lanes::{self, Points, Rays, Surfaces, get, surface_points};
use super::lanes_glossy::{self, ModelGroup};
use super::one_path;
use super::queues::{PathQueue, ShadowQueue};
use crate::bsdf::{Dielectric, Glossy, Kind, Layered, Microfacet, Mirror, Model, Pbr, to_local};
use crate::geometry::Hit;
use crate::integrator::{DIM_DIRECT, Transport, Vertex};
use crate::sampling::numbers::Drawn;
use crate::sampling::rng8::Hasher;
use crate::sampling::{Frame, SamplerKind, rng8};
use glam::{Vec2, Vec3};

/// Shades the paths `idx` (hits on non-Lambertian materials), `L` at a time; `table` is
/// scratch for the numbers drawn ahead.
pub fn shade_shaded(
    width: ShadeWidth,
    t: &Transport,
    q: &mut PathQueue,
    idx: &[u32],
    shadow: &mut ShadowQueue,
    table: &mut Vec<[f32; 2]>,
) {
    width.dispatch(Shaded { t, q, idx, shadow, table })
}

/// [`shade_shaded`]'s arguments, run at the chosen width.
struct Shaded<'a, 's> {
    t: &'a Transport<'s>,
    q: &'a mut PathQueue,
    idx: &'a [u32],
    shadow: &'a mut ShadowQueue,
    table: &'a mut Vec<[f32; 2]>,
}

impl LaneKernel for Shaded<'_, '_> {
    #[inline(always)]
    fn run<H: Hasher, const L: usize>(self, h: H) {
        shade_groups::<H, L>(h, self.t, self.q, self.idx, self.shadow, self.table)
    }
}

#[inline(always)]
fn shade_groups<H: Hasher, const L: usize>(
    h: H,
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
    // Where the surfaces need no more than points and normals, the group's vertices are
    // reconstructed in lanes (as the diffuse kernel's), not one lane at a time.
    let whole = lanes::whole_vertices(t);
    let corner_normals = t.scene.mesh.normals.as_deref();
    let spheres = !t.scene.spheres.is_empty();
    let mut surf = Surfaces::<L>::default();
    let mut pts = Points::<L>::default();
    for chunk in idx.chunks(L) {
        let mut vertex: [Option<Vertex>; L] = [None; L];
        let (mut keys, mut bounces) = ([0u64; L], [0u32; L]);
        let mut first = None;
        // Whether a lane reads light samples (a glossy vertex whose direct light counts):
        // else only the continuation, lobe and roulette numbers are drawn.
        let mut lights = false;
        let mut hits: [Option<(Hit, usize, Vec3)>; L] = [None; L];
        for (j, &pi) in chunk.iter().enumerate() {
            let i = pi as usize;
            let arrival =
                if whole { one_path::arrive_as::<true>(t, q, i) } else { one_path::arrive_as::<false>(t, q, i) };
            let Some(a) = arrival else { continue };
            let depth = q.depth[i];
            (keys[j], bounces[j]) = (q.key[i], depth + 1);
            lights |= t.rules.features.direct
                && t.rules.counts_direct(depth)
                && t.materials.models[a.material].kind() == Kind::Glossy;
            first.get_or_insert(j);
            if whole {
                vertex[j] = Some(a.vertex);
            } else {
                surf.set(t, corner_normals, j, &q.ray[i], &a.hit);
                hits[j] = Some((a.hit, a.material, a.emission));
            }
        }
        let Some(first) = first else { continue };
        if !whole {
            surface_points(&surf, corner_normals.is_some(), spheres, &mut pts);
            for j in 0..L {
                if let Some((hit, m, emission)) = &hits[j] {
                    vertex[j] = Some(lane_vertex(t, &pts, j, hit, *m, *emission));
                }
            }
        }
        let mut rng = rng8::vertex_lanes(h, t.streams.pattern, &keys, &bounces);
        if !hashed {
            // Lanes without a vertex take an active lane's stream, so that the numbers are
            // drawn for streams of one pattern (Sobol's for all lanes at once).
            for j in 0..L {
                if vertex[j].is_none() {
                    rng[j] = rng[first];
                }
            }
        }
        let drawn = if lights { dims } else { dims.min(DIM_DIRECT as usize) };
        for d in 0..drawn {
            if layout.one_d[d] {
                let a = rng8::next_f32_lanes(h, &rng, d as u32);
                for j in 0..L {
                    table[j * dims + d][0] = a[j];
                }
            } else {
                let (a, b) = rng8::next_2d_lanes(h, &rng, d as u32);
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
            one_path::leave(t, q, pi as usize, v, numbers, shadow);
        }
        if pbr.n > 0 {
            lanes_glossy::leave::<Pbr, L>(t, q, &pbr, table, dims, &rng, &mut pending, shadow);
        }
        if phong.n > 0 {
            lanes_glossy::leave::<Glossy, L>(t, q, &phong, table, dims, &rng, &mut pending, shadow);
        }
        if conductor.n > 0 {
            lanes_glossy::leave::<Microfacet, L>(t, q, &conductor, table, dims, &rng, &mut pending, shadow);
        }
        if mirror.n > 0 {
            lanes_glossy::leave::<Mirror, L>(t, q, &mirror, table, dims, &rng, &mut pending, shadow);
        }
        if glass.n > 0 {
            lanes_glossy::leave::<Dielectric, L>(t, q, &glass, table, dims, &rng, &mut pending, shadow);
        }
        if layered.n > 0 {
            lanes_glossy::leave::<Layered, L>(t, q, &layered, table, dims, &rng, &mut pending, shadow);
        }
    }
}

/// Lane `j`'s vertex from the group's points `pts` (hit `hit` on material `m`, emission seen
/// `emission`): what `Transport::vertex` gives a surface with no textures, colours, relief or
/// volumes, field for field.
#[inline(always)]
fn lane_vertex<const L: usize>(
    t: &Transport,
    pts: &Points<L>,
    j: usize,
    hit: &Hit,
    m: usize,
    emission: Vec3,
) -> Vertex {
    let prim = hit.prim as usize;
    // A sphere's uv is computed only for textures (`Scene::surface_point_with`).
    let uv = if prim < t.scene.mesh.triangles.len() { t.scene.triangle_uv(prim, hit.u, hit.v) } else { Vec2::ZERO };
    Vertex {
        p: get(&pts.p, j),
        p_error: get(&pts.e, j),
        ng: get(&pts.ng, j),
        ns: get(&pts.ns, j),
        albedo: t.materials.albedo[m],
        emission,
        metal_rough: t.materials.metal_rough[m],
        material: m as u32,
        front: pts.front[j],
        uv,
        bumped: false,
    }
}
