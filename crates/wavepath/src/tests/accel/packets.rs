//! Shadow-ray packets (`Intersector::any_hits_packets`) against single-ray `any_hit` on a
//! real mesh, for every instruction set: random and hard rays (sharing an origin, as the
//! wavefront's shadow queue holds them), including rays through vertices and along edges,
//! grazing, axis-parallel, starting on the surface and ending exactly on a triangle.

use crate::accel::{BruteForce, Bvh, Intersector, TraceCounters};
use crate::cpu::Isa;
use crate::geometry::Ray;
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::tests::common;
use glam::Vec3;

/// A point on triangle `i` at barycentric (u, v).
fn on_triangle(scene: &Scene, i: usize, u: f32, v: f32) -> Vec3 {
    let [a, b, c] = scene.mesh.corners(i);
    let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
    a + u * (b - a) + v * (c - a)
}

/// Queue-like rays: runs of 1..=9 rays with one origin (a run longer than a packet is split),
/// aimed at random points, corners, edges, a small "light" patch (some runs all of them),
/// along edges and axes.
fn shadow_like_rays(scene: &Scene, n_origins: usize) -> Vec<Ray> {
    let tris = scene.mesh.triangle_count();
    let mut s = Sampler::for_sample(7, 3, 0);
    let (lo, hi) =
        scene.mesh.positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), &p| (l.min(p), h.max(p)));
    let light = lo + (hi - lo) * Vec3::new(0.45, 0.98, 0.45);
    let mut rays = Vec::new();
    for o in 0..n_origins {
        let pick = |s: &mut Sampler| (s.next_f32() * tris as f32) as usize % tris;
        let t0 = pick(&mut s);
        let origin = match o % 4 {
            // On the surface (the hardest: self-intersection is decided by the exact test).
            0 => on_triangle(scene, t0, s.next_f32(), s.next_f32()),
            // A corner of the mesh.
            1 => scene.mesh.corners(t0)[o % 3],
            // Off the surface, anywhere in the bounds.
            _ => lo + (hi - lo) * Vec3::new(s.next_f32(), s.next_f32(), s.next_f32()),
        };
        let count = 1 + (s.next_f32() * 9.0) as usize;
        // Every fifth run aims all its rays at the light patch, as the shadow rays of one
        // point do (one set of shear axes, more rays than triangles in most leaves).
        let at_light = o % 5 == 3;
        for k in 0..count {
            let t1 = pick(&mut s);
            let [a, b, c] = scene.mesh.corners(t1);
            let target = match if at_light { 0 } else { (o + k) % 7 } {
                0 => light + Vec3::new(s.next_f32() - 0.5, 0.0, s.next_f32() - 0.5) * 0.1 * (hi - lo),
                1 => a,
                2 => 0.5 * (b + c),
                3 => on_triangle(scene, t1, s.next_f32(), s.next_f32()),
                4 => origin + (b - a),
                5 => origin + [Vec3::X, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_X][k % 4],
                _ => origin + Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5),
            };
            let d = target - origin;
            // Unnormalised direction with tmax = 1 ends exactly at the target; some rays
            // stop a little short, some run on, some start past 0.
            let (dir, tmin, tmax) = match k % 4 {
                0 => (d, 0.0, 1.0),
                1 => (d, 0.0, 0.999),
                2 => (d.normalize_or_zero(), 0.0, f32::INFINITY),
                _ => (d, 1e-3, 2.0),
            };
            rays.push(Ray { origin, dir, tmin, tmax });
        }
    }
    // Degenerate rays inside a run: zero direction, NaN origin component, empty range.
    let o = rays[0].origin;
    rays.extend([
        Ray { origin: o, dir: Vec3::ZERO, tmin: 0.0, tmax: 1.0 },
        Ray { origin: o, dir: Vec3::Y, tmin: 2.0, tmax: 1.0 },
        Ray { origin: o, dir: Vec3::new(-0.0, 1.0, 0.0), tmin: 0.0, tmax: f32::INFINITY },
        Ray { origin: Vec3::new(f32::NAN, 0.0, 0.0), dir: Vec3::X, tmin: 0.0, tmax: 1.0 },
    ]);
    rays
}

