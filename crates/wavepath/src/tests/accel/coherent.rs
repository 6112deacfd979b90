//! Coherent runs of rays (one origin, nearly parallel directions: a camera's rays, which the
//! batch closest-hit path traces as packets) against the scalar single-ray `closest_hit`,
//! for every instruction set, bit for bit: pixel blocks and jittered samples of a camera,
//! rays aimed exactly at vertices and edge midpoints (ties), axis-parallel rays onto a grid
//! of shared edges, rays lying in the grid's plane, short and offset ranges.

use crate::accel::{Bvh, Intersector, TraceCounters};
use crate::cpu::Isa;
use crate::geometry::{Hit, Ray};
use crate::sampling::Sampler;
use crate::scene::{Scene, Sphere};
use crate::tests::common;
use crate::tests::common::meshgen::{icosphere, quad, scene_of};
use glam::Vec3;

/// A fine sphere of shared vertices, a sphere primitive and a 12 x 12 grid of unit quads in
/// the plane y = -1 (axis-aligned boxes, shared edges and corners).
fn scene() -> Scene {
    let mut mesh = icosphere(12);
    for i in 0..12 {
        for j in 0..12 {
            let (x, z) = (i as f32 - 6.0, j as f32 - 6.0);
            let c = [(x, z), (x + 1.0, z), (x + 1.0, z + 1.0), (x, z + 1.0)].map(|(x, z)| Vec3::new(x, -1.0, z));
            quad(&mut mesh, c, 0);
        }
    }
    scene_of(mesh, vec![Sphere { center: Vec3::new(1.5, -0.4, 0.5), radius: 0.35, material: 0 }])
}

/// Rays of a pinhole camera at `eye` looking at `at`, `w` x `h` pixels with a vertical field
/// of view of `fov` degrees, in 4 x 4 pixel blocks (pixels row-major inside a block), `spp`
/// jittered samples per pixel one after another.
fn camera(eye: Vec3, at: Vec3, (w, h): (usize, usize), fov: f32, spp: usize, s: &mut Sampler) -> Vec<Ray> {
    let fwd = (at - eye).normalize();
    let right = fwd.cross(Vec3::Y).normalize();
    let up = right.cross(fwd);
    let half = (fov.to_radians() * 0.5).tan();
    let mut rays = Vec::new();
    for by in (0..h).step_by(4) {
        for bx in (0..w).step_by(4) {
            for y in by..(by + 4).min(h) {
                for x in bx..(bx + 4).min(w) {
                    for k in 0..spp {
                        let (jx, jy) = if spp == 1 { (0.5, 0.5) } else { (s.next_f32(), s.next_f32()) };
                        let u = (2.0 * (x as f32 + jx) / w as f32 - 1.0) * half * w as f32 / h as f32;
                        let v = (1.0 - 2.0 * (y as f32 + jy) / h as f32) * half;
                        let d = fwd + u * right + v * up;
                        rays.push(Ray::new(eye, if k % 3 == 2 { d } else { d.normalize() }));
                    }
                }
            }
        }
    }
    rays
}

/// Runs of 16 rays from one far point aimed exactly at neighbouring vertices and edge
/// midpoints (unnormalised, `tmax` 1 for some: ending exactly on the surface), and straight
/// down onto the grid's corners and edges, nearly axis-parallel, and lying in its plane.
fn hard_rays(scene: &Scene) -> Vec<Ray> {
    let mut rays = Vec::new();
    let eye = Vec3::new(0.7, 2.5, 40.0);
    let tris = scene.mesh.triangle_count();
    for start in (0..tris - 16).step_by(97) {
        for k in 0..16 {
            let [a, b, _] = scene.mesh.corners(start + k);
            let target = if k % 2 == 0 { a } else { 0.5 * (a + b) };
            let tmax = if k % 3 == 0 { 1.0 } else { f32::INFINITY };
            rays.push(Ray { tmax, ..Ray::new(eye, target - eye) });
        }
    }
    // Straight down from above grid corners and edge points (ties between the triangles that
    // share them); tiny tilts give reciprocals of +-f32::MAX and huge but finite ones.
    for i in 0..4 {
        let o = Vec3::new(i as f32 - 2.0, 3.0, 1.0 - i as f32);
        for k in 0..16 {
            let tilt = [0.0, 1e-30, -1e-30, 1e-8, -1e-8, 1e-4, 0.0, -0.0][k % 8];
            let d = if k < 8 { Vec3::new(tilt, -1.0, 0.0) } else { Vec3::new(0.0, -4.0, tilt) };
            rays.push(Ray::new(o, d));
        }
    }
    // In the grid's plane along an axis, through its shared edges (grazing), and just above.
    for i in 0..2 {
        let o = Vec3::new(i as f32 - 3.0, -1.0 + i as f32 * 1e-6, 8.0);
        for k in 0..16 {
            rays.push(Ray::new(o, Vec3::new(k as f32 * 1e-3, 0.0, -1.0)));
        }
    }
    // A packet whose members start and end at different distances.
    let base = camera(Vec3::new(0.0, 0.5, 6.0), Vec3::ZERO, (4, 4), 10.0, 1, &mut Sampler::for_sample(1, 1, 1));
    for (k, r) in base.iter().enumerate() {
        rays.push(Ray { tmin: [0.0, 5.0, 0.1, 5.4][k % 4], tmax: [f32::INFINITY, 5.3, 6.0, 9.0][k / 4], ..*r });
    }
    rays
}

