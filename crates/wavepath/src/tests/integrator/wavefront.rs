//! The wavefront integrator against the recursive reference: the two are independent
//! estimators (different seeds) of the same image, so per-region means must agree within
//! confidence bounds computed from the per-pixel sample variances.

use crate::load::default_scene;
use crate::sampling::SamplerKind;
use crate::scene::Scene;
use crate::settings::IntegratorKind;
use crate::settings::Settings;
use crate::tests::common;
use crate::tests::common::agree::assert_regions_agree;
use crate::tests::common::render::sums_with;
use crate::tests::common::render::{recursive, wavefront};
use glam::Vec3;

fn settings(max_depth: u32, spp: u32) -> Settings {
    common::render::small_settings(32, 24, max_depth, spp)
}

fn compare(scene: &Scene, s: &Settings, what: &str) {
    let (a, sa) = wavefront(scene, s);
    let mut other = s.clone();
    other.sampling.seed = s.sampling.seed + 1000;
    let (b, sb) = recursive(scene, &other);
    assert_eq!(sa.invalid_samples, 0, "{what}");
    assert_eq!(sb.invalid_samples, 0, "{what}");
    assert!(a.to_film().all_finite());
    let z = assert_regions_agree(&a, &b, 8, 0.0, what);
    eprintln!("{what}: worst |z| = {z:.2}");
}

#[test]
fn direct_light_importance_sampling_agrees() {
    compare(&default_scene(), &settings(1, 32), "direct, light sampling");
}

#[test]
fn direct_light_hemisphere_sampling_agrees() {
    let mut s = settings(1, 32);
    s.paths.hemisphere = true;
    compare(&default_scene(), &s, "direct, hemisphere sampling");
}

#[test]
fn global_illumination_agrees_at_depths_2_3_5() {
    let scene = default_scene();
    for depth in [2, 3, 5] {
        for accumulate in [true, false] {
            let mut s = settings(depth, 32);
            s.paths.accumulate = accumulate;
            compare(&scene, &s, &format!("-m {depth} -o {}", accumulate as u8));
        }
    }
}

#[test]
fn russian_roulette_on_and_off_agree() {
    let scene = default_scene();
    for rr in [0.65, 1.0] {
        let mut s = settings(5, 32);
        s.paths.roulette.continue_prob = rr;
        compare(&scene, &s, &format!("-m 5 --rr {rr}"));
    }
    // Roulette changes the estimator, not the expectation: with and without must agree too.
    let (a, _) = wavefront(&scene, &settings(6, 32).with(|s| s.paths.roulette.continue_prob = 0.5));
    let (b, _) = recursive(
        &scene,
        &settings(6, 32).with(|s| {
            s.paths.roulette.continue_prob = 1.0;
            s.sampling.seed = 77
        }),
    );
    assert_regions_agree(&a, &b, 8, 0.0, "--rr 0.5 vs --rr 1");
}

#[test]
fn hemisphere_indirect_agrees() {
    let mut s = settings(3, 32);
    s.paths.hemisphere = true;
    compare(&default_scene(), &s, "-H -m 3");
}

#[test]
fn adaptive_sampling_agrees_and_stops_pixels_early() {
    let scene = default_scene();
    let mut s = settings(3, 128);
    s.sampling.adaptive = Some((8, 0.1));
    let (a, sa) = wavefront(&scene, &s);
    let (b, sb) = recursive(&scene, &s.clone().with(|s| s.sampling.seed = 5));
    assert_regions_agree(&a, &b, 8, 0.0, "adaptive");
    for st in [&sa, &sb] {
        let (mean, min, max) = st.spp_summary();
        assert!(min >= 8 && max <= 128 && mean < 128.0, "({mean}, {min}, {max})");
        assert!(st.samples_per_pixel.iter().all(|&n| n % 8 == 0), "pixels stop only at batch ends");
    }
    // The same seed gives the same stopping decisions in both integrators' rule.
    let (c, _) = recursive(&scene, &s);
    let differ = a.pixels.iter().zip(&c.pixels).filter(|(p, q)| p.taken != q.taken).count();
    assert!(differ * 20 < a.pixels.len(), "{differ} pixels stopped at different counts");
}

