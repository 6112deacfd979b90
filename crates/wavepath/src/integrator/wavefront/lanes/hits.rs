//! Shade for the hits on one material model, eight or sixteen paths at a time: each lane
//! arrives ([`one_path::arrive_at_hit`]: its emission and the light its ray found), the
//! group's shading points are reconstructed in lanes (one lane at a time where the surface
//! has textures, colours, relief or volumes), each lane's model is made from its vertex, and
//! the group leaves as every model does ([`leave`]), its random numbers drawn `L` streams at
//! a time as the model asks for them ([`Hashed`]: the vertex streams' own, so the rays are
//! those of the one-path kernel, bit for bit).
//!
//! [`super::super::shade`] sorts a wave's hits into one index list per model
//! ([`lane_models!`], the one list of them), so every group is one model and full but for
//! each list's last.

#![allow(clippy::needless_range_loop)]

use super::leave::{Group, leave};
use super::model::LaneModel;
use super::numbers::{Hashed, Stream};
use super::soa::{Points, Rays, Surfaces, get, surface_points, whole_vertices};
use super::width::{LaneKernel, ShadeWidth};
use crate::bsdf::{Dielectric, Glossy, Lambert, Layered, Microfacet, Mirror, Model, Pbr};
use crate::geometry::Hit;
use crate::integrator::wavefront::aov::AovRecords;
use crate::integrator::wavefront::one_path;
use crate::integrator::wavefront::queues::{PathQueue, ShadowQueue};
use crate::integrator::{Transport, Vertex};
use crate::sampling::rng8::{self, Hasher};
use crate::sampling::{Sampler, SamplerKind};
use glam::{Vec2, Vec3};

/// The models shaded in lanes, each with its index list: the one list the sorting after
/// traverse and the kernels are written from. A model added to [`Model`] is a [`LaneModel`]
/// and a line here.
macro_rules! lane_models {
    ($($model:ident),* $(,)?) => {
        /// How many models have an index list.
        pub const MODELS: usize = [$(stringify!($model)),*].len();

        /// The index list of a hit on a material of `model` (a model missing from the list
        /// does not compile).
        #[inline(always)]
        pub fn list_of(model: &Model) -> usize {
            enum List {
                $($model,)*
            }
            match model {
                $(Model::$model(_) => List::$model as usize,)*
            }
        }

        $(impl OfModel for $model {
            #[inline(always)]
            fn of(m: Model) -> Self {
                match m {
                    Model::$model(x) => x,
                    _ => Self::NONE,
                }
            }
        })*

        /// Shades each model's hits (`lists`, by [`list_of`]) in lanes; with `aovs`, records the
        /// output variables of the hits whose samples wait for them.
        pub fn shade_hits(
            width: ShadeWidth,
            t: &Transport,
            q: &mut PathQueue,
            lists: &[Vec<u32>; MODELS],
            shadow: &mut ShadowQueue,
            mut aovs: Option<&mut AovRecords>,
        ) {
            let mut k = 0;
            $(
                if !lists[k].is_empty() {
                    let aovs = aovs.as_deref_mut();
                    width.dispatch(Hits::<$model> { t, q: &mut *q, idx: &lists[k], shadow: &mut *shadow, aovs, model: std::marker::PhantomData });
                }
                k += 1;
            )*
            let _ = k;
        }

        /// Path `i` leaves its vertex `v` with the numbers of its stream `rng`: the leaving
        /// kernel at one lane (the one-path code), `pending` its scratch.
        pub fn leave_one(
            t: &Transport,
            q: &mut PathQueue,
            i: usize,
            v: &Vertex,
            rng: Sampler,
            pending: &mut Vec<Rays<1>>,
            shadow: &mut ShadowQueue,
        ) {
            if !t.rules.features.non_diffuse {
                return one::<Lambert>(t, q, i, v, rng, pending, shadow);
            }
            match t.materials.models[v.material as usize] {
                $(Model::$model(_) => one::<$model>(t, q, i, v, rng, pending, shadow),)*
            }
        }
    };
}

lane_models!(Lambert, Pbr, Glossy, Microfacet, Mirror, Dielectric, Layered);

/// [`leave_one`] for a vertex of model `M`.
#[inline(always)]
fn one<M: OfModel>(
    t: &Transport,
    q: &mut PathQueue,
    i: usize,
    v: &Vertex,
    rng: Sampler,
    pending: &mut Vec<Rays<1>>,
    shadow: &mut ShadowQueue,
) {
    let mut g = Group::<M, 1>::new();
    let m = M::at_vertex(v).unwrap_or_else(|| M::of(t.model_at(v)).seen(t, v, q.ray[i].dir));
    g.push(t, q, i, v, m);
    if g.sends() {
        leave(t, q, &g, Stream(rng), pending, shadow);
    }
}

/// The concrete model of a [`Model`] of its kind (the list's models only).
pub trait OfModel: LaneModel {
    fn of(m: Model) -> Self;
}

/// The hits `idx` (all on materials of model `M`), run at the chosen width.
struct Hits<'a, 's, M> {
    t: &'a Transport<'s>,
    q: &'a mut PathQueue,
    idx: &'a [u32],
    shadow: &'a mut ShadowQueue,
    aovs: Option<&'a mut AovRecords>,
    model: std::marker::PhantomData<M>,
}

