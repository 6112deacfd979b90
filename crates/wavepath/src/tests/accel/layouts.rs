//! The two leaf layouts (`--bvh-leaves corners|packed`) and the two builds (`--bvh-build
//! sah|fast`): the same hits bit for bit on every traversal path and instruction set, and the
//! memory each layout says it takes.

use crate::accel::{BruteForce, Bvh, BvhBuild, BvhOptions, Intersector, LeafLayout, TraceCounters};
use crate::cpu::Isa;
use crate::geometry::Ray;
use crate::scene::{Mesh, Scene, Sphere};
use crate::tests::common::meshgen::{icosphere, scene_of};
use crate::tests::common::{Xorshift, same_hit};
use glam::Vec3;

fn unit(x: &mut Xorshift) -> f32 {
    (x.next() >> 40) as f32 / (1u64 << 24) as f32
}

fn point(x: &mut Xorshift, scale: f32) -> Vec3 {
    Vec3::new(unit(x) - 0.5, unit(x) - 0.5, unit(x) - 0.5) * scale
}

/// Disjoint small triangles (no shared vertex: a packed leaf of four holds twelve vertices,
/// the most a record takes), with two spheres among them.
fn soup() -> Scene {
    let mut x = Xorshift(0x5eed);
    let mut mesh = Mesh::default();
    for i in 0..3000u32 {
        let c = point(&mut x, 2.0);
        for _ in 0..3 {
            mesh.positions.push(c + point(&mut x, 0.1));
        }
        mesh.triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
        mesh.material_ids.push(0);
    }
    let spheres = vec![
        Sphere { center: Vec3::new(0.2, 0.1, 0.0), radius: 0.05, material: 0 },
        Sphere { center: Vec3::new(-0.3, 0.0, 0.2), radius: 0.3, material: 0 },
    ];
    scene_of(mesh, spheres)
}

/// Forty copies of one triangle (every centroid the same: the builder's median splits),
/// beside degenerate ones (a point, a segment) and a closed icosphere.
fn coincident() -> Scene {
    let mut mesh = icosphere(8);
    let base = mesh.positions.len() as u32;
    mesh.positions.extend([Vec3::new(-0.2, -0.2, 1.5), Vec3::new(0.3, -0.1, 1.5), Vec3::new(0.0, 0.4, 1.5)]);
    mesh.positions.extend([Vec3::new(0.0, 0.0, -1.5), Vec3::new(0.5, 0.5, -1.5)]);
    for _ in 0..40 {
        mesh.triangles.push([base, base + 1, base + 2]);
    }
    mesh.triangles.push([base + 3, base + 3, base + 3]);
    mesh.triangles.push([base + 3, base + 4, base + 4]);
    mesh.material_ids.resize(mesh.triangles.len(), 0);
    scene_of(mesh, vec![])
}

fn scenes() -> Vec<(&'static str, Scene)> {
    let sphere = Sphere { center: Vec3::new(0.0, 1.2, 0.0), radius: 0.4, material: 0 };
    vec![("icosphere", scene_of(icosphere(16), vec![sphere])), ("soup", soup()), ("coincident", coincident())]
}

/// Random rays aimed into the scene, axis-parallel ones (with -0 components), and
/// shadow-like copies that stop just short of what they hit.
fn rays(scene: &Scene) -> Vec<Ray> {
    let mut x = Xorshift(17);
    let mut rays: Vec<Ray> = (0..4000)
        .map(|_| {
            let o = point(&mut x, 4.0);
            Ray::new(o, point(&mut x, 1.5) - o)
        })
        .collect();
    for k in 0..100 {
        let t = k as f32 / 50.0 - 1.0;
        rays.push(Ray::new(Vec3::new(t, 0.1, 5.0), Vec3::new(0.0, -0.0, -1.0)));
        rays.push(Ray::new(Vec3::new(-5.0, t, 0.0), Vec3::new(1.0, 0.0, 0.0)));
    }
    let brute = BruteForce::new(scene);
    let mut c = TraceCounters::default();
    let shadows: Vec<Ray> =
        rays.iter().filter_map(|r| brute.closest_hit(r, &mut c).map(|h| Ray { tmax: h.t * 0.999, ..*r })).collect();
    rays.extend(shadows);
    rays
}

