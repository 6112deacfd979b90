//! Closest-hit packets (`Intersector::closest_hits_packets` traces runs of coherent rays together)
//! against the scalar single-ray `closest_hit`, for every instruction set: camera rays in
//! 4x4 pixel blocks and per-pixel jittered samples (the coherent case packets are for), and
//! hard rays in coherent runs: ending exactly on shared vertices and edges, axis-parallel
//! (zero and -0 direction components), starting on the surface, plus incoherent rays with
//! mixed octants, traced in whole batches, shifted and in short slices.

use crate::common;
use crate::common::meshgen::{icosphere, scene_of};
use glam::Vec3;
use wavepath::accel::{Bvh, Intersector, Isa, TraceCounters};
use wavepath::ray::Ray;
use wavepath::sampling::Sampler;
use wavepath::scene::Scene;

fn octant(d: Vec3) -> u32 {
    d.x.is_sign_negative() as u32 | (d.y.is_sign_negative() as u32) << 1 | (d.z.is_sign_negative() as u32) << 2
}

/// Fraction of rays that sit in a run of at least four consecutive rays of one octant (the
/// runs the batch may trace as packets): a property of the input, so the test knows it
/// exercises packets at all.
fn coherent_fraction(rays: &[Ray]) -> f64 {
    let (mut covered, mut i) = (0, 0);
    while i < rays.len() {
        let o = octant(rays[i].dir);
        let mut n = 1;
        while i + n < rays.len() && octant(rays[i + n].dir) == o {
            n += 1;
        }
        if n >= 4 {
            covered += n;
        }
        i += n;
    }
    covered as f64 / rays.len().max(1) as f64
}

/// Camera rays of a `w` x `h` image in 4x4 pixel blocks (the peers' primary order), then
/// `spp` jittered samples per pixel, pixel by pixel (the wavefront's camera queue order).
fn camera_rays(scene: &Scene, w: usize, h: usize, spp: usize) -> Vec<Ray> {
    let cam = &scene.camera;
    let mut rays = Vec::new();
    for by in (0..h).step_by(4) {
        for bx in (0..w).step_by(4) {
            for y in by..(by + 4).min(h) {
                for x in bx..(bx + 4).min(w) {
                    rays.push(cam.generate_ray((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32));
                }
            }
        }
    }
    let mut s = Sampler::for_sample(11, 5, 0);
    for y in 0..h {
        for x in 0..w {
            for _ in 0..spp {
                let (u, v) = (s.next_f32(), s.next_f32());
                rays.push(cam.generate_ray((x as f32 + u) / w as f32, (y as f32 + v) / h as f32));
            }
        }
    }
    rays
}

/// Runs of eight rays from one origin toward one neighbourhood (so they mostly share an
/// octant) that end exactly on corners and edge midpoints, start on the surface, run
/// axis-parallel, or stop just short; then the same rays shuffled (mixed octants).
fn hard_rays(scene: &Scene, runs: usize) -> Vec<Ray> {
    let tris = scene.mesh.triangle_count();
    let mut s = Sampler::for_sample(3, 9, 0);
    let (lo, hi) = scene.bounds().unwrap();
    let mut rays = Vec::new();
    for run in 0..runs {
        let t = (s.next_f32() * tris as f32) as usize % tris;
        let [a, b, c] = scene.mesh.corners(t);
        let [d, e, _] = scene.mesh.corners((t + 1) % tris);
        let targets = [a, b, c, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a), d, 0.5 * (d + e)];
        let off = lo + (hi - lo) * Vec3::new(s.next_f32(), s.next_f32(), s.next_f32());
        match run % 5 {
            // From a point off the surface to corners and edges, ending exactly there.
            0 => rays.extend(targets.map(|p| Ray { tmax: 1.0, ..Ray::new(off, p - off) })),
            // The same, running on (through the shared vertex or edge).
            1 => rays.extend(targets.map(|p| Ray::new(off, (p - off).normalize()))),
            // From a vertex of the mesh (on the surface) toward the neighbourhood.
            2 => {
                let o = scene.mesh.corners((t + 7) % tris)[run % 3];
                rays.extend(targets.map(|p| Ray { tmax: 1.0, ..Ray::new(o, p - o) }));
            }
            // Axis-parallel rays from a small grid of origins (zero and -0 components).
            3 => {
                let axis = [Vec3::X, Vec3::NEG_Y, Vec3::Z, Vec3::new(-0.0, -1.0, 0.0)][run / 5 % 4];
                let q = (a + b + c) / 3.0 - axis * (hi - lo).max_element();
                for k in 0..8 {
                    let jitter = Vec3::new(k as f32 % 3.0, k as f32 / 3.0, 0.0) * 1e-3 * (hi - lo);
                    let side = if axis.x != 0.0 { Vec3::new(0.0, jitter.x, jitter.y) } else { jitter };
                    rays.push(Ray::new(q + side, axis));
                }
            }
            // Starting on a triangle (tmin 0: self-intersection decided by the exact test),
            // into one octant, some with tmin > 0 or a short range.
            _ => {
                let n = (b - a).cross(c - a).normalize_or_zero();
                for k in 0..8 {
                    let (u, v) = (s.next_f32() * 0.5, s.next_f32() * 0.5);
                    let o = a + u * (b - a) + v * (c - a);
                    let dir = n + 0.2 * Vec3::new(s.next_f32(), s.next_f32(), s.next_f32());
                    let dir = if k % 2 == 0 { dir } else { -dir };
                    let (tmin, tmax) = [(0.0, f32::INFINITY), (1e-4, 10.0), (0.0, 1e-3), (0.0, 1.0)][k % 4];
                    rays.push(Ray { origin: o, dir, tmin, tmax });
                }
            }
        }
    }
    let coherent = rays.len();
    for i in 0..coherent {
        let j = (i * 7919 + 13) % coherent;
        rays.push(rays[j]);
    }
    // Degenerate rays inside a coherent run: zero direction, empty range, NaN origin.
    let r = rays[0];
    rays.splice(
        3..3,
        [
            Ray { dir: Vec3::ZERO, ..r },
            Ray { tmin: 2.0, tmax: 1.0, ..r },
            Ray { origin: Vec3::new(f32::NAN, r.origin.y, r.origin.z), ..r },
        ],
    );
    rays
}

