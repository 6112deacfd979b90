//! Bidirectional transport (light tracing, BDPT, VCM) against the path tracer, region by
//! region (`common::agree`): every integrator estimates the same image, so a strategy
//! counted twice or a multiple importance sampling weight that does not add to one with
//! the others shows as a bias the z-test finds (a double count of the CS184 boxes' light
//! through a mirror, 1% of the image, fails it; see `cs184_area_light_and_quad_differ`).
//! Also: the same bits for any thread count, no invalid sample, and one-line refusals of
//! what the bidirectional integrators do not render.

use crate::accel::Intersector;
use crate::film::Accumulator;
use crate::scene::Scene;
use crate::settings::{IntegratorKind, Settings};
use crate::tests::common::agree::assert_regions_agree;
use crate::tests::common::{self, render};

const W: usize = 32;
const H: usize = 24;
const REGION: usize = 8;

fn settings(spp: u32, depth: u32) -> Settings {
    render::settings(W, H, depth, spp)
}

fn bvh(scene: &Scene, s: &Settings) -> Box<dyn Intersector> {
    crate::accel::build(scene, s).0
}

/// The sums of a render with `kind`, asserting it dropped no sample.
fn sums(kind: IntegratorKind, scene: &Scene, s: &Settings) -> Accumulator {
    let accel = bvh(scene, s);
    let (acc, st) = render::sums_with(kind, scene, accel.as_ref(), s, &|_| {});
    assert_eq!(st.invalid_samples, 0, "{}: {} dropped samples", scene.name, kind.name());
    acc
}

/// Light tracing alone equals the path tracer on a diffuse scene lit by an area light:
/// every light path's camera connections against every camera path's light samples.
#[test]
fn light_tracing_agrees_with_the_path_tracer() {
    let Some(scene) = common::load_scene("cs184/sky/CBspheres_lambertian.dae") else { return };
    let path = sums(IntegratorKind::Wavefront, &scene, &settings(256, 3));
    let light = sums(IntegratorKind::Light, &scene, &settings(512, 3));
    assert_regions_agree(&light, &path, REGION, 0.0, "light tracing vs path tracing");
    let z = image_z(&light, &path);
    assert!(z < 5.0, "light tracing vs path tracing over the whole image: z = {z}");
}

/// BDPT and VCM converge to the path tracer's image on a diffuse box with an area light,
/// and on a box whose light is emissive geometry with a mirror and a glass sphere in it
/// (light through them onto the floor: the paths only light tracing and merging find well).
#[test]
fn bdpt_and_vcm_agree_with_the_path_tracer() {
    for (file, depth) in [("cs184/sky/CBspheres_lambertian.dae", 4), ("obj/CornellBox/CornellBox-Sphere.obj", 5)] {
        let Some(scene) = common::load_scene(file) else { return };
        let path = sums(IntegratorKind::Wavefront, &scene, &settings(512, depth));
        for kind in [IntegratorKind::Bdpt, IntegratorKind::Vcm, IntegratorKind::PathLight] {
            let bi = sums(kind, &scene, &settings(96, depth));
            // VCM's merges blur light over a radius that shrinks with the iterations: a
            // bias of a fraction of a percent at this sample count.
            let tol = if kind == IntegratorKind::Vcm { 0.01 } else { 0.0 };
            assert_regions_agree(&bi, &path, REGION, tol, &format!("{file}: {} vs path tracing", kind.name()));
            let z = image_z(&bi, &path);
            assert!(z < 5.0, "{file}: {} vs path tracing over the whole image: z = {z}", kind.name());
        }
    }
}

