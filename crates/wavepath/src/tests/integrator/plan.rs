//! The render plan: built once, it renders any extent (cell, sample range) of its image, and
//! the extents' sums are the whole render's.

use crate::integrator::plan::{Extent, RenderPlan};
use crate::render::{Canvas, Interrupted, render_plan, render_plan_sums, render_sums};
use crate::settings::{Cell, IntegratorKind, Settings};
use crate::tests::common::render;
use std::sync::atomic::{AtomicBool, Ordering};

const W: usize = 23;
const H: usize = 17;

/// Uneven cells that tile the image (rows and columns of different sizes, one a single pixel).
fn cells() -> Vec<Cell> {
    let (xs, ys) = ([0, 1, 9, W], [0, 6, 7, H]);
    let mut out = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            out.push(Cell { x: xs[i], y: ys[j], w: xs[i + 1] - xs[i], h: ys[j + 1] - ys[j] });
        }
    }
    out
}

/// The default scene (CS184 area light) and one lit by an emissive mesh with MIS, both
/// integrators, global illumination with roulette.
fn cases() -> Vec<(&'static str, crate::scene::Scene, Settings)> {
    let base = render::small_settings(W, H, 4, 6).with(|s| s.paths.roulette.continue_prob = 0.7);
    let mut out = Vec::new();
    for integrator in [IntegratorKind::Wavefront, IntegratorKind::Recursive] {
        let s = base.clone().with(|s| s.execution.integrator = integrator);
        out.push(("default", crate::load::default_scene(), s.clone()));
        out.push(("mis", super::mis::scene(), s));
    }
    out
}

/// One plan, rendered cell by cell, gives every pixel the bits of the whole-image render (the
/// split render's and the viewer's bands' promise), and nothing outside the cell.
#[test]
fn one_plan_renders_cells_bit_identical_to_the_whole_image() {
    let never = AtomicBool::new(false);
    for (name, scene, s) in cases() {
        let (accel, _) = crate::accel::build(&scene, &s);
        let (whole, _) = render_sums(&scene, accel.as_ref(), &s, &|_| {}).unwrap();
        assert!(whole.pixels.iter().all(|p| p.taken == 6), "{name}");
        let plan = RenderPlan::new(&scene, &s);
        let mut merged = crate::film::Accumulator::new(W, H);
        for cell in cells() {
            let extent = Extent { cell: Some(cell), samples: None };
            let (sums, _) = render_plan_sums(&plan, accel.as_ref(), extent, &|_| {}, &never).unwrap();
            for y in 0..H {
                for x in 0..W {
                    let (p, inside) =
                        (y * W + x, (cell.x..cell.x + cell.w).contains(&x) && (cell.y..cell.y + cell.h).contains(&y));
                    if inside {
                        merged.pixels[p] = sums.pixels[p];
                    } else {
                        assert_eq!(sums.pixels[p].taken, 0, "{name}: ({x}, {y}) outside {cell:?}");
                    }
                }
            }
        }
        assert_eq!(merged.pixels, whole.pixels, "{name} {:?}", s.execution.integrator);
        // The film of the whole extent is the plain render's too.
        let film = render_plan(&plan, accel.as_ref(), Extent::WHOLE, &|_| {}, &never).unwrap().film;
        assert_eq!(film, whole.to_film(), "{name}");
    }
}

/// Sample ranges of one plan take exactly their samples: merged, they are the whole
/// render's sums up to the order of the f64 additions (a wrong index would change a pixel's
/// sum by a whole sample's radiance, orders of magnitude above the 1e-12 allowed).
#[test]
fn one_plan_renders_sample_ranges_that_merge_into_the_whole_render() {
    let never = AtomicBool::new(false);
    for (name, scene, s) in cases() {
        let (accel, _) = crate::accel::build(&scene, &s);
        let (whole, _) = render_sums(&scene, accel.as_ref(), &s, &|_| {}).unwrap();
        let plan = RenderPlan::new(&scene, &s);
        let mut merged = crate::film::Accumulator::new(W, H);
        for range in [(0, 1), (1, 4), (4, 6)] {
            let extent = Extent { cell: None, samples: Some(range) };
            let (sums, _) = render_plan_sums(&plan, accel.as_ref(), extent, &|_| {}, &never).unwrap();
            assert!(sums.pixels.iter().all(|p| p.taken == range.1 - range.0), "{name} {range:?}");
            for (m, p) in merged.pixels.iter_mut().zip(&sums.pixels) {
                m.merge(p);
            }
        }
        let mut lit = 0;
        for (i, (m, w)) in merged.pixels.iter().zip(&whole.pixels).enumerate() {
            assert_eq!((m.taken, m.valid), (w.taken, w.valid), "{name}: pixel {i}");
            let err = (m.sum - w.sum).abs().max_element();
            assert!(err <= 1e-12 * w.sum.abs().max_element().max(1.0), "{name}: pixel {i}: {} vs {}", m.sum, w.sum);
            lit += (w.sum.max_element() > 0.0) as usize;
        }
        assert!(lit > W * H / 4, "{name}: {lit} lit pixels");
    }
}