/// `fewer`: how many times fewer node visits the batches take at least than the rays alone.
fn check(scene: &Scene, rays: &[Ray], what: &str, fewer: u64) {
    let scalar = Bvh::build(scene).with_isa(Isa::Scalar);
    let mut c = TraceCounters::default();
    let want: Vec<_> = rays.iter().map(|r| scalar.closest_hit(r, &mut c)).collect();
    let hits = want.iter().filter(|h| h.is_some()).count();
    assert!(hits > rays.len() / 4, "{what}: {hits} hits of {}", rays.len());
    for isa in [Isa::Scalar, Isa::Sse, Isa::Avx2] {
        let bvh = Bvh::build(scene).with_isa(isa);
        let alone: u64 = rays
            .iter()
            .map(|r| {
                let (mut got, mut c) = ([None], TraceCounters::default());
                bvh.closest_hits(std::slice::from_ref(r), &mut got, &mut c);
                c.nodes
            })
            .sum();
        for len in [rays.len(), 16, 37, 64, 5] {
            let mut nodes = 0;
            for (k, (rs, ws)) in rays.chunks(len).zip(want.chunks(len)).enumerate() {
                let mut got = vec![Some(Hit { t: -1.0, prim: 7, u: 0.0, v: 0.0 }); rs.len()];
                let mut c = TraceCounters::default();
                bvh.closest_hits(rs, &mut got, &mut c);
                for (i, (g, w)) in got.iter().zip(ws).enumerate() {
                    let r = &rs[i];
                    assert!(
                        common::same_hit(*g, *w),
                        "{what} {isa:?} ray {} of {r:?}: {g:?}, scalar {w:?}",
                        k * len + i
                    );
                }
                assert_eq!(c.rays, rs.len() as u64, "{what} {isa:?} ray count");
                nodes += c.nodes;
            }
            // The runs were traced as packets: one node visit serves a whole run.
            assert!(
                len < 16 || fewer * nodes < alone,
                "{what} {isa:?} in batches of {len}: {nodes} node visits, alone {alone}"
            );
        }
    }
}

#[test]
fn camera_packets_match_single_rays() {
    let scene = scene();
    let mut s = Sampler::for_sample(3, 5, 0);
    let mut rays = camera(Vec3::new(0.4, 1.2, 5.0), Vec3::new(0.0, -0.3, 0.0), (64, 48), 12.0, 1, &mut s);
    rays.extend(camera(Vec3::new(-3.0, 0.5, 4.0), Vec3::ZERO, (16, 12), 8.0, 8, &mut s));
    check(&scene, &rays, "camera", 3);
}

#[test]
fn hard_coherent_runs_match_single_rays() {
    let scene = scene();
    check(&scene, &hard_rays(&scene), "hard", 2);
}

/// Batches mixing lone rays (other origins, as extension rays) with coherent runs: a group
/// whose first two rays start no packet sends the rest of its rays alone, packets or not.
/// Every ray's hit is still its single-ray hit, and the runs that lead a group are still
/// traced as packets.
#[test]
fn mixed_batches_match_single_rays() {
    let scene = scene();
    let mut s = Sampler::for_sample(4, 1, 0);
    let cam = camera(Vec3::new(0.4, 1.2, 5.0), Vec3::new(0.0, -0.3, 0.0), (32, 24), 12.0, 2, &mut s);
    let mut rays = Vec::new();
    for (i, run) in cam.chunks(30).enumerate() {
        for _ in 0..i % 3 {
            let o = Vec3::new(s.next_f32() * 8.0 - 4.0, 2.0, s.next_f32() * 8.0 - 4.0);
            rays.push(Ray::new(o, Vec3::new(s.next_f32() - 0.5, -1.0, s.next_f32() - 0.5)));
        }
        rays.extend_from_slice(run);
    }
    check(&scene, &rays, "mixed", 1);
}

/// Triangles far smaller than the spacing of the rays (a scanned mesh of tens of millions
/// seen at a screen's resolution): a packet's frustum then spans many subtrees between its
/// rays that none of them enters, and the packet must not visit them. Its rays' own tests
/// decide every child, so the packets take fewer node visits than their rays alone.
#[test]
fn packets_over_triangles_smaller_than_their_spacing_visit_only_what_their_rays_enter() {
    let mut mesh = crate::scene::Mesh::default();
    let (n, half) = (250, 0.25);
    for i in 0..n {
        for j in 0..n {
            let e = 2.0 * half / n as f32;
            let (x, z) = (i as f32 * e - half, j as f32 * e - half);
            let c = [(x, z), (x + e, z), (x + e, z + e), (x, z + e)].map(|(x, z)| Vec3::new(x, 0.0, z));
            quad(&mut mesh, c, 0);
        }
    }
    let scene = scene_of(mesh, Vec::new());
    // 16 x 12 pixels half a degree apart (a 4 x 4 block is one packet) over the grid: about
    // ten quads between neighbouring rays.
    let rays = camera(Vec3::new(0.0, 2.0, 0.6), Vec3::ZERO, (16, 12), 6.0, 1, &mut Sampler::for_sample(2, 2, 0));
    check(&scene, &rays, "fine", 1);
}