/// path+light in the wavefront against its one-path reference form (the camera side written
/// from the recursive MIS quantities, its light samples its own): the same estimator, so the
/// same image within the noise, on the box with a mirror and a glass sphere under emissive
/// geometry, where the light subpaths carry the caustics.
#[test]
fn path_light_in_the_wavefront_agrees_with_its_reference_form() {
    let Some(scene) = common::load_scene("obj/CornellBox/CornellBox-Sphere.obj") else { return };
    // Enough samples that a caustic counted by both sides (5-9% of this image) fails the
    // whole-image test (z about 9).
    let mut s = settings(2048, 5);
    s.execution.integrator = IntegratorKind::PathLight;
    let accel = bvh(&scene, &s);
    let plan = crate::integrator::plan::RenderPlan::new(&scene, &s);
    let mut reference = Accumulator::new(W, H);
    let mode = crate::integrator::bidir::Mode::PathLight;
    let stop = std::sync::atomic::AtomicBool::new(false);
    crate::integrator::bidir::render_bidir_into(
        plan.transport(),
        &s,
        accel.as_ref(),
        mode,
        &|_| {},
        &stop,
        &mut reference,
    )
    .unwrap()
    .unwrap();
    let wavefront = sums(IntegratorKind::PathLight, &scene, &s);
    assert_regions_agree(&wavefront, &reference, REGION, 0.0, "path+light: wavefront vs reference form");
    let z = image_z(&wavefront, &reference);
    assert!(z < 5.0, "path+light: wavefront vs reference form over the whole image: z = {z}");
}

/// The CS184 boxes' emissive quad is the area light turned a quarter (0.8 x 0.6 against
/// 0.6 x 0.8): the course's path tracer takes light seen through a mirror or glass from the
/// quad and all other light from the area light; bidirectional transport takes all of it
/// from the area light, one light. A negative control of the agreement test: on such a box
/// with a mirror the two differ by about 1%, and the test must see it.
#[test]
fn cs184_area_light_and_quad_differ() {
    let Some(scene) = common::load_scene("cs184/sky/CBspheres.dae") else { return };
    let path = sums(IntegratorKind::Wavefront, &scene, &settings(512, 2));
    let bdpt = sums(IntegratorKind::Bdpt, &scene, &settings(256, 2));
    let ratio = image_sum(&bdpt) / image_sum(&path);
    assert!(ratio > 1.004 && ratio < 1.03, "bdpt / path = {ratio}");
    let z = image_z(&bdpt, &path);
    assert!(z > 6.0, "the whole-image test misses a 1% difference: z = {z}");
}

/// The sum of an image's pixel means over its channels.
fn image_sum(a: &Accumulator) -> f64 {
    a.pixels.iter().map(|p| p.mean().element_sum() as f64).sum()
}

/// |z| of the difference of two renders' image sums (channels added), the variance of each
/// from its pixels' sample variances: the most sensitive test of a bias that spreads over
/// the image, which a per-region test with its Bonferroni threshold needs far more samples
/// to see.
fn image_z(a: &Accumulator, b: &Accumulator) -> f64 {
    let var = |x: &Accumulator| x.pixels.iter().map(|p| p.variance_of_mean().element_sum()).sum::<f64>();
    (image_sum(a) - image_sum(b)).abs() / (var(a) + var(b)).sqrt()
}

/// Splats are added in a fixed order: one thread and two give the same sums, bit for bit.
#[test]
fn images_do_not_depend_on_the_thread_count() {
    let Some(scene) = common::load_scene("obj/CornellBox/CornellBox-Sphere.obj") else { return };
    for kind in [IntegratorKind::Light, IntegratorKind::Bdpt, IntegratorKind::Vcm, IntegratorKind::PathLight] {
        let s = settings(4, 5);
        let one = crate::render::with_threads(1, || sums(kind, &scene, &s)).unwrap();
        let two = crate::render::with_threads(2, || sums(kind, &scene, &s)).unwrap();
        assert!(one == two, "{}: sums differ between 1 and 2 threads", kind.name());
    }
}