/// A cell or sample range in the settings is not part of the plan: the plan renders the
/// extent it is given, and the settings' extent is what the old entry points pass.
#[test]
fn the_plan_leaves_the_extent_out() {
    let scene = crate::load::default_scene();
    let cell = Cell { x: 2, y: 3, w: 5, h: 4 };
    let s = render::small_settings(W, H, 2, 3).with(|s| {
        s.image.cell = Some(cell);
        s.sampling.sample_range = Some((1, 3));
    });
    let plan = RenderPlan::new(&scene, &s);
    assert_eq!(plan.settings().image.cell, None);
    assert_eq!(plan.settings().sampling.sample_range, None);
    assert_eq!(Extent::of(&s), Extent { cell: Some(cell), samples: Some((1, 3)) });
    let (accel, _) = crate::accel::build(&scene, &s);
    let never = AtomicBool::new(false);
    let (sums, _) = render_plan_sums(&plan, accel.as_ref(), Extent::WHOLE, &|_| {}, &never).unwrap();
    assert!(sums.pixels.iter().all(|p| p.taken == 3));
    let (part, _) = render_sums(&scene, accel.as_ref(), &s, &|_| {}).unwrap();
    let inside =
        |i: usize| (cell.x..cell.x + cell.w).contains(&(i % W)) && (cell.y..cell.y + cell.h).contains(&(i / W));
    for (i, p) in part.pixels.iter().enumerate() {
        assert_eq!(p.taken, if inside(i) { 2 } else { 0 }, "pixel {i}");
    }
}

/// A canvas that renders extents one after another (the viewer's passes of sample ranges,
/// each cut into cells) holds, bit for bit, the separate renders of those extents merged in
/// the same order: keeping the sums and the worker queues from one extent to the next changes
/// nothing. Its statistics count the canvas's samples; a stopped render says so, and a
/// render of another image size is refused.
#[test]
fn a_canvas_holds_its_extents_merged_in_order() {
    let never = AtomicBool::new(false);
    for (name, scene, s) in cases() {
        let (accel, _) = crate::accel::build(&scene, &s);
        let plan = RenderPlan::new(&scene, &s);
        let mut canvas = Canvas::new(W, H);
        let mut merged = crate::film::Accumulator::new(W, H);
        for range in [(0, 2), (2, 5), (5, 6)] {
            for cell in cells() {
                let extent = Extent { cell: Some(cell), samples: Some(range) };
                let stats = canvas.render(&plan, accel.as_ref(), extent, &|_| {}, &never).unwrap();
                assert_eq!(stats.samples_per_pixel, vec![range.1; cell.w * cell.h], "{name} {range:?} {cell:?}");
                let (sums, _) = render_plan_sums(&plan, accel.as_ref(), extent, &|_| {}, &never).unwrap();
                for (m, p) in merged.pixels.iter_mut().zip(&sums.pixels) {
                    m.merge(p);
                }
            }
        }
        assert_eq!(canvas.sums().pixels, merged.pixels, "{name} {:?}", s.execution.integrator);
        assert!(canvas.sums().pixels.iter().all(|p| p.taken == 6), "{name}");
        assert!(canvas.sums().pixels.iter().filter(|p| p.sum.max_element() > 0.0).count() > W * H / 4, "{name}");
        canvas.clear();
        assert!(canvas.sums().pixels.iter().all(|p| *p == crate::film::PixelSums::default()), "{name}");
    }
    let scene = crate::load::default_scene();
    let s = render::small_settings(W, H, 2, 3);
    let (accel, _) = crate::accel::build(&scene, &s);
    let plan = RenderPlan::new(&scene, &s);
    let stop = AtomicBool::new(false);
    stop.store(true, Ordering::Relaxed);
    let err = Canvas::new(W, H).render(&plan, accel.as_ref(), Extent::WHOLE, &|_| {}, &stop).unwrap_err();
    assert!(err.is::<Interrupted>(), "{err:#}");
    let err = Canvas::new(W + 1, H).render(&plan, accel.as_ref(), Extent::WHOLE, &|_| {}, &never).unwrap_err();
    assert!(err.to_string().contains("canvas") && !err.is::<Interrupted>(), "{err}");
}

// ---------------------------------------------------------------------------------------
// The camera a plan fits
// ---------------------------------------------------------------------------------------

/// The repository's CS184 COLLADA scene, whose camera follows the reference's pixel rule.
fn cs184_dae() -> crate::scene::Scene {
    let path = crate::tests::common::repo_root().join("scenes/cornell_mesh.dae");
    let scene = crate::load::load(&path, &crate::load::LoadOptions::default()).unwrap();
    assert!(matches!(scene.camera.fit, crate::scene::FovFit::Cs184 { .. }), "{:?}", scene.camera.fit);
    scene
}

