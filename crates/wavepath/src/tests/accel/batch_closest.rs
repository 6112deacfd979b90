//! The batch closest-hit path for incoherent rays (`Intersector::closest_hits`: root-box
//! admission and set-up a group at a time, then the node loop that pushes every hit child)
//! against the scalar single-ray `closest_hit`, for every instruction set, one ray or three
//! in flight: rays
//! of mixed kinds (diffuse-like bounces from the surface, misses, rays that never enter the
//! root box, dead rays, vertex chords with tied hits) in batches of every length 1..=70 at
//! every start, so a ray dropped, traced twice or given another ray's state (stack, set-up,
//! closest hit) changes some batch's answer.

use crate::accel::{Bvh, Intersector, TraceCounters};
use crate::cpu::Isa;
use crate::geometry::{Hit, Ray};
use crate::sampling::Sampler;
use crate::scene::{Scene, Sphere};
use crate::tests::common;
use crate::tests::common::meshgen::{icosphere, scene_of};
use glam::Vec3;

/// A shuffled mix: bounces off the surface into random directions (long and short
/// traversals), rays from outside aimed at or away from the scene, rays far outside that
/// miss the root box, chords from vertex to vertex ending on the target (ties at `t = 1`),
/// and dead rays (zero direction, empty range, NaN origin).
fn mixed_rays(scene: &Scene, n: usize) -> Vec<Ray> {
    let tris = scene.mesh.triangle_count();
    let (lo, hi) = scene.bounds().unwrap();
    let (mid, size) = (0.5 * (lo + hi), (hi - lo).max_element());
    let mut s = Sampler::for_sample(7, 3, 1);
    let unit =
        |s: &mut Sampler| Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5).normalize_or(Vec3::X);
    let mut rays = Vec::with_capacity(n);
    for k in 0..n {
        let t = (s.next_f32() * tris as f32) as usize % tris;
        let [a, b, c] = scene.mesh.corners(t);
        let ray = match k % 7 {
            0..=2 => {
                let (u, v) = (0.5 * s.next_f32(), 0.5 * s.next_f32());
                let d = unit(&mut s);
                Ray { tmin: 1e-4 * size, ..Ray::new(a + u * (b - a) + v * (c - a), d) }
            }
            3 => {
                let o = mid + 2.0 * size * unit(&mut s);
                let d = if s.next_f32() < 0.7 { (a + b + c) / 3.0 - o } else { o - mid };
                Ray::new(o, d)
            }
            4 => {
                let o = mid + 5.0 * size * unit(&mut s);
                Ray::new(o, unit(&mut s).cross(o - mid))
            }
            5 => {
                let [d, _, _] = scene.mesh.corners((t + 1 + k) % tris);
                Ray { tmax: 1.0, ..Ray::new(a, d - a) }
            }
            _ => {
                let r = Ray::new(a, unit(&mut s));
                [
                    Ray { dir: Vec3::ZERO, ..r },
                    Ray { tmin: 2.0, tmax: 1.0, ..r },
                    Ray { origin: Vec3::new(f32::NAN, a.y, a.z), ..r },
                    r,
                ][k / 7 % 4]
            }
        };
        rays.push(ray);
    }
    rays
}

fn check(scene: &Scene, what: &str) {
    let rays = mixed_rays(scene, 700);
    let scalar = Bvh::build(scene).with_isa(Isa::Scalar);
    let mut c = TraceCounters::default();
    let want: Vec<_> = rays.iter().map(|r| scalar.closest_hit(r, &mut c)).collect();
    let hits = want.iter().filter(|h| h.is_some()).count();
    assert!(hits > rays.len() / 4 && hits < rays.len() * 3 / 4, "{what}: {hits} hits of {}", rays.len());
    // Each instruction set, and each way of tracing single rays (one at a time without
    // prefetching for trees that fit the caches, three in flight with it for larger ones).
    let modes = [Isa::Scalar, Isa::Sse, Isa::Avx2].into_iter().flat_map(|i| [(i, true), (i, false)]);
    for (isa, cached) in modes {
        let bvh = Bvh::build(scene).with_isa(isa).assume_cached(cached);
        // Per ray alone: its node count, for the totals of the batches below.
        let nodes: Vec<u64> = rays
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let (mut got, mut c) = ([None], TraceCounters::default());
                bvh.closest_hits(std::slice::from_ref(r), &mut got, &mut c);
                assert!(
                    common::same_hit(got[0], want[i]),
                    "{what} {isa:?} cached {cached} ray {i} alone {r:?}: {:?}, scalar {:?}",
                    got[0],
                    want[i]
                );
                c.nodes
            })
            .collect();
        for len in 1..=70 {
            let mut start = len % 5;
            while start < rays.len() {
                let end = (start + len).min(rays.len());
                let (mut got, mut c) =
                    (vec![Some(Hit { t: -1.0, prim: 7, u: 0.0, v: 0.0 }); end - start], TraceCounters::default());
                bvh.closest_hits(&rays[start..end], &mut got, &mut c);
                for (k, g) in got.iter().enumerate() {
                    let i = start + k;
                    assert!(
                        common::same_hit(*g, want[i]),
                        "{what} {isa:?} cached {cached} ray {i} in {start}..{end}: {g:?}, scalar {:?}",
                        want[i]
                    );
                }
                assert_eq!(c.rays, (end - start) as u64, "{what} {isa:?} cached {cached}: rays of {start}..{end}");
                assert_eq!(
                    c.nodes,
                    nodes[start..end].iter().sum::<u64>(),
                    "{what} {isa:?} cached {cached}: nodes of {start}..{end}"
                );
                start = end + len % 3;
            }
        }
    }
}

#[test]
fn incoherent_batches_match_single_rays_on_an_icosphere_with_spheres() {
    let spheres = vec![
        Sphere { center: Vec3::new(0.4, 0.1, 0.2), radius: 0.3, material: 0 },
        Sphere { center: Vec3::new(-1.3, 0.0, 0.0), radius: 0.5, material: 0 },
    ];
    check(&scene_of(icosphere(6), spheres), "icosphere");
}

#[test]
fn incoherent_batches_match_single_rays_on_the_bunny() {
    let Some(scene) = common::load_scene("cs184/sky/CBbunny.dae") else { return };
    check(&scene, "CBbunny");
}
