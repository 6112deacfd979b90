//! Negative controls of the shared region test (`common::agree`): a render shifted by a known
//! multiple of its standard error must fail `regions_agree` and `regions_match`, while an
//! unbiased render of the same scene (another seed, or the exact answer) passes. Without
//! these, a z-test that never fails (a threshold too high, a variance too large, a region
//! that compares nothing) would pass every other test that uses it.
//!
//! How the bias is made: every sample of a pixel is moved by the same `delta` (per channel),
//! written straight into the pixel's sums: `sum += n delta`, `sum_sq += 2 delta sum + n
//! delta^2`. The pixel's mean moves by `delta` and its sample variance is unchanged (the
//! difference `sum_sq - sum^2 / n` is invariant), so the test sees the same standard error
//! and only the shifted mean.
//!
//! Why failure is certain: per region and channel the test computes `z = (|d| - tol) / sd`
//! (`d` the difference of the region sums, `sd` its standard error) and fails at
//! `z >= z_max`, Bonferroni's threshold for the call. The region's sum is shifted by
//! `B = (2 z_max + 1) sd + 2 tol`. The unbiased comparison passes first, so its noise has
//! `|d0| < z_max sd + tol`; after the shift `|d0 + B| >= B - |d0| > (z_max + 1) sd + tol`,
//! so `z > z_max + 1`: every region fails, whatever the seeds, not only most of the time.

use crate::film::Accumulator;
use crate::scene::{Camera, Light, Material, Mesh, Scene};
use crate::tests::common::agree::{self, z_threshold};
use crate::tests::common::meshgen::quad;
use crate::tests::common::render;
use glam::{DVec3, Vec3, vec3};

/// Regions of 8 x 8 pixels on a 32 x 24 image: 4 x 3 regions, 36 comparisons a call.
const SIZE: usize = 8;
const W: usize = 32;
const H: usize = 24;

/// Per region, the sum of the pixels' variances of the mean (the variance of the region's
/// sum of means, as the test defines it) and the number of pixels.
fn region_variance(acc: &Accumulator, rx: usize, ry: usize) -> (DVec3, usize) {
    let mut v = DVec3::ZERO;
    for y in ry * SIZE..(ry + 1) * SIZE {
        for x in rx * SIZE..(rx + 1) * SIZE {
            v += acc.pixels[y * acc.width + x].variance_of_mean();
        }
    }
    (v, SIZE * SIZE)
}

/// `acc` with every sample of every pixel of region (rx, ry) moved by `shift[c] / pixels`,
/// so the region's sum of means moves by `shift` and every variance stays.
fn shifted(acc: &Accumulator, shift: impl Fn(usize, usize) -> DVec3) -> Accumulator {
    let mut out = acc.clone();
    for y in 0..(H / SIZE) * SIZE {
        for x in 0..(W / SIZE) * SIZE {
            let delta = shift(x / SIZE, y / SIZE) / (SIZE * SIZE) as f64;
            let p = &mut out.pixels[y * W + x];
            let n = p.valid as f64;
            p.sum_sq += 2.0 * delta * p.sum + n * delta * delta;
            p.sum += n * delta;
        }
    }
    // The shift kept each pixel's variance (to rounding).
    for (a, b) in acc.pixels.iter().zip(&out.pixels) {
        let (va, vb) = (a.variance_of_mean(), b.variance_of_mean());
        assert!((va - vb).abs().max_element() <= 1e-9 * va.max_element().max(1e-12), "{va} vs {vb}");
    }
    out
}