#[test]
fn every_build_and_leaf_layout_gives_the_hits_of_brute_force_on_every_path() {
    for (name, scene) in scenes() {
        let rays = rays(&scene);
        let brute = BruteForce::new(&scene);
        let mut c = TraceCounters::default();
        let want: Vec<_> = rays.iter().map(|r| brute.closest_hit(r, &mut c)).collect();
        let hits = want.iter().filter(|h| h.is_some()).count();
        assert!(hits > rays.len() / 4 && hits < rays.len(), "{name}: {hits} of {} rays hit", rays.len());
        let layouts = [LeafLayout::Corners, LeafLayout::Packed];
        for (build, leaves) in [BvhBuild::Sah, BvhBuild::Fast].into_iter().flat_map(|b| layouts.map(|l| (b, l))) {
            for isa in [Isa::Scalar, Isa::Sse, Isa::Avx2] {
                let bvh = Bvh::build_with(&scene, BvhOptions { build, leaves }).with_isa(isa);
                let what = format!("{name} {build:?} {leaves:?} {isa:?}");
                let mut batch = vec![None; rays.len()];
                bvh.closest_hits(&rays, &mut batch, &mut c);
                let (mut any, mut packets) = (vec![false; rays.len()], vec![false; rays.len()]);
                bvh.any_hits(&rays, &mut any, &mut c);
                bvh.any_hits_packets(&rays, &mut packets, &mut c);
                for (i, r) in rays.iter().enumerate() {
                    let single = bvh.closest_hit(r, &mut c);
                    assert!(same_hit(single, want[i]), "{what} ray {i}: {single:?} vs brute force {:?}", want[i]);
                    assert!(same_hit(batch[i], want[i]), "{what} batch ray {i}");
                    assert_eq!(any[i], want[i].is_some(), "{what} any-hit ray {i}");
                    assert_eq!(packets[i], want[i].is_some(), "{what} packet ray {i}");
                    assert_eq!(bvh.any_hit(r, &mut c), want[i].is_some(), "{what} single any-hit ray {i}");
                }
            }
        }
    }
}

#[test]
fn leaf_layouts_take_the_memory_they_report() {
    let sphere_bytes = 16;
    for (name, scene) in scenes() {
        let with = |leaves| Bvh::build_with(&scene, BvhOptions { leaves, ..BvhOptions::default() }).info();
        let (corners, packed) = (with(LeafLayout::Corners), with(LeafLayout::Packed));
        // The same tree; only the leaves differ.
        assert_eq!((corners.nodes, corners.depth), (packed.nodes, packed.depth), "{name}");
        assert_eq!(corners.node_bytes, corners.nodes * 256, "{name}: a node is four cache lines");
        assert_eq!(packed.node_bytes, corners.node_bytes, "{name}");
        let spheres = scene.spheres.len() * sphere_bytes;
        assert_eq!(corners.leaf_bytes, corners.leaves * 192 + spheres, "{name}: a corner leaf is three lines");
        // A packed record is whole lines, two at least (a triangle's nine coordinates and the
        // record's eight words do not fit one) and three at most (twelve vertices).
        let lines = (packed.leaf_bytes - spheres) / 64;
        assert_eq!((packed.leaf_bytes - spheres) % 64, 0, "{name}");
        assert!(lines <= 3 * corners.leaves, "{name}: {lines} lines for {} leaves", corners.leaves);
        if name == "soup" {
            // Disjoint triangles: only leaves of fewer than four triangles fit in two lines.
            assert!(lines > 2 * corners.leaves, "{name}: {lines} lines for {} leaves", corners.leaves);
        }
        if name == "icosphere" {
            // Four neighbouring triangles share vertices: at most eight distinct ones, two
            // lines, where corners take three.
            let ratio = packed.leaf_bytes as f64 / corners.leaf_bytes as f64;
            assert!(ratio < 0.72, "{name}: packed leaves take {ratio:.3} of the corners'");
        }
    }
    // The mesh's own arrays: 12 bytes a position, 12 a triangle, 8 a run of one material
    // (the soup has one).
    let scene = soup();
    let m = &scene.mesh;
    assert_eq!(m.material_ids.runs().count(), 1);
    assert_eq!(m.bytes(), 12 * m.positions.len() + 12 * m.triangles.len() + 8);
}
