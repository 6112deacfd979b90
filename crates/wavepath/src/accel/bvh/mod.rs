//! The bounding volume hierarchy: binned SAH build ([`build`]), collapse to 8-wide nodes
//! with SoA child boxes ([`wide`]), and traversal ([`traverse`]) with a box test chosen at
//! run time ([`Isa`]); the triangle test is the watertight one in every path.
/// Runs `$body` with `$t` bound to the kernel token of the best instruction set the tree may
/// use. The body is expanded once per instruction set, never shared as a closure: the AVX2
/// copy is inlined into `with_avx2`'s target-feature context (an out-of-line closure there
/// was compiled for the baseline set and ran 2-6x slower, three times over).
macro_rules! on_isa {
    ($bvh:expr, |$t:ident| $body:expr) => {
        match $bvh.tokens() {
            (_, Some(avx)) => $crate::cpu::with_avx2(
                avx,
                #[inline(always)]
                |$t| $body,
            ),
            (Some($t), None) => $body,
            _ => {
                let $t = $crate::accel::bvh::boxtest::Scalar;
                $body
            }
        }
    };
}

mod boxtest;
mod build;
mod coherent;
mod leaf;
mod morton;
mod packet;
mod simd;
mod traverse;
mod wide;

use super::{BuildInfo, Intersector, TraceCounters};
use crate::geometry::{Hit, Ray};
use crate::scene::Scene;
pub use crate::settings::{BvhBuild, BvhOptions, LeafLayout};

use crate::cpu::{Avx2, Isa, Sse};
use boxtest::{BoxRay, BoxTest, Frustum, RootBox};
use build::PrimRef;
use glam::Vec3;
use rayon::prelude::*;
use std::time::Instant;
use traverse::BigStack;
pub use wide::Node8;

/// Tree size (nodes and leaves, bytes) above which single rays are traced as in a tree that
/// does not fit the caches: three in flight at once, each prefetching the children it pushes,
/// which hides memory latency (25.6M, 1.6 GB: diffuse rays 1.19 -> 1.53 Mrays/s). Below it
/// they go one at a time without prefetching: the prefetches are only extra instructions
/// (Lucy 100k, 6 MB: 1-3% faster without), and rays in flight gain 2-5% on a lone mesh's
/// diffuse rays but cost renders 4-6% of their traverse stage (rays that end after a node or
/// two, a Cornell box's walls, pay the bookkeeping and overlap nothing). At 1.6M (100 MB) the
/// prefetches break even and rays in flight gain 15%. Packets prefetch at every size (camera
/// rays at 100k: 6-8% slower without).
const CACHED_UP_TO: usize = 32 << 20;

/// An 8-wide BVH over the triangles and spheres of a scene.
pub struct Bvh {
    nodes: Vec<Node8>,
    /// The leaves (a leaf reference's `first` is its place here): for the SIMD filter, the
    /// triangles lane by lane or a packed record; and the ids of all its primitives.
    leaves: leaf::LeafStore,
    /// Address of the leaf store and bytes per unit of `first`, for prefetching.
    leaf_base: (usize, usize),
    /// Whether single rays are traced as in a tree that fits the caches (see
    /// [`CACHED_UP_TO`]).
    cached: bool,
    /// (centre, radius) of each scene sphere; a sphere's primitive id is `tri_count` + its
    /// index.
    spheres: Vec<(Vec3, f32)>,
    tri_count: u32,
    stack_need: usize,
    isa: Isa,
    /// The kernel tokens `isa` allows, made once (not per ray).
    tokens: (Option<Sse>, Option<Avx2>),
    /// The quick test of batched closest-hit rays (None: every ray is traversed).
    root: Option<RootBox>,
    info: BuildInfo,
}

impl Bvh {
    /// Builds the tree with the leaf layout chosen by size; the box test is the best the CPU
    /// has (see [`Bvh::with_isa`]).
    pub fn build(scene: &Scene) -> Bvh {
        Bvh::build_with(scene, BvhOptions::default())
    }

