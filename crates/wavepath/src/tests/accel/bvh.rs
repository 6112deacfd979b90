//! BVH against brute force, and every SIMD path against the scalar one.

use crate::accel::{BruteForce, Bvh, Intersector, TraceCounters, build};
use crate::cpu::Isa;
use crate::geometry::Ray;
use crate::sampling::Sampler;
use crate::scene::{Mesh, Sphere};
use crate::tests::common;
use crate::tests::common::meshgen::{icosphere, scene_of};
use crate::tests::common::same_hit;
use glam::Vec3;

fn random_ray(s: &mut Sampler, scale: f32) -> Ray {
    let o = Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5) * 4.0 * scale;
    let d = Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5);
    Ray::new(o, d)
}

#[test]
fn icosphere_is_closed() {
    let m = icosphere(6);
    assert_eq!(m.triangles.len(), 20 * 36);
    // Closed 2-manifold: every edge is used by exactly two triangles.
    let mut edges = std::collections::HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
            *edges.entry((a, b)).or_insert(0) += 1;
        }
    }
    assert!(edges.values().all(|&c| c == 2));
    assert_eq!(m.positions.len() + m.triangles.len() - edges.len(), 2, "Euler characteristic");
}

#[test]
fn bvh_equals_brute_force_on_random_rays() {
    let mut mesh = icosphere(12);
    let mut other = icosphere(5);
    for p in &mut other.positions {
        *p = *p * 0.4 + Vec3::new(0.3, 0.2, -0.1);
    }
    mesh.append(other);
    let spheres = vec![
        Sphere { center: Vec3::new(1.5, 0.0, 0.0), radius: 0.3, material: 0 },
        Sphere { center: Vec3::new(-0.2, 0.1, 0.0), radius: 0.25, material: 0 },
    ];
    let scene = scene_of(mesh, spheres);
    let brute = BruteForce::new(&scene);
    let bvh = Bvh::build(&scene).with_isa(Isa::Scalar);
    let info = bvh.info();
    assert!(info.nodes > 0 && info.depth > 1 && info.sah_cost > 0.0);
    let mut s = Sampler::for_sample(7, 0, 0);
    let (mut hits, mut c1, mut c2) = (0, TraceCounters::default(), TraceCounters::default());
    for _ in 0..20_000 {
        let r = random_ray(&mut s, 1.0);
        let (a, b) = (brute.closest_hit(&r, &mut c1), bvh.closest_hit(&r, &mut c2));
        assert!(same_hit(a, b), "{r:?}: brute {a:?} bvh {b:?}");
        assert_eq!(brute.any_hit(&r, &mut c1), a.is_some());
        assert_eq!(bvh.any_hit(&r, &mut c2), a.is_some());
        let short = Ray { tmax: a.map_or(1.0, |h| h.t * 0.999), ..r };
        assert_eq!(brute.any_hit(&short, &mut c1), bvh.any_hit(&short, &mut c2));
        hits += a.is_some() as usize;
    }
    assert!(hits > 2500, "too few hits ({hits}) for the test to mean much");
    assert!(c2.prim_tests < c1.prim_tests / 20, "the BVH should test far fewer primitives");
    assert!(c2.nodes > 0);
}

#[test]
fn every_isa_gives_identical_hits() {
    let scene = scene_of(icosphere(20), vec![Sphere { center: Vec3::new(0.0, 1.2, 0.0), radius: 0.4, material: 0 }]);
    let reference = Bvh::build(&scene).with_isa(Isa::Scalar);
    let mut rays = Vec::new();
    let mut s = Sampler::for_sample(3, 1, 0);
    for _ in 0..20_000 {
        rays.push(random_ray(&mut s, 1.0));
    }
    // Axis-parallel rays with +0 and -0 components.
    for k in 0..200 {
        let x = k as f32 / 100.0 - 1.0;
        rays.push(Ray::new(Vec3::new(x, 0.1, 5.0), Vec3::new(0.0, -0.0, -1.0)));
        rays.push(Ray::new(Vec3::new(x, 5.0, 0.1), Vec3::new(-0.0, -1.0, 0.0)));
        rays.push(Ray::new(Vec3::new(-5.0, x, 0.0), Vec3::new(1.0, 0.0, 0.0)));
    }
    let mut c = TraceCounters::default();
    let want: Vec<_> = rays.iter().map(|r| reference.closest_hit(r, &mut c)).collect();
    for isa in [Isa::Sse, Isa::Avx2] {
        let bvh = Bvh::build(&scene).with_isa(isa);
        let mut batch = vec![None; rays.len()];
        bvh.closest_hits(&rays, &mut batch, &mut c);
        for (i, r) in rays.iter().enumerate() {
            let got = bvh.closest_hit(r, &mut c);
            assert!(same_hit(got, want[i]), "{isa:?} {r:?}: {got:?} vs scalar {:?}", want[i]);
            assert!(same_hit(batch[i], want[i]), "{isa:?} batch {r:?}");
            assert_eq!(bvh.any_hit(r, &mut c), want[i].is_some());
        }
    }
}

