//! The bounding volume hierarchy: 8-wide nodes with SoA child boxes ([`tree`]), built by the
//! binned SAH or along a Morton curve ([`build`]), traced by the loops of [`traverse`] with
//! the kernels of [`simd`] chosen at run time ([`Isa`]); [`query`] answers the
//! [`crate::accel::Intersector`] queries with them. The triangle test is the watertight one in
//! every path.
mod build;
mod query;
mod simd;
mod traverse;
mod tree;

use super::BuildInfo;
use super::cutout::Cutouts;
use crate::cpu::Isa;
use crate::scene::Scene;
#[cfg(test)]
pub use crate::settings::BvhBuild;
pub use crate::settings::{BvhOptions, LeafLayout};
use glam::Vec3;
use simd::{RootBox, Tokens};
pub use tree::Node8;
use tree::{EMPTY, LEAF_BIT, LeafStore, Tri4, WIDTH};

/// An 8-wide BVH over the triangles and spheres of a scene.
pub struct Bvh {
    nodes: Vec<Node8>,
    /// The leaves (a leaf reference's `first` is its place here): for the SIMD filter, the
    /// triangles lane by lane or a packed record; and the ids of all its primitives.
    leaves: LeafStore,
    /// Address of the leaf store and bytes per unit of `first`, for prefetching.
    leaf_base: (usize, usize),
    /// Whether single rays are traced as in a tree that fits the caches (see
    /// `traverse::CACHED_UP_TO`).
    cached: bool,
    /// (centre, radius) of each scene sphere; a sphere's primitive id is `tri_count` + its
    /// index.
    spheres: Vec<(Vec3, f32)>,
    tri_count: u32,
    /// The alpha test of the scene's cut triangles; `None` (no test compiled into the
    /// loops) when nothing is cut.
    cutouts: Option<Box<Cutouts>>,
    stack_need: usize,
    isa: Isa,
    /// The kernel tokens `isa` allows, made once (not per ray).
    tokens: Tokens,
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
        build::build(scene, opts)
    }

    /// About how many bytes building a tree over `primitives` needs on top of the scene
    /// (see [`build::bytes`]), for refusing, before anything is allocated, a build that
    /// cannot fit.
    pub fn build_bytes(primitives: usize, layout: LeafLayout) -> u64 {
        build::bytes(primitives, layout)
    }

    /// The same tree with another box-test path (falls back to what the CPU has).
    pub fn with_isa(mut self, isa: Isa) -> Bvh {
        self.isa = isa.at_most_avx2();
        self.tokens = Tokens::of(isa);
        self
    }

    /// The same tree traced as if it did (or did not) fit the caches, whatever its size: the
    /// traversal `traverse::CACHED_UP_TO` picks for large trees, on small ones (for tests and
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
                .filter(|&c| c != EMPTY && c & LEAF_BIT == 0)
                .map(|c| c as usize)
                .collect();
        }
        let mut out = Vec::new();
        for node in level.iter().filter_map(|&n| self.nodes.get(n)) {
            for k in 0..WIDTH {
                if node.child[k] != EMPTY {
                    let b = |i: usize| node.b[i][k];
                    out.push((Vec3::new(b(0), b(2), b(4)), Vec3::new(b(1), b(3), b(5))));
                }
            }
        }
        out
    }

    /// The leaf layout the tree was built with (see [`LeafLayout`]).
    pub fn layout(&self) -> &'static str {
        match self.leaves {
            LeafStore::Corners(_) => "corners",
            LeafStore::Packed { .. } => "packed",
        }
    }

    /// Leaf block `i` as the SIMD filter reads it: in place, or gathered into `scratch`.
    #[inline(always)]
    fn block<'a>(&'a self, i: usize, scratch: &'a mut Tri4) -> &'a Tri4 {
        self.leaves.block(i, scratch)
    }
}