    /// Builds the tree by `opts.build` with leaves in `opts.leaves`.
    pub fn build_with(scene: &Scene, opts: BvhOptions) -> Bvh {
        let start = Instant::now();
        let mesh = &scene.mesh;
        let tri_count = mesh.triangle_count();
        let total = tri_count + scene.spheres.len();
        assert!(total < wide::MAX_PRIMS, "a BVH holds at most {} primitives", wide::MAX_PRIMS);
        // A primitive's box: triangles first, then spheres (its index is its id).
        let prim = |i: usize| {
            if i < tri_count {
                let [a, b, c] = mesh.corners(i);
                (a.min(b).min(c), a.max(b).max(c))
            } else {
                let s = &scene.spheres[i - tri_count];
                let r = Vec3::splat(s.radius.abs());
                (s.center - r, s.center + r)
            }
        };
        let (mut nodes, depth, sah_cost, ids) = if total == 0 {
            (vec![], 0, 0.0, vec![])
        } else {
            let (bin, ids) = match opts.build {
                BvhBuild::Sah => {
                    let mut refs: Vec<PrimRef> = (0..total)
                        .into_par_iter()
                        .map(|i| {
                            let (lo, hi) = prim(i);
                            PrimRef::new(lo, hi, i as u32, i >= tri_count)
                        })
                        .collect();
                    let bin = build::build(&mut refs);
                    // Only the ids are kept: the references are freed before the collapse
                    // allocates.
                    let ids: Vec<u32> = refs.par_iter().map(PrimRef::id).collect();
                    (bin, ids)
                }
                BvhBuild::Fast => morton::build(total, prim),
            };
            let w = wide::collapse(&bin);
            (w.nodes, w.depth, w.sah_cost, ids)
        };
        let leaves = leaf::store_leaves(&mut nodes, &ids, scene, packs(opts.leaves, total));
        drop(ids);
        assert!(WIDTH_STACK * (depth + 1) <= traverse::BIG_STACK, "a BVH of {depth} levels is deeper than its stack");
        let info = BuildInfo {
            method: match opts.build {
                BvhBuild::Sah => "sah",
                BvhBuild::Fast => "fast",
            },
            build_s: start.elapsed().as_secs_f64(),
            nodes: nodes.len(),
            leaves: leaves.leaves(),
            depth,
            sah_cost,
            node_bytes: std::mem::size_of_val(&nodes[..]),
            leaf_bytes: leaves.bytes() + scene.spheres.len() * std::mem::size_of::<(Vec3, f32)>(),
        };
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        if let Some(root) = nodes.first() {
            for i in 0..wide::WIDTH {
                lo = lo.min(Vec3::new(root.b[0][i], root.b[2][i], root.b[4][i]));
                hi = hi.max(Vec3::new(root.b[1][i], root.b[3][i], root.b[5][i]));
            }
        }
        Bvh {
            root: RootBox::new(lo, hi),
            nodes,
            leaf_base: leaves.base(),
            cached: info.node_bytes + info.leaf_bytes <= CACHED_UP_TO,
            leaves,
            spheres: scene.spheres.iter().map(|s| (s.center, s.radius)).collect(),
            tri_count: tri_count as u32,
            stack_need: WIDTH_STACK * (depth + 1),
            isa: Isa::detect(),
            tokens: tokens_of(Isa::detect()),
            info,
        }
    }

    /// About how many bytes building a tree over `primitives` needs on top of the scene
    /// (references and binary nodes while it builds, then the nodes and leaves it keeps),
    /// from the peaks measured on subdivided Lucy (docs/decisions.md, "What a large mesh
    /// costs in memory"): 72 bytes a primitive with corner leaves, 56 with packed ones. For
    /// refusing, before anything is allocated, a build that cannot fit.
    pub fn build_bytes(primitives: usize, layout: LeafLayout) -> u64 {
        primitives as u64 * if packs(layout, primitives) { 56 } else { 72 }
    }

    /// The same tree with another box-test path (falls back to what the CPU has).
    pub fn with_isa(mut self, isa: Isa) -> Bvh {
        self.isa = isa.effective();
        self.tokens = tokens_of(isa);
        self
    }

    /// The same tree traced as if it did (or did not) fit the caches, whatever its size: the
    /// traversal [`CACHED_UP_TO`] picks for large trees, on small ones (for tests and
    /// measurements; hits are the same either way).
    pub fn assume_cached(mut self, cached: bool) -> Bvh {
        self.cached = cached;
        self
    }

    pub fn isa(&self) -> Isa {
        self.isa
    }

    pub fn info(&self) -> BuildInfo {
        self.info
    }

    /// The wide nodes, root first (for tests and diagnostics).
    pub fn nodes(&self) -> &[Node8] {
        &self.nodes
    }