/// Chords from vertex to vertex ending exactly on the target (`tmax = 1`): from inside a
/// closed mesh the first hit is the target vertex itself, shared by several triangles at
/// the same `t` (the tie the lower id must win in every visiting order). Each origin aims at
/// runs of eight vertices nearest to one another (a coherent run that forms a packet when
/// seen from far enough), and the same targets in another order.
fn vertex_rays(scene: &Scene) -> Vec<Ray> {
    let v = &scene.mesh.positions;
    let step = v.len() / 60 + 1;
    let clusters: Vec<Vec<Vec3>> = v
        .iter()
        .step_by(step)
        .map(|&b| {
            let mut near: Vec<Vec3> = v.clone();
            near.sort_by(|p, q| (*p - b).length_squared().total_cmp(&(*q - b).length_squared()));
            near.dedup();
            near.truncate(8);
            near
        })
        .collect();
    let mut rays = Vec::new();
    for &a in v.iter().step_by(step) {
        for cluster in &clusters {
            for &b in cluster {
                if a != b {
                    rays.push(Ray { tmax: 1.0, ..Ray::new(a, b - a) });
                }
            }
        }
    }
    rays
}

/// Every instruction set's batch (packets where runs allow) equals the scalar single ray.
fn check(scene: &Scene, rays: &[Ray], what: &str) {
    let scalar = Bvh::build(scene).with_isa(Isa::Scalar);
    let mut c = TraceCounters::default();
    let want: Vec<_> = rays.iter().map(|r| scalar.closest_hit(r, &mut c)).collect();
    let hits = want.iter().filter(|h| h.is_some()).count();
    assert!(hits > rays.len() / 10 && hits < rays.len(), "{what}: {hits} hits of {}", rays.len());
    for isa in [Isa::Scalar, Isa::Sse, Isa::Avx2, Isa::Avx512] {
        let bvh = Bvh::build(scene).with_isa(isa);
        let mut got = vec![None; rays.len()];
        let mut c = TraceCounters::default();
        bvh.closest_hits_packets(rays, &mut got, &mut c);
        assert_eq!(c.rays, rays.len() as u64, "{what} {isa:?}");
        for (i, r) in rays.iter().enumerate() {
            assert!(
                common::same_hit(got[i], want[i]),
                "{what} {isa:?} ray {i} {r:?}: {:?}, scalar {:?}",
                got[i],
                want[i]
            );
        }
        // Other groupings: shifted by three, and slices of 1..=9 rays (short packets).
        let mut got = vec![None; rays.len() - 3];
        bvh.closest_hits_packets(&rays[3..], &mut got, &mut c);
        assert!(got.iter().zip(&want[3..]).all(|(a, b)| common::same_hit(*a, *b)), "{what} {isa:?} shifted");
        let (mut i, mut len) = (0, 1);
        while i < rays.len() {
            let n = len.min(rays.len() - i);
            let mut got = vec![None; n];
            bvh.closest_hits_packets(&rays[i..i + n], &mut got, &mut c);
            for k in 0..n {
                assert!(
                    common::same_hit(got[k], want[i + k]),
                    "{what} {isa:?} slice {i}+{k} of {n}: {:?}",
                    rays[i + k]
                );
            }
            i += n;
            len = len % 9 + 1;
        }
    }
}

fn check_scene(scene: &Scene, what: &str) {
    let cam = camera_rays(scene, 40, 28, 8);
    assert!(coherent_fraction(&cam) > 0.9, "{what}: camera rays are not coherent");
    check(scene, &cam, &format!("{what} camera"));
    let hard = hard_rays(scene, 400);
    let f = coherent_fraction(&hard);
    assert!(f > 0.15, "{what}: too few coherent hard rays ({f})");
    check(scene, &hard, &format!("{what} hard"));
    check(scene, &vertex_rays(scene), &format!("{what} vertices"));
}

#[test]
fn closest_packets_match_single_rays_on_the_bunny() {
    let Some(scene) = common::load_scene("cs184/sky/CBbunny.dae") else { return };
    check_scene(&scene, "CBbunny");
}

#[test]
fn closest_packets_match_single_rays_on_the_cornell_box() {
    let Some(scene) = common::load_scene("cs184/sky/CBspheres_lambertian.dae") else { return };
    check_scene(&scene, "CBspheres_lambertian");
}

/// A closed icosphere seen from outside: every camera ray through it crosses shared edges
/// and vertices somewhere, and hard rays end exactly on them.
#[test]
fn closest_packets_match_single_rays_on_an_icosphere() {
    let mut scene = scene_of(icosphere(8), vec![]);
    scene.camera = wavepath::scene::Camera::look_at(Vec3::new(0.3, 0.4, 3.0), Vec3::ZERO, Vec3::Y, 40.0, 1.4);
    check_scene(&scene, "icosphere");
}