#[test]
fn batches_of_every_isa_match_single_rays() {
    let scene = scene_of(icosphere(16), vec![Sphere { center: Vec3::new(0.0, 1.2, 0.0), radius: 0.4, material: 0 }]);
    let reference = Bvh::build(&scene).with_isa(Isa::Scalar);
    let mut s = Sampler::for_sample(11, 2, 0);
    let mut rays: Vec<Ray> = (0..5000).map(|_| random_ray(&mut s, 1.0)).collect();
    // Shadow-like rays that stop short of what they would hit.
    let mut c = TraceCounters::default();
    for k in 0..rays.len() / 2 {
        if let Some(h) = reference.closest_hit(&rays[k], &mut c) {
            rays[k].tmax = h.t * 0.999;
        }
    }
    let want_hit: Vec<_> = rays.iter().map(|r| reference.closest_hit(r, &mut c)).collect();
    let want_any: Vec<_> = rays.iter().map(|r| reference.any_hit(r, &mut c)).collect();
    let occluded = want_any.iter().filter(|&&o| o).count();
    assert!(occluded > 200 && rays.len() - occluded > 200, "{occluded} of {} rays occluded", rays.len());
    for isa in [Isa::Scalar, Isa::Sse, Isa::Avx2] {
        let bvh = Bvh::build(&scene).with_isa(isa);
        let (mut hits, mut occluded) = (vec![None; rays.len()], vec![false; rays.len()]);
        let (mut c1, mut c2) = (TraceCounters::default(), TraceCounters::default());
        bvh.closest_hits(&rays, &mut hits, &mut c1);
        bvh.any_hits(&rays, &mut occluded, &mut c2);
        for i in 0..rays.len() {
            assert!(same_hit(hits[i], want_hit[i]), "{isa:?} ray {i}: {:?} vs {:?}", hits[i], want_hit[i]);
            assert_eq!(occluded[i], want_any[i], "{isa:?} any-hit ray {i}");
        }
        assert_eq!((c1.rays, c2.rays), (rays.len() as u64, rays.len() as u64));
    }
}

#[test]
fn accel_build_switches_between_bvh_and_brute_force() {
    let scene = scene_of(icosphere(4), vec![]);
    let (bvh, info) = build(&scene, &crate::settings::Settings::default());
    let (brute, binfo) = build(&scene, &crate::settings::Settings::default().with(|s| s.accel.use_bvh = false));
    assert!(bvh.name().starts_with("bvh8"));
    assert_eq!(brute.name(), "brute force");
    assert!(info.nodes > 0 && binfo.nodes == 0);
    let r = Ray::new(Vec3::new(0.01, 0.02, 5.0), Vec3::new(0.0, 0.0, -1.0));
    let mut c = TraceCounters::default();
    assert!(same_hit(bvh.closest_hit(&r, &mut c), brute.closest_hit(&r, &mut c)));
}

#[test]
fn tiny_and_empty_scenes() {
    // One triangle (the root is a single leaf) and a scene with only a sphere.
    let mesh = Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        triangles: vec![[0, 1, 2]],
        material_ids: vec![0].into(),
        ..Mesh::default()
    };
    let bvh = Bvh::build(&scene_of(mesh, vec![]));
    let mut c = TraceCounters::default();
    let h = bvh.closest_hit(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.0, 0.0, -1.0)), &mut c).unwrap();
    assert_eq!((h.t, h.prim), (1.0, 0));
    let only_sphere = scene_of(Mesh::default(), vec![Sphere { center: Vec3::ZERO, radius: 1.0, material: 0 }]);
    let bvh = Bvh::build(&only_sphere);
    let h = bvh.closest_hit(&Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::new(0.0, 0.0, -1.0)), &mut c).unwrap();
    assert_eq!((h.t, h.prim), (2.0, 0));
    let none = Bvh::build(&scene_of(Mesh::default(), vec![]));
    assert!(none.closest_hit(&Ray::new(Vec3::ZERO, Vec3::X), &mut c).is_none());
}