    /// The boxes `depth` levels below the root's children (0: the root's children), inner
    /// nodes and leaves alike, as (lower, upper) corners: what a BVH view outlines.
    pub fn boxes_at_depth(&self, depth: u32) -> Vec<(Vec3, Vec3)> {
        let mut level = vec![0usize];
        for _ in 0..depth {
            level = level
                .iter()
                .flat_map(|&n| self.nodes.get(n).into_iter().flat_map(|node| node.child))
                .filter(|&c| c != wide::EMPTY && c & wide::LEAF_BIT == 0)
                .map(|c| c as usize)
                .collect();
        }
        let mut out = Vec::new();
        for node in level.iter().filter_map(|&n| self.nodes.get(n)) {
            for k in 0..wide::WIDTH {
                if node.child[k] != wide::EMPTY {
                    let b = |i: usize| node.b[i][k];
                    out.push((Vec3::new(b(0), b(2), b(4)), Vec3::new(b(1), b(3), b(5))));
                }
            }
        }
        out
    }

    fn dispatch_closest(&self, ray: &Ray, counters: &mut TraceCounters) -> Option<Hit> {
        on_isa!(self, |isa| traverse::closest_hit(self, isa, ray, counters))
    }

    /// Leaf block `i` as the SIMD filter reads it: in place, or gathered into `scratch`.
    #[inline(always)]
    fn block<'a>(&'a self, i: usize, scratch: &'a mut leaf::Tri4) -> &'a leaf::Tri4 {
        self.leaves.block(i, scratch)
    }

    /// The leaf layout the tree was built with (see [`LeafLayout`]).
    pub fn layout(&self) -> &'static str {
        match self.leaves {
            leaf::LeafStore::Corners(_) => "corners",
            leaf::LeafStore::Packed { .. } => "packed",
        }
    }

    #[inline(always)]
    fn tokens(&self) -> (Option<Sse>, Option<Avx2>) {
        self.tokens
    }
}

/// The tokens of the box-test paths `isa` allows on this CPU.
fn tokens_of(isa: Isa) -> (Option<Sse>, Option<Avx2>) {
    (isa.sse(), isa.avx2())
}

/// Primitives from which [`LeafLayout::Auto`] packs the leaves (chosen by measurement: see
/// docs/decisions.md, "Leaf layouts").
const PACKED_FROM: usize = 16_000_000;

/// Whether a tree of `primitives` in `layout` packs its leaves.
fn packs(layout: LeafLayout, primitives: usize) -> bool {
    match layout {
        LeafLayout::Corners => false,
        LeafLayout::Packed => true,
        LeafLayout::Auto => primitives >= PACKED_FROM,
    }
}

/// Rays set up at a time ahead of their traversal in a batch (at most 32: one bit each
/// in the mask of rays that may enter the tree).
const SETUP_GROUP: usize = 32;
const _: () = assert!(SETUP_GROUP <= 32);

/// Stack entries needed per tree level (a node pushes at most all its children).
const WIDTH_STACK: usize = wide::WIDTH;

impl Intersector for Bvh {
    fn closest_hit(&self, ray: &Ray, counters: &mut TraceCounters) -> Option<Hit> {
        if self.nodes.is_empty() {
            counters.rays += 1;
            return None;
        }
        self.dispatch_closest(ray, counters)
    }

    fn any_hit(&self, ray: &Ray, counters: &mut TraceCounters) -> bool {
        if self.nodes.is_empty() {
            counters.rays += 1;
            return false;
        }
        on_isa!(self, |isa| traverse::any_hit(self, isa, ray, counters))
    }

    fn name(&self) -> String {
        format!("bvh8 {}, {} build", self.isa.name(), self.info.method)
    }

    fn closest_hits(&self, rays: &[Ray], hits: &mut [Option<Hit>], counters: &mut TraceCounters) {
        self.closest_batch(rays, hits, counters)
    }

    fn any_hits_packets(&self, rays: &[Ray], occluded: &mut [bool], counters: &mut TraceCounters) {
        if self.nodes.is_empty() {
            return self.any_hits(rays, occluded, counters);
        }
        packet::any_hits(self, rays, occluded, counters);
    }