/// path+light's light side is counted apart from its camera side: the camera side traces the
/// path tracer's own camera and extension rays (the same paths, only weighted differently),
/// the light side at least one ray per light subpath that leaves its light and at most one per
/// edge a subpath may have, and each side's time per vertex is reported; the path tracer has
/// no light side to report.
#[test]
fn the_light_side_is_counted_apart() {
    let Some(scene) = common::load_scene("obj/CornellBox/CornellBox-Sphere.obj") else { return };
    let (spp, depth) = (4, 5);
    let s = settings(spp, depth);
    let accel = bvh(&scene, &s);
    let (_, path) = render::sums_with(IntegratorKind::Wavefront, &scene, accel.as_ref(), &s, &|_| {});
    let (_, pl) = render::sums_with(IntegratorKind::PathLight, &scene, accel.as_ref(), &s, &|_| {});
    assert_eq!((path.camera_rays, path.extension_rays), (pl.camera_rays, pl.extension_rays));
    assert!(pl.shadow_rays > path.shadow_rays, "no camera connection traced");
    assert_eq!((path.light_rays, path.ns_per_vertex()), (0, None));
    // A quarter of the pixels' light subpaths per sample (the default share), each from a
    // one-sided emitter into its hemisphere: all of them leave it.
    let subpaths = ((W * H) as u64).div_ceil(4) * spp as u64;
    assert!(
        (subpaths..=subpaths * depth as u64).contains(&pl.light_rays),
        "{} light rays for {subpaths} light subpaths",
        pl.light_rays
    );
    assert_eq!(pl.total_rays(), pl.camera_rays + pl.extension_rays + pl.shadow_rays + pl.light_rays);
    let (camera, light) = pl.ns_per_vertex().expect("path+light reports both sides");
    assert!(camera > 0.0 && light > 0.0 && camera.is_finite() && light.is_finite(), "{camera} {light}");
}

/// A cell (`-p`, a tile of a split render, the viewer's band) traces every light subpath and
/// keeps its own pixels: two cells give, bit for bit, the sums of the whole image.
#[test]
fn cells_give_the_whole_images_sums() {
    let Some(scene) = common::load_scene("obj/CornellBox/CornellBox-Sphere.obj") else { return };
    for kind in [IntegratorKind::Bdpt, IntegratorKind::Vcm, IntegratorKind::PathLight] {
        let s = settings(4, 5);
        let whole = sums(kind, &scene, &s);
        for (y, h) in [(0, 10), (10, H - 10)] {
            let mut c = s.clone();
            c.image.cell = Some(crate::settings::Cell { x: 5, y, w: W - 5, h });
            let part = sums(kind, &scene, &c);
            for py in 0..H {
                for px in 0..W {
                    let inside = px >= 5 && py >= y && py < y + h;
                    let (a, b) = (&part.pixels[py * W + px], &whole.pixels[py * W + px]);
                    if inside {
                        assert!(a == b, "{}: pixel ({px}, {py}) differs from the whole image's", kind.name());
                    } else {
                        assert_eq!(a.taken, 0, "{}: pixel ({px}, {py}) outside the cell", kind.name());
                    }
                }
            }
        }
    }
}

/// The viewer's bands of a pass (cells of one plan rendering the same samples into one
/// canvas) share one light pass: the first band traces every light subpath of the image, the
/// plan keeps what they splatted, the other bands trace none; the next pass traces its own.
/// The canvas's sums are bit for bit those of the same passes over the whole image.
#[test]
fn bands_of_a_pass_share_one_light_pass() {
    let Some(scene) = common::load_scene("obj/CornellBox/CornellBox-Sphere.obj") else { return };
    let mut s = settings(8, 5);
    s.execution.integrator = IntegratorKind::PathLight;
    let accel = bvh(&scene, &s);
    let plan = crate::integrator::plan::RenderPlan::new(&scene, &s);
    let stop = std::sync::atomic::AtomicBool::new(false);
    let passes = [(0, 4), (4, 8)];
    let mut whole = crate::render::Canvas::new(W, H);
    for samples in passes {
        let extent = crate::integrator::plan::Extent { cell: None, samples: Some(samples) };
        whole.render(&plan, accel.as_ref(), extent, &|_| {}, &stop).unwrap();
    }
    let mut canvas = crate::render::Canvas::new(W, H);
    for samples in passes {
        for (band, rows) in [(0, 10), (10, 20), (20, H)].into_iter().enumerate() {
            let cell = crate::settings::Cell { x: 0, y: rows.0, w: W, h: rows.1 - rows.0 };
            let extent = crate::integrator::plan::Extent { cell: Some(cell), samples: Some(samples) };
            let st = canvas.render(&plan, accel.as_ref(), extent, &|_| {}, &stop).unwrap();
            match band {
                0 => assert!(st.light_rays > 0, "{samples:?}: the first band traced no light subpath"),
                _ => assert_eq!(st.light_rays, 0, "{samples:?}: band {band} traced the light subpaths again"),
            }
        }
    }
    assert!(canvas.sums().pixels == whole.sums().pixels, "bands' sums differ from the whole image's");
}