impl<M: OfModel> LaneKernel for Hits<'_, '_, M> {
    #[inline(always)]
    fn run<H: Hasher, const L: usize>(self, h: H) {
        let Hits { t, q, idx, shadow, aovs, .. } = self;
        shade_groups::<M, H, L>(h, t, q, idx, shadow, aovs)
    }
}

/// The hits `idx` on model `M`, `L` at a time; the random numbers are drawn `L` streams at
/// a time (with `h`).
#[inline(always)]
fn shade_groups<M: OfModel, H: Hasher, const L: usize>(
    h: H,
    t: &Transport,
    q: &mut PathQueue,
    idx: &[u32],
    shadow: &mut ShadowQueue,
    mut aovs: Option<&mut AovRecords>,
) {
    let mut g = Group::<M, L>::new();
    let mut gather = Gather::<L>::new(t);
    let mut pending: Vec<Rays<L>> = Vec::new();
    let hashed = t.streams.pattern.kind == SamplerKind::Independent;
    for chunk in idx.chunks(L) {
        g.clear();
        let keys = if gather.whole {
            gather.gather::<M, true>(t, q, chunk, &mut g, None)
        } else {
            gather.gather::<M, false>(t, q, chunk, &mut g, aovs.as_deref_mut())
        };
        if !g.sends() {
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
        leave(t, q, &g, Hashed { h, rng: &rng }, &mut pending, shadow);
    }
}

/// What the gather of a group keeps between groups.
struct Gather<'t, const L: usize> {
    /// Whole vertices are gathered one lane at a time ([`whole_vertices`]); else the
    /// group's shading points are reconstructed in lanes.
    whole: bool,
    surf: Surfaces<L>,
    normals: Option<&'t [Vec3]>,
    spheres: bool,
    /// Each lane's hit, material and emission seen (points in lanes only).
    hits: [(Hit, usize, Vec3); L],
    /// Each lane's material (points in lanes only).
    materials: [usize; L],
}

impl<'t, const L: usize> Gather<'t, L> {
    fn new(t: &'t Transport) -> Self {
        let none = (Hit { t: 0.0, u: 0.0, v: 0.0, prim: 0 }, 0, Vec3::ZERO);
        Gather {
            whole: whole_vertices(t),
            surf: Surfaces::default(),
            normals: t.scene.mesh.normals.as_deref(),
            spheres: !t.scene.spheres.is_empty(),
            hits: [none; L],
            materials: [0; L],
        }
    }

    /// The paths of `chunk` arrive, one at a time; those that go on into `g`, their models
    /// made from their vertices (`WHOLE`: `Transport::vertex`; else reconstructed in lanes).
    /// Each lane's path key. With `aovs` (points in lanes only), the lanes whose samples wait
    /// for their output variables record them from the group's points.
    #[inline(always)]
    fn gather<M: OfModel, const WHOLE: bool>(
        &mut self,
        t: &Transport,
        q: &mut PathQueue,
        chunk: &[u32],
        g: &mut Group<M, L>,
        aovs: Option<&mut AovRecords>,
    ) -> [u64; L] {
        let leaves = t.rules.features.direct || t.rules.features.indirect;
        let mut keys = [0u64; L];
        for &pi in chunk {
            let i = pi as usize;
            let hit = q.hit[i].expect("a model's list holds hits only");
            let a = one_path::arrive_at_hit::<WHOLE>(t, q, i, hit);
            if !leaves {
                continue;
            }
            let j = g.n;
            keys[j] = q.key[i];
            if WHOLE {
                let v = &a.vertex;
                let m = M::at_vertex(v).unwrap_or_else(|| M::of(t.model_at(v)).seen(t, v, q.ray[i].dir));
                g.push(t, q, i, v, m);
            } else {
                // The model is made below, where the lane's point is known, unless the
                // material alone makes it.
                g.push_path(t, q, i, M::at_material(t, a.material));
                self.surf.set(t, self.normals, j, &q.ray[i], &hit);
                self.materials[j] = a.material;
                if !M::FROM_MATERIAL {
                    self.hits[j] = (hit, a.material, a.emission);
                }
            }
        }
        if !WHOLE && g.n > 0 {
            // Only into the group's points: what follows reads a lane's point there, and the
            // lanes are not relief-mapped (copying the points into vertices lane by lane
            // was 8% of the Lambertian kind's stage).
            surface_points(&self.surf, self.normals.is_some(), self.spheres, &mut g.pts);
            if let Some(r) = aovs {
                for j in 0..g.n {
                    let i = g.path[j];
                    let slot = q.slot[i] as usize;
                    if r.pending(slot) {
                        let (m, t_hit) = (self.materials[j], q.hit[i].map_or(0.0, |h| h.t));
                        // `Transport::model_at` for a surface without textures or colours.
                        let albedo = t.materials.models[m].oriented(g.pts.front[j]).albedo_estimate();
                        let (p, ns) = (get(&g.pts.p, j), get(&g.pts.ns, j));
                        r.record_hit(slot, q.depth[i], t_hit, q.ray[i].dir, p, ns, albedo);
                    }
                }
            }
            if !M::FROM_MATERIAL {
                for j in 0..g.n {
                    let (hit, m, emission) = &self.hits[j];
                    let v = lane_vertex(t, &g.pts, j, hit, *m, *emission);
                    let dir = q.ray[g.path[j]].dir;
                    g.set_model(t, j, M::of(t.model_at(&v)).seen(t, &v, dir));
                }
            }
        }
        keys
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