/// Packets give each ray exactly its single-ray answer, and every instruction set gives the
/// scalar path's answer (also on rays whose range ends exactly on a surface: see
/// docs/decisions.md, "Ties at shared vertices").
fn check(scene: &Scene, what: &str) {
    let rays = shadow_like_rays(scene, 3000);
    let scalar = Bvh::build(scene).with_isa(Isa::Scalar);
    let mut c = TraceCounters::default();
    let want: Vec<bool> = rays.iter().map(|r| scalar.any_hit(r, &mut c)).collect();
    let occluded = want.iter().filter(|&&o| o).count();
    assert!(
        occluded > rays.len() / 10 && rays.len() - occluded > rays.len() / 10,
        "{what}: {occluded} of {}",
        rays.len()
    );
    for isa in [Isa::Scalar, Isa::Sse, Isa::Avx2] {
        let bvh = Bvh::build(scene).with_isa(isa);
        for (i, r) in rays.iter().enumerate() {
            assert_eq!(bvh.any_hit(r, &mut c), want[i], "{what} {isa:?} single ray {i}: {r:?}");
        }
        let mut got = vec![false; rays.len()];
        let mut c = TraceCounters::default();
        bvh.any_hits_packets(&rays, &mut got, &mut c);
        assert_eq!(c.rays, rays.len() as u64);
        for i in 0..rays.len() {
            assert_eq!(got[i], want[i], "{what} {isa:?} ray {i}: {:?}", rays[i]);
        }
        // Packets that start mid-run (another grouping of the same rays) agree too.
        let mut got = vec![false; rays.len() - 3];
        bvh.any_hits_packets(&rays[3..], &mut got, &mut c);
        assert!(got.iter().zip(&want[3..]).all(|(a, b)| a == b), "{what} {isa:?} shifted");
    }
}

#[test]
fn packets_match_single_rays_on_the_bunny() {
    let Some(scene) = common::load_scene("cs184/sky/CBbunny.dae") else { return };
    check(&scene, "CBbunny");
}

#[test]
fn packets_match_single_rays_on_the_cornell_box() {
    let Some(scene) = common::load_scene("cs184/sky/CBspheres_lambertian.dae") else { return };
    check(&scene, "CBspheres_lambertian");
}

/// Whether `r` is occluded, by a plain f64 Moeller-Trumbore test of every triangle and a
/// quadratic for every sphere; `None` when a hit lies within a hair of an edge or of the
/// ray's ends, where f32 and f64 may honestly disagree.
fn occluded_f64(scene: &Scene, r: &Ray) -> Option<bool> {
    let (o, d) = (r.origin.as_dvec3(), r.dir.as_dvec3());
    let (t0, t1) = (r.tmin as f64, r.tmax as f64);
    let scale = 1e-5 * t1.clamp(1.0, 1e6);
    let mut hit = false;
    for i in 0..scene.mesh.triangle_count() {
        let Some((t, u, v)) = common::triangle_f64(o, d, scene.mesh.corners(i).map(|p| p.as_dvec3())) else {
            continue;
        };
        let near_edge = [u, v, 1.0 - u - v].iter().any(|w| w.abs() < 1e-6);
        let near_end = (t - t0).abs() < scale || (t - t1).abs() < scale;
        let inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > t0 && t < t1;
        if (near_edge || near_end) && (u >= -1e-6 && v >= -1e-6 && u + v <= 1.0 + 1e-6) {
            return None;
        }
        hit |= inside;
    }
    for sp in &scene.spheres {
        let oc = o - sp.center.as_dvec3();
        let (a, b, c) = (d.dot(d), oc.dot(d), oc.dot(oc) - (sp.radius as f64).powi(2));
        let disc = b * b - a * c;
        if disc < 0.0 {
            continue;
        }
        for t in [(-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a] {
            if (t - t0).abs() < scale || (t - t1).abs() < scale {
                return None;
            }
            hit |= t > t0 && t < t1;
        }
    }
    Some(hit)
}

/// Brute force (which has no packets of its own) against an independent f64 reference on
/// the same hard rays: every unambiguous ray gets the reference's answer, and both answers
/// occur.
#[test]
fn brute_force_packets_match_an_f64_reference() {
    let Some(scene) = common::load_scene("cs184/sky/CBspheres_lambertian.dae") else { return };
    let rays = shadow_like_rays(&scene, 300);
    let brute = BruteForce::new(&scene);
    let mut c = TraceCounters::default();
    let mut got = vec![false; rays.len()];
    brute.any_hits_packets(&rays, &mut got, &mut c);
    let (mut checked, mut blocked) = (0, 0);
    for (r, g) in rays.iter().zip(&got) {
        if let Some(want) = occluded_f64(&scene, r) {
            assert_eq!(*g, want, "{r:?}");
            checked += 1;
            blocked += want as usize;
        }
    }
    // Most of these rays start on a surface or end on a vertex or an edge, on purpose; the
    // rest still gives hundreds of clear answers of both kinds.
    assert!(
        checked >= 300 && blocked >= 50 && checked - blocked >= 50,
        "{} rays: {checked} checked, {blocked} blocked",
        rays.len()
    );
}