/// What the bidirectional integrators do not render is refused in one line naming why,
/// never rendered wrong.
#[test]
fn refusals_are_one_line() {
    let scene = crate::load::default_scene();
    type Change = fn(&mut Settings);
    let cases: [(&str, Change); 3] = [
        ("adaptive", |s| s.sampling.adaptive = Some((8, 0.05))),
        ("last bounce", |s| s.paths.accumulate = false),
        ("light paths", |s| s.sampling.light_paths = Some(0.5)),
    ];
    for (what, change) in cases {
        let mut s = settings(2, 4);
        change(&mut s);
        s.execution.integrator = IntegratorKind::Bdpt;
        let accel = bvh(&scene, &s);
        let err = crate::render::render_sums(&scene, accel.as_ref(), &s, &|_| {}).expect_err(what).to_string();
        assert!(err.starts_with("bdpt ") && !err.contains('\n'), "{what}: {err}");
    }
}

/// The weights the integrator computes from its running quantities, for one concrete path
/// light -> floor -> wall -> camera, equal the power heuristic over every strategy that
/// makes the path, computed here from each vertex's density on each side (products, as
/// Veach writes them): so each strategy's weighted contribution adds up to the unweighted
/// estimate. BDPT's four strategies, and with merging its two merges besides.
#[test]
fn mis_weights_are_the_power_heuristic_and_add_to_one() {
    use crate::integrator::bidir::IterFactors;
    use crate::integrator::bidir::connect::{
        camera_weight, connection_weight, hit_weight, light_sample_weight, merge_weight,
    };
    use crate::integrator::bidir::walk::mis;
    use crate::lights::emission::Illumination;
    use glam::Vec3;
    use std::f32::consts::PI;

    let (x0, n0) = (Vec3::new(0.1, 1.0, 0.2), Vec3::NEG_Y);
    let (x1, n1) = (Vec3::new(0.3, 0.0, -0.1), Vec3::Y);
    let (x2, n2) = (Vec3::new(-1.0, 0.6, 0.4), Vec3::X);
    let cam = Vec3::new(0.2, 0.5, 3.0);
    let (area, pick, light_paths, pixels_per_area, radius) = (0.25f32, 0.7f32, 1000.0f32, 5000.0f32, 0.01f32);
    let cos = |a: Vec3, b: Vec3, n: Vec3| (b - a).normalize().dot(n).abs();
    let d2 = |a: Vec3, b: Vec3| (b - a).length_squared();
    // Lambertian density of leaving `a` (normal n) toward `b`.
    let lam = |a: Vec3, b: Vec3, n: Vec3| cos(a, b, n) / PI;
    let cos_cam = (x2 - cam).normalize().dot(Vec3::NEG_Z);
    let cam_pdf_w = pixels_per_area / (cos_cam * cos_cam * cos_cam);

    // Each vertex's area density on the light's side and the camera's.
    let pl0 = pick / area;
    let pl1 = lam(x0, x1, n0) * cos(x0, x1, n1) / d2(x0, x1);
    let pl2 = lam(x1, x2, n1) * cos(x1, x2, n2) / d2(x1, x2);
    let pc2 = cam_pdf_w * cos(cam, x2, n2) / d2(cam, x2);
    let pc1 = lam(x2, x1, n2) * cos(x2, x1, n1) / d2(x1, x2);
    let pc0 = lam(x1, x0, n1) * cos(x1, x0, n0) / d2(x0, x1);
    let eta = PI * radius * radius * light_paths;
    let connections = [pc0 * pc1 * pc2, pl0 * pc1 * pc2, pl0 * pl1 * pc2, light_paths * pl0 * pl1 * pl2];
    let merges = [eta * pl0 * pl1 * pc1 * pc2, eta * pl0 * pl1 * pl2 * pc2];

    for merging in [false, true] {
        let f = IterFactors::new(radius, light_paths, merging);
        let start = |d_vcm: f32, d_vc: f32| subpath_start(d_vcm, d_vc, &f);
        // The camera subpath at x2, then at x1, then at the light.
        let mut c2 = start(mis(light_paths / cam_pdf_w), 0.0);
        c2.arrive_at(cos(cam, x2, n2), d2(cam, x2).sqrt());
        let mut c1 = c2;
        c1.leave(cos(x2, x1, n2), lam(x2, x1, n2), lam(x2, cam, n2), false, &f);
        c1.arrive_at(cos(x2, x1, n1), d2(x1, x2).sqrt());
        let mut c0 = c1;
        c0.leave(cos(x1, x0, n1), lam(x1, x0, n1), lam(x1, x2, n1), false, &f);
        c0.arrive_at(cos(x1, x0, n0), d2(x0, x1).sqrt());
        // The light subpath at x1, then at x2.
        let emission_pdf_w = (1.0 / area) * lam(x0, x1, n0) * pick;
        let mut l1 = start(mis(pick / area / emission_pdf_w), mis(cos(x0, x1, n0) / emission_pdf_w));
        l1.arrive_at(cos(x0, x1, n1), d2(x0, x1).sqrt());
        let mut l2 = l1;
        l2.leave(cos(x1, x2, n1), lam(x1, x2, n1), lam(x1, x0, n1), false, &f);
        l2.arrive_at(cos(x1, x2, n2), d2(x1, x2).sqrt());

        let il = Illumination {
            wi: (x0 - x1).normalize(),
            target: Some(x0),
            radiance: Vec3::ONE,
            direct_pdf_w: d2(x0, x1) / (area * cos(x1, x0, n0)),
            direct_pdf_a: 1.0 / area,
            emission_pdf_w: lam(x0, x1, n0) / area,
            cos_light: cos(x1, x0, n0),
            delta: false,
        };
        let got_connections = [
            hit_weight(c0.quantities(), pick / area, emission_pdf_w),
            light_sample_weight(c1.quantities(), &il, pick, cos(x1, x0, n1), lam(x1, x0, n1), lam(x1, x2, n1), &f),
            connection_weight(
                c2.quantities(),
                l1.quantities(),
                lam(x2, x1, n2) * cos(x2, x1, n1) / d2(x1, x2),
                lam(x1, x2, n1) * cos(x1, x2, n2) / d2(x1, x2),
                lam(x2, cam, n2),
                lam(x1, x0, n1),
                &f,
            ),
            camera_weight(l2.quantities(), pc2, light_paths, lam(x2, x1, n2), &f),
        ];
        let got_merges = [
            merge_weight(c1.quantities(), l1.quantities(), lam(x1, x0, n1), lam(x1, x2, n1), &f),
            merge_weight(c2.quantities(), l2.quantities(), lam(x2, x1, n2), lam(x2, cam, n2), &f),
        ];
        let all: Vec<f32> = connections.iter().chain(if merging { &merges[..] } else { &[] }).copied().collect();
        let total: f64 = all.iter().map(|&q| (q as f64).powi(2)).sum();
        let expect = |q: f32| (q as f64).powi(2) / total;
        let mut sum = 0.0;
        for (s, (&q, &w)) in connections.iter().zip(&got_connections).enumerate() {
            assert!(
                (w as f64 - expect(q)).abs() < 1e-3 * expect(q),
                "merging {merging}, s = {s}: {w} vs {}",
                expect(q)
            );
            sum += w as f64;
        }
        if merging {
            for (i, (&q, &w)) in merges.iter().zip(&got_merges).enumerate() {
                assert!((w as f64 - expect(q)).abs() < 1e-3 * expect(q), "merge at x{}: {w} vs {}", i + 1, expect(q));
                sum += w as f64;
            }
        }
        assert!((sum - 1.0).abs() < 1e-4, "merging {merging}: the weights add to {sum}");
        // The path-and-light mode on this path (it reaches the light from a diffuse vertex,
        // so light tracing does not share it): BSDF hit against light sample alone.
        if !merging {
            use crate::integrator::bidir::connect::{pl_hit_weight, pl_light_sample_weight};
            let shared = [connections[0], connections[1]];
            let total: f64 = shared.iter().map(|&q| (q as f64).powi(2)).sum();
            let got = [
                // A hit from a diffuse vertex: the camera path passes no light-tracing term.
                pl_hit_weight(c0.d_vcm, 0.0, pick / area, emission_pdf_w),
                pl_light_sample_weight(&il, pick, lam(x1, x0, n1)),
            ];
            for (&q, &w) in shared.iter().zip(&got) {
                let e = (q as f64).powi(2) / total;
                assert!((w as f64 - e).abs() < 1e-3 * e, "path+light: {w} vs {e} ({got:?})");
            }
        }
        // Every strategy has a weight well above f32's rounding on this path, so the
        // relative comparison above tests each of them.
        assert!(got_connections.iter().all(|&w| w > 1e-4), "{got_connections:?}");
    }
}

