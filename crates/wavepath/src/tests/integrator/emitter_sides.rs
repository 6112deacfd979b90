//! Which faces of an emitter emit: both for a two-sided material (the CS184 emission BSDF, a
//! double-sided glTF material), only the front (the side its winding points to) for a
//! one-sided one (OBJ `Ke`, a single-sided glTF material). The scene of `integrator::mis`, a
//! small emitter just above a floor, seen from above: the floor is lit only by the emitter's
//! lower face and the camera sees only its upper one, so every answer is exact: pixels that
//! see nothing lit are exactly zero, the emitter's pixels exactly its radiance or zero.

use super::mis::{GAP, H, HALF, W, floor_points, scene};
use crate::film::Accumulator;
use crate::scene::{Camera, Scene};
use crate::tests::common::render;
use glam::Vec3;

/// The mis scene with its emitter turned to face up (`up`) or down, one- or two-sided.
fn emitter(up: bool, two_sided: bool) -> Scene {
    let mut s = scene();
    s.materials[1].two_sided_emission = two_sided;
    if up {
        for t in s.mesh.triangles.iter_mut().skip(2) {
            t.swap(1, 2);
        }
    }
    s
}

/// Whether pixel (x, y) shows only the emitter (its corners and centre all hit it).
fn emitter_pixel(cam: &Camera, x: usize, y: usize) -> bool {
    [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)].iter().all(|&(fx, fy)| {
        let r = cam.generate_ray((x as f32 + fx) / W as f32, (y as f32 + fy) / H as f32);
        let e = r.at((GAP - r.origin.y) / r.dir.y);
        e.x.abs() < HALF && e.z.abs() < HALF
    })
}

/// The mean values of the floor-only and emitter-only pixels of `acc`, and whether every
/// floor-only pixel is exactly zero.
fn floor_and_emitter(scene: &Scene, acc: &Accumulator) -> (f32, f32, bool) {
    let film = acc.to_film();
    let (mut floor, mut nf, mut em, mut ne, mut dark) = (0.0, 0, 0.0, 0, true);
    for y in 0..H {
        for x in 0..W {
            let p = film.pixels[y * W + x];
            if floor_points(&scene.camera, x, y).is_some() {
                floor += p.x;
                nf += 1;
                dark &= p == Vec3::ZERO;
            } else if emitter_pixel(&scene.camera, x, y) {
                em += p.x;
                ne += 1;
            }
        }
    }
    assert!(nf > W * H / 2 && ne >= 4, "{nf} floor pixels, {ne} emitter pixels");
    (floor / nf as f32, em / ne as f32, dark)
}

#[test]
fn one_sided_emitters_light_only_their_front() {
    let s = render::settings(W, H, 2, 16);
    for (what, s) in [
        ("light sampling and MIS", s.clone()),
        ("light sampling alone", s.clone().with(|s| s.paths.mis = false)),
        ("hemisphere probes (-H)", s.clone().with(|s| s.paths.hemisphere = true)),
    ] {
        for recursive in [false, true] {
            let run = |scene: &Scene| {
                let acc = if recursive { render::recursive(scene, &s).0 } else { render::wavefront(scene, &s).0 };
                floor_and_emitter(scene, &acc)
            };
            let what = format!("{what}, {}", if recursive { "recursive" } else { "wavefront" });
            // Facing the floor: the floor is lit as by a two-sided emitter (the same paths
            // and numbers), the camera sees the dark back.
            let (floor_two, top_two, _) = run(&emitter(false, true));
            let (floor_one, top_one, _) = run(&emitter(false, false));
            assert!(floor_two > 0.0 && floor_one == floor_two, "{what}: floor {floor_one} vs two-sided {floor_two}");
            assert_eq!((top_two, top_one), (5.0, 0.0), "{what}: the emitter's upper face");
            // Facing up: nothing reaches the floor, the camera sees the emitting front.
            let (floor_up, top_up, dark) = run(&emitter(true, false));
            assert!(dark && floor_up == 0.0, "{what}: the floor under an upward emitter gets {floor_up}");
            assert_eq!(top_up, 5.0, "{what}");
            // Two-sided, the winding does not matter.
            let (floor_flipped, _, _) = run(&emitter(true, true));
            assert!(floor_flipped > 0.0, "{what}");
        }
    }
}
