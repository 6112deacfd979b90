//! Multiple importance sampling at diffuse surfaces: a small emitter hanging just above a
//! floor (the OBJ Cornell box's light hangs 1 cm under its ceiling). Light sampling alone
//! weighs a floor point next to the emitter by 1 / distance^2 and fills the picture with
//! fireflies; combined with the cosine-sampled continuation by the power heuristic, the
//! estimate stays bounded and converges to the same radiance, `albedo * Le * F` with F the
//! emitter's form factor (closed form).

use crate::scene::{Camera, Scene};
use crate::tests::common::meshgen::{EMITTER_GAP, EMITTER_HALF, emitter_above_floor};
use crate::tests::common::{agree, render};
use glam::{DVec3, Vec3};

pub const W: usize = 32;
pub const H: usize = 24;
pub const GAP: f32 = EMITTER_GAP;
pub const HALF: f32 = EMITTER_HALF;

pub fn scene() -> Scene {
    emitter_above_floor(W as f32 / H as f32)
}

/// The floor points across pixel (x, y) on a 6x6 grid (its samples are jittered uniformly
/// across it, and next to the emitter the radiance changes within a pixel), when nothing but
/// floor lies anywhere in the pixel (a sample that saw the emitter would add its emission).
pub fn floor_points(cam: &Camera, x: usize, y: usize) -> Option<Vec<Vec3>> {
    let at = |fx: f32, fy: f32, h: f32| {
        let r = cam.generate_ray((x as f32 + fx) / W as f32, (y as f32 + fy) / H as f32);
        r.at((h - r.origin.y) / r.dir.y)
    };
    let clear = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)].iter().all(|&(fx, fy)| {
        let e = at(fx, fy, GAP);
        e.x.abs() > HALF || e.z.abs() > HALF
    });
    let grid = (0..36).map(|k| at((k % 6) as f32 / 6.0 + 1.0 / 12.0, (k / 6) as f32 / 6.0 + 1.0 / 12.0, 0.0));
    clear.then(|| grid.collect())
}

/// Both estimators on the same paths (depth 2: the camera's hit continues, so its light is
/// found both ways): with MIS every 8x8 region's mean agrees with the closed form (the shared
/// z-test of `common::agree`: false failures below 1e-6, fixed seeds),
/// and its summed variance is under a tenth of light sampling's alone.
#[test]
fn mis_bounds_the_variance_next_to_an_emitter_and_keeps_the_mean() {
    let scene = scene();
    let expect = |x, y| {
        floor_points(&scene.camera, x, y).map(|points| {
            let radiance = |p: &Vec3| {
                let f = |cx: f32, cz: f32| {
                    crate::tests::common::corner_form_factor((cx - p.x) as f64, (cz - p.z) as f64, GAP as f64)
                };
                0.8 * 5.0 * (f(HALF, HALF) - f(-HALF, HALF) - f(HALF, -HALF) + f(-HALF, -HALF))
            };
            points.iter().map(radiance).sum::<f64>() / points.len() as f64
        })
    };
    let s = render::settings(W, H, 2, 512);
    let with = render::wavefront(&scene, &s).0;
    let without = render::wavefront(&scene, &s.clone().with(|s| s.paths.mis = false)).0;
    // The recursive reference shares the weights: the same estimator, other code.
    let reference = render::recursive(&scene, &s).0;
    for (acc, what) in [(&with, "wavefront"), (&reference, "recursive")] {
        agree::assert_regions_match(acc, 8, |x, y| expect(x, y).map(DVec3::splat), 1e-4, what);
    }
    let (mut var_with, mut var_without, mut floor) = (0.0, 0.0, 0);
    for y in 0..H {
        for x in 0..W {
            if expect(x, y).is_some() {
                var_with += with.pixels[y * W + x].variance_of_mean().x;
                var_without += without.pixels[y * W + x].variance_of_mean().x;
                floor += 1;
            }
        }
    }
    assert!(floor > W * H / 2, "{floor} floor pixels");
    assert!(var_with < 0.1 * var_without, "variance with MIS {var_with}, light sampling alone {var_without}");
}

/// MIS runs where the lights are emissive triangles (or an environment map), not for the
/// CS184 area lights, never with `--no-mis`, `-H` or direct light only.
#[test]
fn mis_is_on_where_the_lights_call_for_it() {
    use crate::effects::Effects;
    let global = render::settings(W, H, 5, 1);
    assert!(Effects::of(&scene(), &global).mis);
    assert!(!Effects::of(&crate::load::default_scene(), &global).mis);
    for off in [
        global.clone().with(|s| s.paths.mis = false),
        global.clone().with(|s| s.paths.hemisphere = true),
        render::settings(W, H, 1, 1),
    ] {
        assert!(!Effects::of(&scene(), &off).mis, "{off:?}");
    }
}

/// The last vertex too: depth-2 paths from a ceiling end on the floor beside the emitter.
/// Light sampling alone there (no ray to weigh it against) gave each vertex within a few
/// centimetres of the light an unweighted sample worth Le cos cos A / r^2; with the last
/// vertex's BSDF ray traced for the light it finds and both weighed by MIS, the image keeps
/// its mean (every 8x8 region agrees with light sampling alone and with the recursive
/// reference) at under a fifth of the variance (0.06 measured).
#[test]
fn mis_at_the_last_vertex_keeps_the_mean_and_bounds_the_variance() {
    let scene = super::emitter_filter::ceiling_scene(W as f32 / H as f32);
    let s = render::settings(W, H, 2, 256);
    let with = render::wavefront(&scene, &s).0;
    let without = render::wavefront(&scene, &s.clone().with(|s| s.paths.mis = false)).0;
    let reference = render::recursive(&scene, &s).0;
    agree::assert_regions_agree(&with, &without, 8, 1e-4, "MIS against light sampling alone");
    agree::assert_regions_agree(&with, &reference, 8, 1e-4, "wavefront against recursive");
    let variance = |acc: &crate::film::Accumulator| acc.pixels.iter().map(|p| p.variance_of_mean().x).sum::<f64>();
    let (var_with, var_without) = (variance(&with), variance(&without));
    assert!(var_with < 0.2 * var_without, "variance with MIS {var_with}, light sampling alone {var_without}");
}