/// path+light's weights on a caustic seen directly (camera -> wall -> mirror -> light): the
/// camera's BSDF hit on the light against light tracing from the light through the mirror,
/// the power heuristic of the two explicit path densities (Veach's products; the mirror's
/// delta density cancels, its area conversions stay), adding to one.
#[test]
fn path_light_weights_on_a_caustic_are_the_power_heuristic() {
    use crate::integrator::bidir::IterFactors;
    use crate::integrator::bidir::connect::{pl_camera_weight, pl_hit_weight};
    use crate::integrator::bidir::walk::mis;
    use glam::Vec3;
    use std::f32::consts::PI;

    let (x2, n2) = (Vec3::new(-1.0, 0.6, 0.4), Vec3::X);
    let (x1, n1) = (Vec3::new(0.3, 0.0, -0.1), Vec3::Y);
    // The light where the mirror reflects the ray from x2, on the ceiling (y = 1).
    let d = (x1 - x2).normalize();
    let r = d - 2.0 * d.dot(n1) * n1;
    let (x0, n0) = (x1 + r * (1.0 / r.y), Vec3::NEG_Y);
    let cam = Vec3::new(0.2, 0.5, 3.0);
    let (area, pick, light_paths, pixels_per_area) = (0.25f32, 0.7f32, 1000.0f32, 5000.0f32);
    let cos = |a: Vec3, b: Vec3, n: Vec3| (b - a).normalize().dot(n).abs();
    let d2 = |a: Vec3, b: Vec3| (b - a).length_squared();
    let lam = |a: Vec3, b: Vec3, n: Vec3| cos(a, b, n) / PI;
    let cos_cam = (x2 - cam).normalize().dot(Vec3::NEG_Z);
    let cam_pdf_w = pixels_per_area / (cos_cam * cos_cam * cos_cam);
    let pc2 = cam_pdf_w * cos(cam, x2, n2) / d2(cam, x2);
    let q_hit = pc2 * (lam(x2, x1, n2) * cos(x2, x1, n1) / d2(x1, x2)) * (cos(x1, x0, n0) / d2(x1, x0));
    let q_lt =
        light_paths * (pick / area) * (lam(x0, x1, n0) * cos(x0, x1, n1) / d2(x0, x1)) * (cos(x1, x2, n2) / d2(x1, x2));

    let f = IterFactors::new(0.01, light_paths, false);
    let start = |d_vcm: f32, d_vc: f32| subpath_start(d_vcm, d_vc, &f);
    let mut c = start(mis(light_paths / cam_pdf_w), 0.0);
    c.arrive_at(cos(cam, x2, n2), d2(cam, x2).sqrt());
    c.leave(cos(x2, x1, n2), lam(x2, x1, n2), lam(x2, cam, n2), false, &f);
    c.arrive_at(cos(x2, x1, n1), d2(x1, x2).sqrt());
    c.leave(cos(x1, x0, n1), 1.0, 0.0, true, &f);
    c.arrive_at(cos(x1, x0, n0), d2(x1, x0).sqrt());
    let emission_pdf_w = (1.0 / area) * lam(x0, x1, n0) * pick;
    let mut l = start(mis(pick / area / emission_pdf_w), mis(cos(x0, x1, n0) / emission_pdf_w));
    l.arrive_at(cos(x0, x1, n1), d2(x0, x1).sqrt());
    l.leave(cos(x1, x2, n1), 1.0, 0.0, true, &f);
    l.arrive_at(cos(x1, x2, n2), d2(x1, x2).sqrt());

    let got = [
        pl_hit_weight(c.d_vcm, c.d_pl, pick / area, emission_pdf_w),
        pl_camera_weight(l.d_pl, pc2, light_paths, lam(x2, x1, n2)),
    ];
    let total = (q_hit as f64).powi(2) + (q_lt as f64).powi(2);
    for (&q, &w) in [q_hit, q_lt].iter().zip(&got) {
        let e = (q as f64).powi(2) / total;
        assert!((w as f64 - e).abs() < 1e-3 * e, "{w} vs {e} ({got:?})");
    }
    // Both strategies matter on this path: the comparison tests each.
    assert!(got.iter().all(|&w| w > 1e-3), "{got:?}");
}

