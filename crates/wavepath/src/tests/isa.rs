//! One switch forces every SIMD kernel onto its scalar path (`Settings::isa`, `--isa`): the
//! BVH's box tests and leaf filter, the eight-lane camera rays, shading lanes and random
//! streams. Every path gives the same bits, so whole renders are compared here.

use crate::accel::build;
use crate::cpu::Isa;
use crate::load::default_scene;
use crate::render::render;
use crate::scene::Scene;
use crate::settings::{IntegratorKind, Settings, Shading};

fn image(scene: &Scene, s: &Settings) -> Vec<[u32; 3]> {
    let (accel, _) = build(scene, s);
    let (film, stats) = render(scene, accel.as_ref(), s).unwrap();
    assert_eq!(stats.invalid_samples, 0);
    film.pixels.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
}

/// Diffuse scenes (the shading-lanes kernel, with area lights and with emissive triangles),
/// mirrors and glass (the per-path kernel), a pinhole (camera lanes), the default
/// scene's spheres, and path+light's light subpaths: each instruction set the CPU
/// offers gives the scalar image bit for bit, with enough light in it to mean something.
#[test]
fn every_instruction_set_renders_the_scalar_image() {
    let mut scenes = vec![("default", default_scene())];
    for name in ["CBbunny.dae", "CBspheres.dae"] {
        if let Some(scene) = crate::tests::common::load_scene(&format!("cs184/sky/{name}")) {
            scenes.push((name, scene));
        }
    }
    // The light quad as one-sided emissive triangles, under MIS (the standard dialect): the
    // lane kernel's lights that are not area lights.
    let mut emissive = default_scene();
    emissive.lights.clear();
    emissive.source.dialect = crate::cs184::Dialect::Standard;
    emissive.materials[3].two_sided_emission = false;
    scenes.push(("default with an emissive quad", emissive));
    let mut kinds = vec![IntegratorKind::Auto; scenes.len()];
    // path+light (the light side's starts in lanes, its batched traversal, its splats) on
    // glass and a mirror under one-sided and two-sided emissive triangles.
    if let Some(sphere) = crate::tests::common::load_scene("obj/CornellBox/CornellBox-Sphere.obj") {
        let mut two_sided = sphere.clone();
        two_sided.materials.iter_mut().filter(|m| m.emission != glam::Vec3::ZERO).for_each(|m| {
            m.two_sided_emission = true;
        });
        scenes.push(("CornellBox-Sphere, path+light", sphere));
        scenes.push(("CornellBox-Sphere with two-sided emitters, path+light", two_sided));
        kinds.extend([IntegratorKind::PathLight; 2]);
    }
    for ((name, scene), kind) in scenes.iter().zip(kinds) {
        let mut base = Settings::default();
        base.image.width = 40;
        base.image.height = 30;
        base.sampling.spp = 4;
        base.sampling.light_samples = 2;
        base.paths.max_depth = 4;
        base.paths.shading = Shading::Global;
        base.execution.threads = 1;
        base.execution.integrator = kind;
        let mut scene = scene.clone();
        scene.camera.fit_aspect(40.0 / 30.0);
        let scalar = image(&scene, &base.clone().with(|s| s.execution.isa = Isa::Scalar));
        let lit = scalar.iter().filter(|p| p.iter().any(|&b| f32::from_bits(b) > 0.0)).count();
        // The OBJ box, framed from its bounding box, fills a fifth of the frame.
        let need = if kind == IntegratorKind::PathLight { scalar.len() / 8 } else { scalar.len() / 4 };
        assert!(lit > need, "{name}: only {lit} lit pixels");
        // Each path the CPU runs, once: a request this CPU cannot honour falls back to one
        // already compared.
        let mut ran = vec![Isa::Scalar];
        for isa in [Isa::Portable, Isa::Sse, Isa::Avx2, Isa::Avx512] {
            if ran.contains(&isa.effective()) {
                eprintln!("{name}: {} runs as {}, compared already", isa.name(), isa.effective().name());
                continue;
            }
            ran.push(isa.effective());
            let got = image(&scene, &base.clone().with(|s| s.execution.isa = isa));
            let differ = got.iter().zip(&scalar).filter(|(a, b)| a != b).count();
            assert_eq!(
                differ,
                0,
                "{name}: {} ({}) differs from scalar in {differ} pixels",
                isa.name(),
                isa.effective().name()
            );
        }
    }
}

/// The comparisons above mean something only where the SIMD paths run: on a CPU that has
/// AVX-512 (F, VL, DQ, BW), AVX2 (with FMA, BMI1, POPCNT) or SSE4.1, by the standard
/// library's own detection, the requests resolve to them, and the default request takes
/// the widest.
#[test]
fn simd_paths_run_where_the_cpu_has_them() {
    #[cfg(target_arch = "x86_64")]
    {
        let avx2 = std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("fma")
            && std::is_x86_feature_detected!("bmi1")
            && std::is_x86_feature_detected!("popcnt");
        let avx512 = avx2
            && std::is_x86_feature_detected!("avx512f")
            && std::is_x86_feature_detected!("avx512vl")
            && std::is_x86_feature_detected!("avx512dq")
            && std::is_x86_feature_detected!("avx512bw");
        if avx2 {
            assert_eq!(Isa::Avx2.effective(), Isa::Avx2);
            assert!("avx512".parse::<Isa>().unwrap().avx2().is_some());
            assert!(Isa::Avx2.avx512().is_none());
            assert_eq!(Isa::Avx512.at_most_avx2(), Isa::Avx2);
        } else {
            eprintln!("skipped the AVX2 check: this CPU has no AVX2");
        }
        if avx512 {
            assert_eq!(Isa::default().effective(), Isa::Avx512);
            assert!(Isa::Avx512.avx512().is_some());
        } else {
            assert_eq!(Isa::Avx512.effective(), if avx2 { Isa::Avx2 } else { Isa::Avx512.effective() });
            assert!(Isa::Avx512.avx512().is_none());
            eprintln!("skipped the AVX-512 check: this CPU has no AVX-512");
        }
        if std::is_x86_feature_detected!("sse4.1") {
            assert_eq!(Isa::Sse.effective(), Isa::Sse);
            assert!(Isa::Sse.sse().is_some() && Isa::Sse.avx2().is_none());
        } else {
            eprintln!("skipped the SSE4.1 check: this CPU has no SSE4.1");
        }
    }
    assert_eq!(Isa::Scalar.effective(), Isa::Scalar);
    assert!(Isa::Scalar.sse().is_none() && Isa::Scalar.avx2().is_none());
    // The portable lanes run on every CPU, and are what a CPU without the x86 sets shades with.
    assert_eq!(Isa::Portable.effective(), Isa::Portable);
    assert!(Isa::Portable.shades_in_lanes() && !Isa::Scalar.shades_in_lanes());
    #[cfg(not(target_arch = "x86_64"))]
    assert_eq!(Isa::default().effective(), Isa::Portable);
}