/// Renders of one CS184 scene at two sizes under both rules, the request applied as the
/// command line applies it, each see through their own fit, and the scene is the value it
/// was loaded as: nothing writes a fit into it, so a second size fits from the file's camera.
#[test]
fn renders_at_two_sizes_leave_a_cs184_scene_and_its_camera_as_loaded() {
    use crate::request::Request;
    use crate::scene::FovRule;
    let scene = cs184_dae();
    let request = |w, h, fov| Request { resolution: Some((w, h)), fov: Some(fov), ..Request::default() };
    // The request's own camera step applies the lens alone: no fit.
    assert_eq!(request(20, 30, FovRule::Frame).camera(scene.camera), scene.camera);
    let (loaded, camera) = (format!("{scene:?}"), scene.camera);
    let (accel, _) = crate::accel::build(&scene, &Settings::default());
    let mut cameras = Vec::new();
    for fov in [FovRule::Cs184, FovRule::Frame] {
        for (w, h) in [(32, 24), (20, 30)] {
            let s = request(w, h, fov).apply(render::settings(1, 1, 1, 1), |_| "-x").unwrap();
            assert_eq!((s.image.width, s.image.height, s.image.fov), (w as usize, h as usize, fov));
            let plan = RenderPlan::new(&scene, &s);
            assert_eq!(*plan.camera(), camera.fitted(fov, w as usize, h as usize));
            let never = AtomicBool::new(false);
            let film = render_plan(&plan, accel.as_ref(), Extent::WHOLE, &|_| {}, &never).unwrap().film;
            assert!(film.pixels.iter().any(|p| p.max_element() > 0.0), "{fov:?} {w}x{h}: a black image");
            cameras.push(*plan.camera());
            assert_eq!(scene.camera, camera, "{fov:?} {w}x{h}");
        }
    }
    // Four different fits of the one camera (the sizes and the rules both reach the render).
    for (i, a) in cameras.iter().enumerate() {
        assert!(cameras[i + 1..].iter().all(|b| (a.hfov_deg, a.vfov_deg) != (b.hfov_deg, b.vfov_deg)), "{cameras:?}");
    }
    assert_eq!(format!("{scene:?}"), loaded);
}

/// A plan at W x H with `--fov frame` traces the camera rays of the scene's camera fitted by
/// hand (the whole 800x600 picture's vertical field, then the aspect), bit for bit; the
/// default rule's are those of the camera's own fit. The expectation is built from the
/// camera's parts, not from the function the plan calls.
#[test]
fn a_plan_traces_the_rays_of_the_camera_fitted_by_hand() {
    use crate::scene::FovRule;
    let scene = cs184_dae();
    let (w, h) = (W, H);
    let mut frame = scene.camera;
    frame.whole_frame();
    frame.fit_to(w as f32, h as f32);
    let mut own = scene.camera;
    own.fit_to(w as f32, h as f32);
    assert_ne!((frame.hfov_deg, frame.vfov_deg), (own.hfov_deg, own.vfov_deg));
    for (fov, by_hand) in [(FovRule::Frame, frame), (FovRule::Cs184, own)] {
        let s = render::settings(w, h, 1, 1).with(|s| s.image.fov = fov);
        let plan = RenderPlan::new(&scene, &s);
        for (x, y) in [(0, 0), (w - 1, 0), (7, 11), (w - 1, h - 1), (0, h - 1)] {
            let ray = plan.transport().camera_ray(x as u32, y as u32, w, h, 0, 1);
            let expected = by_hand.generate_ray((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            assert_eq!(ray, expected, "{fov:?} ({x}, {y})");
        }
    }
}

/// The normals view of a plan sees through the plan's fitted camera, as light transport does.
#[test]
fn a_plans_normals_view_sees_through_its_fitted_camera() {
    use crate::render::render_normals;
    use crate::scene::FovRule;
    let scene = cs184_dae();
    let s = render::settings(W, H, 1, 1).with(|s| {
        s.paths.shading = crate::settings::Shading::Normals;
        s.image.fov = FovRule::Frame;
    });
    let (accel, _) = crate::accel::build(&scene, &s);
    let plan = RenderPlan::new(&scene, &s);
    let never = AtomicBool::new(false);
    let film = render_plan(&plan, accel.as_ref(), Extent::WHOLE, &|_| {}, &never).unwrap().film;
    let mut by_hand = scene.camera;
    by_hand.whole_frame();
    by_hand.fit_to(W as f32, H as f32);
    assert_eq!(film, render_normals(&scene, &by_hand, accel.as_ref(), &s).0);
    assert_ne!(film, render_normals(&scene, &scene.camera, accel.as_ref(), &s).0);
}