/// A subpath before its first segment with the running quantities `d_vcm` and `d_vc` (the
/// others follow from them under `f`), as both MIS tests start their walks.
fn subpath_start(
    d_vcm: f32,
    d_vc: f32,
    f: &crate::integrator::bidir::IterFactors,
) -> crate::integrator::bidir::walk::PathState {
    crate::integrator::bidir::walk::PathState {
        ray: crate::geometry::Ray::new(glam::Vec3::ZERO, glam::Vec3::Z),
        throughput: glam::Vec3::ONE,
        len: 0,
        d_vcm,
        d_vc,
        d_vm: d_vc * f.mis_vc,
        d_pl: d_vc,
        infinite_start: false,
        falloff_free: false,
        after_delta: false,
    }
}

/// `--light-paths` out of range is refused in one line naming the option.
#[test]
fn light_paths_out_of_range_is_refused() {
    for v in [0.0, -1.0, f64::NAN, 1e6] {
        let r = crate::request::Request { light_paths: Some(v), ..Default::default() };
        let names: crate::request::Names =
            |f| if f == crate::request::Field::LightPaths { "--light-paths" } else { "?" };
        let err = r.apply(Settings::default(), names);
        let msg = err.expect_err("out of range").to_string();
        assert!(msg.starts_with("--light-paths (light subpaths per pixel and sample)"), "{msg}");
    }
}