    fn any_hits(&self, rays: &[Ray], occluded: &mut [bool], counters: &mut TraceCounters) {
        if self.nodes.is_empty() {
            counters.rays += rays.len() as u64;
            occluded.iter_mut().for_each(|o| *o = false);
            return;
        }
        let mut stack = traverse::BigStack::boxed();
        macro_rules! run {
            ($isa:expr) => {
                for (r, o) in rays.iter().zip(occluded.iter_mut()) {
                    *o = traverse::any_hit_with(self, $isa, r, counters, &mut stack);
                }
            };
        }
        on_isa!(self, |isa| run!(isa))
    }
}

impl Bvh {
    /// Closest hits of a batch.
    fn closest_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>], counters: &mut TraceCounters) {
        if self.nodes.is_empty() {
            counters.rays += rays.len() as u64;
            hits.iter_mut().for_each(|h| *h = None);
            return;
        }
        // One dispatch and one stack for the whole batch, so the loop runs inside the AVX2
        // context and no stack is cleared per ray.
        // The loop is spelled out in the macro (here and in `any_hits`) on purpose: moving it
        // into a helper taking a closure compiled it outside the AVX2 context and halved
        // traversal speed (measured: CBspheres_lambertian 1.2 s -> 2.6 s, one thread).
        // Every closure given to `with_avx2` is `#[inline(always)]` for the same reason: a
        // larger body (set-up of the shear added to this loop) was left out of line by the
        // inliner, outside the AVX2 context, and ran six times slower.
        let mut stack = BigStack::boxed();
        // The stacks of the second and third ray in flight (trees beyond the caches only).
        let mut more: Option<Box<[BigStack; 2]>> = None;
        let mut packets = None;
        // Filled per group (not cleared: every entry read was just written).
        let mut prep = [BoxRay::DEAD; SETUP_GROUP];
        macro_rules! run {
            ($isa:expr) => {{
                // Per group, eight rays at a time: which may enter the tree at all (most
                // primary rays miss it) and the set-up (three divisions per ray) of the eights
                // that have one; the others are misses without further work.
                let mut slot = [0u8; SETUP_GROUP];
                let mut singles = [0u8; SETUP_GROUP];
                for (rs, hs) in rays.chunks(SETUP_GROUP).zip(hits.chunks_mut(SETUP_GROUP)) {
                    let mut todo = $isa.set_up(self.root.as_ref(), rs, &mut prep[..rs.len()]);
                    let mut n = 0;
                    while todo != 0 {
                        slot[n] = todo.trailing_zeros() as u8;
                        todo &= todo - 1;
                        n += 1;
                    }
                    counters.rays += (rs.len() - n) as u64;
                    hs.fill(None);
                    // Runs of coherent rays (camera rays) as packets, the others one by one or,
                    // in trees beyond the caches, three at a time.
                    let mut k = 0;
                    let mut m = 0;
                    while k < n {
                        let len = coherent::packet_len(rs, &slot[k..n], &prep);
                        if len >= coherent::MIN_RAYS {
                            let mut rays = [rs[slot[k] as usize]; coherent::COHERENT];
                            for (r, &i) in rays.iter_mut().zip(&slot[k..k + len]) {
                                *r = rs[i as usize];
                            }
                            let mut out = [None; coherent::COHERENT];
                            let f = Frustum::of(slot[k..k + len].iter().map(|&i| &prep[i as usize]));
                            let packets = packets.get_or_insert_with(|| coherent::PacketStack::new(self));
                            coherent::closest_packet(self, $isa, &rays[..len], &f, &mut out[..len], counters, packets);
                            for (&i, h) in slot[k..k + len].iter().zip(out) {
                                hs[i as usize] = h;
                            }
                        } else if self.cached {
                            for &i in &slot[k..k + len] {
                                let i = i as usize;
                                hs[i] = traverse::closest_hit_with(self, $isa, &rs[i], &prep[i], counters, &mut stack);
                            }
                        } else {
                            singles[m..m + len].copy_from_slice(&slot[k..k + len]);
                            m += len;
                        }
                        k += len;
                    }
                    if m > 0 {
                        let more = more.get_or_insert_with(|| Box::new([BigStack::new(), BigStack::new()]));
                        let [b, c] = &mut **more;
                        let stacks = [&mut *stack, b, c];
                        traverse::closest_interleaved(self, $isa, rs, &prep, &singles[..m], hs, counters, stacks);
                    }
                }
            }};
        }
        on_isa!(self, |isa| run!(isa))
    }
}
