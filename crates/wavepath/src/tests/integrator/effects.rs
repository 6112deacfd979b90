//! Effects: derived from the scene and settings, they decide which stages run. A stage that
//! is off reports no time (absent from the stats JSON), and forcing every effect on must not
//! change the image (every kernel part is exact when its effect is not needed).

use crate::accel::{self, BruteForce};
use crate::effects::Effects;
use crate::load::default_scene;
use crate::scene::Scene;
use crate::settings::IntegratorKind;
use crate::settings::{Settings, Shading};
use crate::stats::RenderStats;
use crate::tests::common;
use crate::tests::common::render::sums_with;
use crate::tests::common::render::wavefront;
use glam::Vec3;

fn settings(max_depth: u32, spp: u32) -> Settings {
    common::render::small_settings(24, 18, max_depth, spp)
}

fn stages_json(scene: &Scene, s: &Settings, st: &RenderStats) -> serde_json::Value {
    let json = crate::stats::to_json(scene, s, &Effects::of(scene, s), &Default::default(), st);
    json["stages"].clone()
}

#[test]
fn normal_shading_runs_no_shadow_stage() {
    let scene = default_scene();
    let mut s = settings(1, 2);
    s.paths.shading = Shading::Normals;
    let e = Effects::of(&scene, &s);
    assert!(e.normal_shading && !e.direct && !e.indirect);
    assert_eq!(e.names(), ["normal-shading", "spheres"]);
    let (film, st) = crate::render::render(&scene, &BruteForce::new(&scene), &s).unwrap();
    assert!(film.pixels.iter().any(|p| *p != Vec3::ZERO));
    assert_eq!(st.shadow_rays, 0);
    assert_eq!(st.stages.shadow, None);
    let stages = stages_json(&scene, &s, &st);
    assert!(stages.get("shadow").is_none() && stages.get("shade").is_none(), "{stages}");
    assert!(stages.get("traverse").is_some(), "{stages}");
}

#[test]
fn depth_one_runs_no_bounce_or_roulette() {
    let scene = default_scene();
    let s = settings(1, 4);
    let e = Effects::of(&scene, &s);
    assert!(!e.indirect && !e.russian_roulette && e.direct);
    assert!(!e.names().contains(&"indirect") && !e.names().contains(&"russian-roulette"));
    let (_, st) = wavefront(&scene, &s);
    assert_eq!(st.extension_rays, 0);
    assert_eq!(st.stages.compact, None);
    let stages = stages_json(&scene, &s, &st);
    let keys: Vec<&String> = stages.as_object().unwrap().keys().collect();
    assert_eq!(keys, ["generate", "shade", "shadow", "traverse"], "sorted keys: no compact");
    // At -m 5 both are on, and the bounce stage runs.
    let s5 = settings(5, 4);
    let e5 = Effects::of(&scene, &s5);
    assert!(e5.indirect && e5.russian_roulette);
    let (_, st5) = wavefront(&scene, &s5);
    assert!(st5.extension_rays > 0 && st5.stages.compact.is_some());
    // -m 2: a bounce, but roulette never stops the first indirect bounce, so it is off.
    let e2 = Effects::of(&scene, &settings(2, 4));
    assert!(e2.indirect && !e2.russian_roulette);
}

#[test]
fn sphere_effect_follows_the_scene() {
    let with = default_scene();
    assert!(!with.spheres.is_empty());
    assert!(Effects::of(&with, &settings(1, 1)).names().contains(&"spheres"));
    let Some(without) = common::load_scene("cs184/sky/CBempty.dae") else { return };
    assert!(without.spheres.is_empty());
    let e = Effects::of(&without, &settings(1, 1));
    assert!(!e.spheres && !e.names().contains(&"spheres"), "{:?}", e.names());
}

#[test]
fn a_scene_without_lights_runs_no_shadow_stage() {
    let mut scene = default_scene();
    scene.lights.clear();
    for m in &mut scene.materials {
        m.emission = Vec3::ZERO;
    }
    let s = settings(3, 2);
    let e = Effects::of(&scene, &s);
    assert!(!e.direct && !e.area_lights && !e.emission, "{:?}", e.names());
    let (acc, st) = wavefront(&scene, &s);
    assert_eq!((st.shadow_rays, st.stages.shadow), (0, None));
    assert!(acc.to_film().pixels.iter().all(|p| *p == Vec3::ZERO), "nothing emits, so all is black");
}

/// The forced kernels draw the same random numbers, so the images are bit-identical.
#[test]
fn forcing_all_effects_on_gives_the_same_image() {
    let scene = default_scene();
    let (bvh, _) = accel::build(&scene, &Settings::default());
    for (depth, hemisphere, rr) in
        [(1, false, 0.65), (2, false, 0.65), (5, false, 1.0), (5, false, 0.65), (3, true, 0.65)]
    {
        let mut s = settings(depth, 8);
        s.paths.hemisphere = hemisphere;
        s.paths.roulette.continue_prob = rr;
        let mut forced = s.clone();
        forced.execution.all_effects = true;
        let e = Effects::of(&scene, &forced);
        assert!(e.forced && e.indirect && e.russian_roulette && e.direct && e.environment && e.adaptive);
        let (a, sa) = sums_with(IntegratorKind::Wavefront, &scene, bvh.as_ref(), &s, &|_| {});
        let (b, sb) = sums_with(IntegratorKind::Wavefront, &scene, bvh.as_ref(), &forced, &|_| {});
        let what = format!("-m {depth} -H {hemisphere} --rr {rr}");
        assert_eq!(a.to_film(), b.to_film(), "{what}");
        assert_eq!(a.samples_taken(), b.samples_taken(), "{what}");
        assert_eq!(sa.total_rays(), sb.total_rays(), "{what}");
        assert!(sb.stages.list().len() == 5, "{what}: forced runs every stage");
        assert!(a.to_film().pixels.iter().any(|p| *p != Vec3::ZERO));
    }
}