/// The embedded Cornell box with global illumination at 32 x 24, 16 spp: seed 1 against
/// seed 2 agree; seed 1 shifted per region by `(2 z_max + 1) sd + 2 tol` fails. Here
/// `z_max = z_threshold(36)`, 5.55 (two-sided tail 1e-6 / 36), so the shift is 12.1 of
/// the difference's standard errors: the biased comparison's `z` exceeds `z_max + 1` in every
/// region (module comment). `tol` is `regions_agree`'s floor of 1e-9 a pixel (`rel_tol` 0).
#[test]
fn a_render_biased_by_its_standard_error_does_not_agree() {
    let scene = crate::load::default_scene();
    let base = render::settings(W, H, 4, 16);
    let mut s1 = base.clone();
    s1.sampling.seed = 1;
    let mut s2 = base;
    s2.sampling.seed = 2;
    let (a, b) = (render::wavefront(&scene, &s1).0, render::wavefront(&scene, &s2).0);
    assert!(a != b, "the seeds gave the same render");
    let z_max = z_threshold((W / SIZE) * (H / SIZE) * 3);
    assert!((5.5..5.6).contains(&z_max), "z_max {z_max}");
    let unbiased = agree::regions_agree(&a, &b, SIZE, 0.0, "seed 1 against seed 2");
    assert!(unbiased.is_ok(), "{unbiased:?}");
    let tol = 1e-9 * (SIZE * SIZE) as f64;
    let shift = |rx: usize, ry: usize| {
        let ((va, n), (vb, _)) = (region_variance(&a, rx, ry), region_variance(&b, rx, ry));
        let sd = (2.0 * va.max(vb)).map(f64::sqrt);
        assert!(sd.min_element() > 1e3 * tol && n == SIZE * SIZE, "region ({rx},{ry}) has no noise: {sd}");
        (2.0 * z_max + 1.0) * sd + DVec3::splat(2.0 * tol)
    };
    for sign in [1.0, -1.0] {
        let biased = shifted(&a, |rx, ry| sign * shift(rx, ry));
        let e = agree::regions_agree(&biased, &b, SIZE, 0.0, "biased seed 1 against seed 2")
            .expect_err("a render biased by 12 standard errors agreed");
        assert!(e.contains("region (0,0) channel 0") && e.contains(">="), "{e}");
        // Only one region biased: the test still finds it (the maximum over regions is
        // what fails, not an average).
        let one = shifted(&a, |rx, ry| if (rx, ry) == (2, 1) { sign * shift(rx, ry) } else { DVec3::ZERO });
        let e = agree::regions_agree(&one, &b, SIZE, 0.0, "one region biased").expect_err("one biased region passed");
        assert!(e.contains("region (2,1)"), "{e}");
        // The panicking form panics.
        let panicked = std::panic::catch_unwind(|| agree::assert_regions_agree(&biased, &b, SIZE, 0.0, "panics"));
        assert!(panicked.is_err(), "assert_regions_agree did not panic");
    }
}

/// A floor (albedo 0.6) under the hemisphere light (radiance 1.5), seen from above, every
/// pixel on the floor: each pixel's expectation is exactly 0.6 x 1.5 = 0.9 (the radiance of a
/// diffuse plane under a uniform sky: albedo times sky radiance). Uniform hemisphere sampling
/// (`-H`, 4 light samples, 16 spp) makes it noisy. The unbiased render matches 0.9; the same
/// render shifted per region by `(2 z_max + 1) sd + 2 tol` (`z_max = z_threshold(36)`, about
/// 5.55; `sd` the region's standard error; `tol` the test's 1e-7 a pixel with `rel_tol` 0)
/// fails in every region, up or down (module comment).
#[test]
fn a_render_biased_by_its_standard_error_does_not_match_the_expectation() {
    let mut mesh = Mesh::default();
    let half = 50.0;
    quad(
        &mut mesh,
        [vec3(-half, 0.0, -half), vec3(-half, 0.0, half), vec3(half, 0.0, half), vec3(half, 0.0, -half)],
        0,
    );
    let mut camera = Camera::look_at(vec3(0.0, 3.0, 0.5), Vec3::ZERO, Vec3::Y, 40.0, W as f32 / H as f32);
    camera.nclip = 0.01;
    let scene = Scene {
        name: "floor under the sky".into(),
        mesh,
        materials: vec![Material::diffuse("grey", Vec3::splat(0.6))],
        lights: vec![Light::Hemisphere { radiance: Vec3::splat(1.5) }],
        camera,
        ..Scene::default()
    };
    let mut s = render::settings(W, H, 1, 16);
    s.paths.hemisphere = true;
    s.sampling.light_samples = 4;
    let acc = render::wavefront(&scene, &s).0;
    let expect = |_: usize, _: usize| Some(DVec3::splat(0.9));
    let (worst, checked) = agree::regions_match(&acc, SIZE, expect, 0.0, "unbiased").expect("the unbiased render");
    assert_eq!(checked, W * H);
    let z_max = z_threshold((W / SIZE) * (H / SIZE) * 3);
    assert!(worst < z_max);
    let tol = 1e-7 * (SIZE * SIZE) as f64;
    let shift = |rx: usize, ry: usize| {
        let sd = region_variance(&acc, rx, ry).0.map(f64::sqrt);
        assert!(sd.min_element() > 1e3 * tol, "region ({rx},{ry}) has no noise: {sd}");
        (2.0 * z_max + 1.0) * sd + DVec3::splat(2.0 * tol)
    };
    for sign in [1.0, -1.0] {
        let biased = shifted(&acc, |rx, ry| sign * shift(rx, ry));
        let e = agree::regions_match(&biased, SIZE, expect, 0.0, "biased")
            .expect_err("a render biased by 12 standard errors matched");
        assert!(e.contains("region (0,0) channel 0"), "{e}");
        let panicked = std::panic::catch_unwind(|| agree::assert_regions_match(&biased, SIZE, expect, 0.0, "panics"));
        assert!(panicked.is_err(), "assert_regions_match did not panic");
    }
    // The same shift on the expectation instead of the render fails too (the test is
    // two-sided about which side is off).
    let off = |x: usize, y: usize| Some(DVec3::splat(0.9) + shift(x / SIZE, y / SIZE) / (SIZE * SIZE) as f64);
    assert!(agree::regions_match(&acc, SIZE, off, 0.0, "expectation off").is_err());
}