#[test]
fn thin_lens_agrees() {
    let mut scene = default_scene();
    scene.camera.lens_radius = 0.05;
    scene.camera.focal_distance = 3.0;
    compare(&scene, &settings(2, 32), "thin lens -m 2");
}

#[test]
fn image_is_identical_for_any_thread_count() {
    // 96x72 at 4 samples: 6912 pixels in waves of 1024 (4096 paths), seven waves per frame,
    // so every pool has work to share; with and without adaptive sampling, for every sampler.
    let scene = default_scene();
    let accel = crate::accel::build(&scene, &Default::default()).0;
    let mut base = settings(3, 4);
    base.image.width = 96;
    base.image.height = 72;
    let mut adaptive = base.clone();
    adaptive.sampling.spp = 8;
    adaptive.sampling.adaptive = Some((4, 0.05));
    let patterned = SamplerKind::ALL.map(|sampler| base.clone().with(|s| s.sampling.sampler = sampler));
    for s in [base.clone(), adaptive.clone(), adaptive.with(|s| s.sampling.sampler = SamplerKind::Sobol)]
        .iter()
        .chain(&patterned)
    {
        let run = |threads| {
            let waves = std::sync::atomic::AtomicUsize::new(0);
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let acc = pool.install(|| {
                sums_with(IntegratorKind::Wavefront, &scene, accel.as_ref(), s, &|_| {
                    waves.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                })
                .0
            });
            (acc, waves.into_inner())
        };
        let (one, waves) = run(1);
        assert!(waves >= 7, "{waves} waves: the pools would have nothing to share");
        assert!(one.to_film().pixels.iter().filter(|p| **p != Vec3::ZERO).count() > 96 * 72 / 5);
        let bits = |a: &crate::film::Accumulator| -> Vec<[u32; 3]> {
            a.to_film().pixels.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
        };
        for threads in [2, 3, 8] {
            let (other, _) = run(threads);
            assert_eq!(
                bits(&one),
                bits(&other),
                "{threads} threads, adaptive {:?}, {:?}",
                s.sampling.adaptive,
                s.sampling.sampler
            );
            assert_eq!(one.samples_taken(), other.samples_taken());
        }
    }
}

#[test]
fn ray_counts_add_up() {
    let scene = default_scene();
    let s = settings(1, 4);
    let (_, st) = wavefront(&scene, &s);
    assert_eq!(st.camera_rays, 32 * 24 * 4);
    assert_eq!(st.extension_rays, 0, "-m 1 traces no continuation rays");
    // One area light sampled -l 2 times per hit, minus samples facing away from the light.
    assert!(st.shadow_rays > 0 && st.shadow_rays <= st.camera_rays * 2);
    assert_eq!(st.counters.rays, st.total_rays());
    // The stages ran (their times are measurements, not properties).
    assert!(st.stages.traverse.is_some() && st.stages.shade.is_some());
    assert_eq!(st.stages.compact, None, "-m 1 runs no bounce stage");
}

#[test]
fn cell_renders_only_its_pixels() {
    let scene = default_scene();
    let mut s = settings(2, 4);
    s.image.cell = Some(crate::settings::Cell { x: 4, y: 2, w: 5, h: 3 });
    let (a, st) = wavefront(&scene, &s);
    assert_eq!(st.samples_per_pixel.len(), 15);
    for y in 0..24 {
        for x in 0..32 {
            let inside = (4..9).contains(&x) && (2..5).contains(&y);
            assert_eq!(a.pixels[y * 32 + x].taken, if inside { 4 } else { 0 });
        }
    }
}

/// The CS184 scenes (loaded by the COLLADA loader) render with both integrators alike and
/// without a single NaN or Inf sample.
#[test]
fn cs184_scenes_agree_and_stay_finite() {
    for name in ["CBspheres_lambertian", "CBempty"] {
        let Some(mut scene) = common::load_scene(&format!("cs184/sky/{name}.dae")) else { return };
        scene.camera.fit_aspect(32.0 / 24.0);
        let mut s = settings(3, 16);
        s.sampling.light_samples = 1;
        compare(&scene, &s, name);
        let (_, st) = wavefront(&scene, &s.clone().with(|s| s.paths.hemisphere = true));
        assert_eq!(st.invalid_samples, 0);
    }
}
