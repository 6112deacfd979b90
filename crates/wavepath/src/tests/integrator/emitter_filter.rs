//! The emitter filter: a ray from a path's last vertex that misses every emissive triangle is
//! not traced. It must pass every ray whose closest hit in the scene is an emitter (at shared
//! edges and vertices too, on every instruction set), and it must not change a bit of an
//! image, only the number of rays traced.

use crate::accel::{BruteForce, Bvh, Intersector, TraceCounters};
use crate::cpu::Isa;
use crate::geometry::Ray;
use crate::integrator::emitter_filter::EmitterFilter;
use crate::integrator::plan::{Extent, RenderPlan};
use crate::load::default_scene;
use crate::render::render_plan_sums;
use crate::sampling::Sampler;
use crate::scene::{Material, Scene};
use crate::settings::IntegratorKind;
use crate::tests::common::meshgen::{icosphere, quad};
use crate::tests::common::render;
use glam::{Vec3, vec3};
use std::sync::atomic::AtomicBool;

/// An icosphere with every third triangle emissive: each emitter shares its edges and
/// vertices with triangles that do not emit.
fn speckled_sphere() -> Scene {
    let mut mesh = icosphere(12);
    let n = mesh.triangles.len();
    mesh.material_ids = Default::default();
    for i in 0..n {
        mesh.material_ids.push((i % 3 == 0) as u32);
    }
    Scene {
        mesh,
        materials: vec![Material::diffuse("wall", Vec3::splat(0.5)), Material::emitter("light", Vec3::ONE)],
        ..Scene::default()
    }
}

/// From inside the sphere toward every vertex, points on every edge, and random directions,
/// and from outside through the same points: wherever the scene's closest hit (the BVH on
/// each instruction set, and brute force) is an emitter, the filter passes the ray. From
/// inside, a ray leaves through one triangle, so away from the shared edges the filter also
/// stops the rays that leave through a wall (two thirds of them): it does filter.
#[test]
fn the_filter_passes_every_ray_whose_closest_hit_emits() {
    let scene = speckled_sphere();
    let m = &scene.mesh;
    let mut targets = m.positions.clone();
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (m.positions[t[k] as usize], m.positions[t[(k + 1) % 3] as usize]);
            targets.extend([0.5 * (a + b), a + (b - a) * 0.25]);
        }
    }
    let mut s = Sampler::for_sample(7, 0, 0);
    for _ in 0..20_000 {
        let d = Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5);
        targets.push(d.normalize_or(Vec3::Y));
    }
    let brute = BruteForce::new(&scene);
    let mut tc = TraceCounters::default();
    for isa in [Isa::Scalar, Isa::Sse, Isa::Avx2, Isa::Avx512] {
        let filter = EmitterFilter::new(&scene, false, isa).expect("the sphere has emitters");
        let bvh = Bvh::build(&scene).with_isa(isa);
        let (mut emitting, mut stopped) = (0, 0);
        for (k, &p) in targets.iter().enumerate() {
            let jitter = Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5) * 0.1;
            let inside = Ray::new(jitter, p - jitter);
            let far = p * 3.0 + jitter;
            let outside = Ray::new(far, p - far);
            for (ray, accel) in [(inside, &bvh as &dyn Intersector), (outside, &bvh), (inside, &brute)] {
                let Some(hit) = accel.closest_hit(&ray, &mut tc) else { continue };
                let passes = filter.may_find_light(&ray);
                if hit.prim % 3 == 0 {
                    emitting += 1;
                    assert!(passes, "{isa:?}, {}: target {k} {p:?}, closest hit {} emits", accel.name(), hit.prim);
                } else {
                    stopped += !passes as usize;
                }
            }
        }
        assert!(emitting > 10_000, "{isa:?}: {emitting} rays hit an emitter");
        assert!(stopped > emitting, "{isa:?}: {stopped} rays stopped, {emitting} hit an emitter");
    }
}

/// The filter is built only where emissive triangles are all the light a ray can find.
#[test]
fn the_filter_exists_where_emitters_are_the_only_light_rays_find() {
    let isa = Isa::detect();
    assert!(EmitterFilter::new(&speckled_sphere(), false, isa).is_some());
    assert!(EmitterFilter::new(&speckled_sphere(), true, isa).is_none(), "light from infinity or area lights");
    let mut dark = speckled_sphere();
    dark.materials[1] = Material::diffuse("not a light", Vec3::ONE);
    assert!(EmitterFilter::new(&dark, false, isa).is_none(), "nothing emits");
    let mut sphere_light = speckled_sphere();
    sphere_light.spheres.push(crate::scene::Sphere { center: Vec3::ZERO, radius: 0.1, material: 1 });
    assert!(EmitterFilter::new(&sphere_light, false, isa).is_none(), "an emissive sphere");
}

/// A ceiling seen from below sends its paths down to a floor beside a small emitter: the
/// last vertices of depth-2 paths sit next to the light.
pub fn ceiling_scene(aspect: f32) -> Scene {
    let mut scene = crate::tests::common::meshgen::emitter_above_floor(aspect);
    // Wound to face the floor, like the emitter.
    let y = 0.5;
    quad(&mut scene.mesh, [vec3(-5.0, y, -5.0), vec3(5.0, y, -5.0), vec3(5.0, y, 5.0), vec3(-5.0, y, 5.0)], 0);
    scene.camera = crate::scene::Camera::look_at(vec3(0.0, 0.1, 0.3), vec3(0.0, y, 0.0), Vec3::Y, 50.0, aspect);
    scene
}

/// Renders with the filter give the bits of renders that trace every last ray, with fewer
/// extension rays: Lambertian vertices under MIS (the ceiling scene), and mirror and glass
/// spheres lit by an emissive quad (the default scene in the standard dialect), both
/// integrators, with Russian roulette.
#[test]
fn the_filter_changes_no_bit_and_saves_rays() {
    let mut spheres = default_scene();
    spheres.lights.clear();
    spheres.source.dialect = crate::cs184::Dialect::Standard;
    let never = AtomicBool::new(false);
    for (name, scene) in [("ceiling", ceiling_scene(4.0 / 3.0)), ("default, emissive quad", spheres)] {
        for integrator in [IntegratorKind::Wavefront, IntegratorKind::Recursive] {
            let s = render::settings(16, 12, 3, 8).with(|s| {
                s.execution.integrator = integrator;
                s.paths.roulette.continue_prob = 0.8;
            });
            let (accel, _) = crate::accel::build(&scene, &s);
            let plan = RenderPlan::new(&scene, &s);
            assert!(plan.effects().mis, "{name}");
            let (filtered, fs) = render_plan_sums(&plan, accel.as_ref(), Extent::WHOLE, &|_| {}, &never).unwrap();
            let every = plan.tracing_every_ray();
            let (traced, ts) = render_plan_sums(&every, accel.as_ref(), Extent::WHOLE, &|_| {}, &never).unwrap();
            assert_eq!(filtered.pixels, traced.pixels, "{name}, {integrator:?}");
            assert!(filtered.pixels.iter().any(|p| p.sum.max_element() > 0.0), "{name}: a black image");
            assert!(
                fs.extension_rays < ts.extension_rays,
                "{name}, {integrator:?}: {} extension rays with the filter, {} without",
                fs.extension_rays,
                ts.extension_rays
            );
            assert_eq!((fs.camera_rays, fs.shadow_rays), (ts.camera_rays, ts.shadow_rays), "{name}");
        }
    }
}