/// `--integrator auto` (the default): path+light where smooth mirrors or glass carry light
/// from emissive triangles, the path tracer for scenes without such caustics (a diffuse box,
/// the CS184 boxes whose light is an area light), below two bounces, and where path+light
/// cannot run (adaptive sampling); a render plan holds the kind chosen.
#[test]
fn auto_chooses_path_light_for_caustics_from_emissive_triangles() {
    use crate::integrator::plan::RenderPlan;
    let cases = [
        ("obj/CornellBox/CornellBox-Sphere.obj", 5, false, IntegratorKind::PathLight),
        ("obj/CornellBox/CornellBox-Sphere.obj", 1, false, IntegratorKind::Wavefront),
        ("obj/CornellBox/CornellBox-Sphere.obj", 5, true, IntegratorKind::Wavefront),
        ("obj/CornellBox/CornellBox-Original.obj", 5, false, IntegratorKind::Wavefront),
        ("cs184/sky/CBspheres.dae", 5, false, IntegratorKind::Wavefront),
    ];
    for (file, depth, adaptive, expect) in cases {
        let Some(scene) = common::load_scene(file) else { return };
        let mut s = settings(4, depth);
        assert_eq!(s.execution.integrator, IntegratorKind::Auto, "auto is the default");
        if adaptive {
            s.sampling.adaptive = Some((8, 0.05));
        }
        let plan = RenderPlan::new(&scene, &s);
        let e = plan.effects();
        assert_eq!(e.integrator_kind, expect, "{file} -m {depth} adaptive {adaptive}: {}", e.integrator.reason);
        assert_eq!(plan.settings().execution.integrator, expect, "{file}: the plan holds the choice");
        if adaptive {
            assert!(e.integrator.reason.contains("adaptive"), "{}", e.integrator.reason);
        }
    }
}
