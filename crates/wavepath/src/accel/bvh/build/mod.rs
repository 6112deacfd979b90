//! Building a [`Bvh`]: a binary tree by the SAH ([`sah`]) or along a Morton curve
//! ([`morton`]), both in the layout of [`binary`]; then the collapse to 8-wide nodes
//! ([`collapse`]) and the leaf store ([`leaves`]), shared by both.
mod binary;
mod collapse;
mod leaves;
mod morton;
mod sah;

use super::Bvh;
use super::simd::{RootBox, Tokens};
use super::traverse::{BIG_STACK, CACHED_UP_TO, WIDTH_STACK};
use super::tree::{MAX_PRIMS, WIDTH};
use crate::accel::BuildInfo;
use crate::accel::cutout::Cutouts;
use crate::cpu::Isa;
use crate::scene::Scene;
use crate::settings::{BvhBuild, BvhOptions, LeafLayout};
use glam::Vec3;
use rayon::prelude::*;
use sah::PrimRef;
use std::time::Instant;

/// Builds the tree by `opts.build` with leaves in `opts.leaves`.
pub fn build(scene: &Scene, opts: BvhOptions) -> Bvh {
    let start = Instant::now();
    let mesh = &scene.mesh;
    let tri_count = mesh.triangle_count();
    let total = tri_count + scene.spheres.len();
    assert!(total < MAX_PRIMS, "a BVH holds at most {} primitives", MAX_PRIMS);
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
                let bin = sah::build(&mut refs);
                // Only the ids are kept: the references are freed before the collapse
                // allocates.
                let ids: Vec<u32> = refs.par_iter().map(PrimRef::id).collect();
                (bin, ids)
            }
            BvhBuild::Fast => morton::build(total, prim),
        };
        let w = collapse::collapse(&bin);
        (w.nodes, w.depth, w.sah_cost, ids)
    };
    let leaves = leaves::store_leaves(&mut nodes, &ids, scene, packs(opts.leaves, total));
    drop(ids);
    assert!(WIDTH_STACK * (depth + 1) <= BIG_STACK, "a BVH of {depth} levels is deeper than its stack");
    let cutouts = Cutouts::of(scene).map(Box::new);
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
        leaf_bytes: leaves.bytes()
            + scene.spheres.len() * std::mem::size_of::<(Vec3, f32)>()
            + cutouts.as_ref().map_or(0, |c| c.bytes()),
    };
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    if let Some(root) = nodes.first() {
        for i in 0..WIDTH {
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
        cutouts,
        stack_need: WIDTH_STACK * (depth + 1),
        isa: Isa::detect(),
        tokens: Tokens::of(Isa::detect()),
        info,
    }
}

/// About how many bytes building a tree over `primitives` needs on top of the scene
/// (references and binary nodes while it builds, then the nodes and leaves it keeps),
/// from the peaks measured on subdivided Lucy (docs/decisions.md, "What a large mesh
/// costs in memory"): 72 bytes a primitive with corner leaves, 56 with packed ones.
pub fn bytes(primitives: usize, layout: LeafLayout) -> u64 {
    primitives as u64 * if packs(layout, primitives) { 56 } else { 72 }
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