#[test]
fn degenerate_triangles_are_never_hit() {
    // Zero-area triangles (collinear and coincident corners) mixed into a real mesh.
    let mut mesh = icosphere(3);
    let base = mesh.positions.len() as u32;
    mesh.positions.extend([Vec3::new(-2.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.0)]);
    mesh.triangles.extend([[base, base + 1, base + 2], [base, base, base]]);
    mesh.material_ids.extend([0, 0]);
    let scene = scene_of(mesh, vec![]);
    let bvh = Bvh::build(&scene);
    let ndeg = scene.mesh.triangles.len() as u32 - 2;
    let mut c = TraceCounters::default();
    let mut s = Sampler::for_sample(1, 1, 1);
    for _ in 0..10_000 {
        let r = random_ray(&mut s, 1.0);
        if let Some(h) = bvh.closest_hit(&r, &mut c) {
            assert!(h.prim < ndeg);
        }
    }
    // A ray along the degenerate segment itself.
    let r = Ray::new(Vec3::new(-3.0, 0.0, 0.0), Vec3::X);
    assert!(bvh.closest_hit(&r, &mut c).is_none_or(|h| h.prim < ndeg));
}

/// Rays from one vertex to another (unnormalised direction, `tmax = 1`) end exactly on a
/// surface, where the box test's entry distance and the triangle's `t` are both rounded:
/// every ISA must still find the same hits (the fused and unfused slab forms round the
/// entry differently, so the comparison with `tmax` needs the same margin as the exit).
#[test]
fn every_isa_agrees_on_rays_ending_on_vertices() {
    let mut scenes = vec![scene_of(icosphere(8), vec![])];
    scenes.extend(common::load_scene("cs184/sky/CBspheres_lambertian.dae"));
    for scene in &scenes {
        let v = &scene.mesh.positions;
        let step = v.len() / 60 + 1;
        // From vertices and from a few points off the surfaces, to vertices.
        let (lo, hi) = scene.bounds().unwrap();
        let mut from: Vec<Vec3> = v.iter().copied().step_by(step).collect();
        from.extend([0.5, 0.37, 0.81].map(|f| lo + (hi - lo) * f));
        let mut rays = Vec::new();
        for &a in &from {
            for &b in v.iter().step_by(step) {
                if a != b {
                    rays.push(Ray { tmax: 1.0, ..Ray::new(a, b - a) });
                }
            }
        }
        let reference = Bvh::build(scene).with_isa(Isa::Scalar);
        let mut c = TraceCounters::default();
        let want: Vec<_> = rays.iter().map(|r| reference.closest_hit(r, &mut c)).collect();
        assert!(want.iter().filter(|h| h.is_some()).count() > rays.len() / 10, "too few hits");
        // Brute force tests in id order: at a tie the lowest id, as the BVH's rule says.
        let brute = BruteForce::new(scene);
        for (r, w) in rays.iter().zip(&want) {
            let b = brute.closest_hit(r, &mut c);
            assert!(same_hit(b, *w), "{r:?}: bvh {w:?}, brute force {b:?}");
        }
        for isa in [Isa::Sse, Isa::Avx2] {
            let bvh = Bvh::build(scene).with_isa(isa);
            let mut batch = vec![None; rays.len()];
            bvh.closest_hits(&rays, &mut batch, &mut c);
            let mut occ = vec![false; rays.len()];
            bvh.any_hits(&rays, &mut occ, &mut c);
            for (i, r) in rays.iter().enumerate() {
                let got = bvh.closest_hit(r, &mut c);
                assert!(same_hit(got, want[i]), "{isa:?} {r:?}: {got:?}, scalar {:?}", want[i]);
                assert!(same_hit(batch[i], want[i]), "{isa:?} batch {r:?}: scalar {:?}", want[i]);
                assert_eq!(occ[i], want[i].is_some(), "{isa:?} any-hit {r:?}");
            }
        }
    }
}
