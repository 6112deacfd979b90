//! Ray origins offset by per-point error bounds (src/geometry/offset.rs): a ray leaving a
//! surface point never finds its own surface again, at any scale and any direction down to
//! grazing, and the offset never steps over a thin feature.
//!
//! Surface points come from the renderer's own pipeline: a ray is traced at a random point of
//! the surface and the hit reconstructed with `Scene::surface_point`, so the error bound under
//! test is the one shading sees.

use crate::accel::{BruteForce, Intersector, TraceCounters, build};
use crate::geometry::Ray;
use crate::geometry::offset::{offset_origin, shadow_ray};
use crate::sampling::{Frame, Sampler};
use crate::scene::{Material, Mesh, Scene, Sphere, SurfacePoint};
use crate::tests::common::meshgen::quad;
use glam::{Vec3, vec3};

/// Rays per configuration; every test runs at least 10^5 in total.
const RAYS: usize = 25_000;

fn scene(mesh: Mesh, spheres: Vec<Sphere>) -> Scene {
    Scene {
        name: "offsets".into(),
        mesh,
        spheres,
        materials: vec![Material::diffuse("grey", Vec3::splat(0.5))],
        ..Scene::default()
    }
}

/// A parallelogram of two triangles: corner `o`, edges `e1`, `e2`.
fn parallelogram(mesh: &mut Mesh, o: Vec3, e1: Vec3, e2: Vec3) {
    quad(mesh, [o, o + e1, o + e1 + e2, o + e2], 0);
}

/// A direction about `n` whose cosine is uniform half of the time and log-uniform in
/// [1e-6, 1e-1] (near-grazing) otherwise.
fn direction(n: Vec3, rng: &mut Sampler) -> Vec3 {
    let (a, b) = rng.next_2d();
    let cos = if rng.next_f32() < 0.5 { 1.0 - a } else { 10f32.powf(-1.0 - 5.0 * a) };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * b;
    Frame::new(n).to_world(vec3(sin * phi.cos(), sin * phi.sin(), cos)).normalize()
}

/// A direction about `n` at least 3 degrees from grazing: camera rays that find a point.
fn camera_direction(n: Vec3, rng: &mut Sampler) -> Vec3 {
    let (a, b) = rng.next_2d();
    let cos = 0.05 + 0.95 * a;
    let sin = (1.0 - cos * cos).sqrt();
    let phi = std::f32::consts::TAU * b;
    Frame::new(n).to_world(vec3(sin * phi.cos(), sin * phi.sin(), cos)).normalize()
}

/// The surface point a ray from `from` toward `target` finds.
fn shoot(scene: &Scene, accel: &dyn Intersector, from: Vec3, target: Vec3) -> Option<(SurfacePoint, u32)> {
    let ray = Ray::new(from, (target - from).normalize());
    let hit = accel.closest_hit(&ray, &mut TraceCounters::default())?;
    Some((scene.surface_point(&ray, &hit), hit.prim))
}

/// Rays leaving random points of the single triangle in `scene` (corner `o`, edges `e1`,
/// `e2`) to both sides: none may hit anything (the triangle is all there is; one triangle,
/// not a quad, because the rounded corners of a quad far from the origin are not coplanar,
/// and a ray may then rightly hit the other half).
/// Returns (rays cast, re-hits).
fn plane_rehits(scene: &Scene, o: Vec3, e1: Vec3, e2: Vec3, seed: u64) -> (usize, usize) {
    let (accel, _) = build(scene, &crate::settings::Settings::default());
    let brute = BruteForce::new(scene);
    let n = e1.cross(e2).normalize();
    let size = e1.length().max(e2.length());
    let mut rng = Sampler::for_sample(seed, 0, 0);
    let (mut cast, mut rehits) = (0, 0);
    for i in 0..RAYS {
        let (mut s, mut t) = (0.01 + 0.98 * rng.next_f32(), 0.01 + 0.98 * rng.next_f32());
        if s + t > 0.99 {
            (s, t) = (1.0 - s, 1.0 - t);
        }
        let target = o + s * e1 + t * e2;
        let side = if rng.next_f32() < 0.5 { n } else { -n };
        // Camera rays come in from anywhere on one side, at the quad's scale.
        let from = target + size * camera_direction(side, &mut rng);
        let Some((sp, _)) = shoot(scene, accel.as_ref(), from, target) else { continue };
        // Leave to either side: reflection and transmission.
        let out_side = if rng.next_f32() < 0.5 { side } else { -side };
        let dir = direction(out_side, &mut rng);
        let ray = Ray::new(offset_origin(sp.position, sp.p_error, sp.geometric_normal, dir), dir);
        cast += 1;
        let mut c = TraceCounters::default();
        let hit = if i % 8 == 0 { brute.closest_hit(&ray, &mut c) } else { accel.closest_hit(&ray, &mut c) };
        if let Some(h) = hit {
            rehits += 1;
            if rehits <= 3 {
                eprintln!("re-hit: p {} err {} dir {dir} t {}", sp.position, sp.p_error, h.t);
            }
        }
    }
    (cast, rehits)
}

fn assert_no_plane_rehits(o: Vec3, e1: Vec3, e2: Vec3, what: &str) {
    let mesh = Mesh {
        positions: vec![o, o + e1, o + e2],
        triangles: vec![[0, 1, 2]],
        material_ids: vec![0].into(),
        ..Mesh::default()
    };
    let s = scene(mesh, vec![]);
    let (cast, rehits) = plane_rehits(&s, o, e1, e2, 7);
    assert!(cast > RAYS * 9 / 10, "{what}: only {cast} surface points found");
    assert_eq!(rehits, 0, "{what}: {rehits} of {cast} rays re-hit the surface they left");
}

/// Tilted edges (no axis-aligned plane makes the arithmetic exact by accident).
fn tilted(size: f32) -> (Vec3, Vec3) {
    let e1 = vec3(1.0, 0.31, -0.17).normalize() * size;
    let e2 = e1.cross(vec3(0.2, 1.0, 0.4)).normalize() * size;
    (e1, e2)
}

#[test]
fn no_rehits_on_large_triangles() {
    for size in [10.0, 100.0, 1e3, 1e4] {
        let (e1, e2) = tilted(size);
        assert_no_plane_rehits(-0.3 * (e1 + e2), e1, e2, &format!("tilted quad of size {size}"));
        let h = 0.5 * size;
        assert_no_plane_rehits(
            vec3(-h, 0.0, -h),
            vec3(size, 0.0, 0.0),
            vec3(0.0, 0.0, size),
            &format!("axis quad of size {size}"),
        );
    }
}

#[test]
fn no_rehits_on_tiny_triangles() {
    for (size, at) in [(1e-4, Vec3::ZERO), (1e-4, vec3(1.0, -2.0, 0.5)), (1e-4, vec3(30.0, 10.0, -20.0))] {
        let (e1, e2) = tilted(size);
        assert_no_plane_rehits(at - 0.3 * (e1 + e2), e1, e2, &format!("quad of size {size} at {at}"));
    }
}

#[test]
fn no_rehits_on_triangles_far_from_the_origin() {
    for (size, at) in [(1.0, Vec3::splat(1e5)), (10.0, vec3(1e5, -3e4, 5e4)), (0.5, vec3(-1e5, 2e3, 1e5))] {
        let (e1, e2) = tilted(size);
        assert_no_plane_rehits(at - 0.3 * (e1 + e2), e1, e2, &format!("quad of size {size} at {at}"));
    }
}

/// Rays leaving random points of one sphere: outward ones hit nothing, inward ones hit the
/// far side at the chord length 2 r cos, not the point they left.
#[test]
fn no_rehits_on_spheres() {
    for (radius, center) in [
        (1e-3, Vec3::ZERO),
        (1e-3, vec3(1.0, 2.0, 3.0)),
        (1.0, vec3(0.3, -0.2, 0.1)),
        (1e2, vec3(-50.0, 7.0, 3.0)),
        (1e4, Vec3::ZERO),
        (1.0, Vec3::splat(1e4)),
    ] {
        let s = scene(Mesh::default(), vec![Sphere { center, radius, material: 0 }]);
        let (accel, _) = build(&s, &crate::settings::Settings::default());
        let mut rng = Sampler::for_sample(11, 0, 0);
        let (mut cast, mut rehits) = (0, 0);
        for _ in 0..RAYS {
            let n0 = direction(Vec3::Y, &mut rng) * if rng.next_f32() < 0.5 { 1.0 } else { -1.0 };
            let from = center + 3.0 * radius * camera_direction(n0, &mut rng);
            let Some((sp, _)) = shoot(&s, accel.as_ref(), from, center + radius * n0) else { continue };
            let n = sp.geometric_normal;
            let inward = rng.next_f32() < 0.5;
            let dir = direction(if inward { -n } else { n }, &mut rng);
            let ray = Ray::new(offset_origin(sp.position, sp.p_error, n, dir), dir);
            cast += 1;
            let hit = accel.closest_hit(&ray, &mut TraceCounters::default());
            // In exact arithmetic: the origin is on the side the ray leaves to, and an inward
            // ray leaves the sphere after `far`.
            let (o, d, c) = (ray.origin.as_dvec3() - center.as_dvec3(), dir.as_dvec3(), radius as f64);
            let side_ok = (o.length() > c) != inward;
            let b = o.dot(d);
            let far = -b + (b * b - (o.length_squared() - c * c)).max(0.0).sqrt();
            let ok = side_ok
                && match hit {
                    None => !inward,
                    // Near-tangent chords: the sphere test's discriminant cancels, its roots
                    // are good to a few sqrt(eps) r (sqrt(eps) = 2.4e-4).
                    Some(h) => inward && (h.t as f64 - far).abs() <= 1e-3 * far + 4e-3 * c,
                };
            if !ok {
                rehits += 1;
                if rehits <= 3 {
                    eprintln!(
                        "r {radius}: p {} err {} dir {dir} inward {inward} hit {hit:?} far {far}",
                        sp.position, sp.p_error
                    );
                }
            }
        }
        assert!(cast > RAYS * 9 / 10, "sphere r {radius} at {center}: only {cast} points");
        assert_eq!(rehits, 0, "sphere r {radius} at {center}: {rehits} of {cast} rays went wrong");
    }
}

/// Two parallel quads 1e-3 apart, 1e5 from the origin along the planes: a ray from either
/// toward the other must hit it (an offset proportional to |p| would be ~0.1 there and
/// start beyond the other plane), at the distance the gap and the angle give.
#[test]
fn no_leaks_between_close_parallel_planes() {
    let gap = 1e-3f32;
    let size = 4.0;
    for at in [vec3(1e5, 0.0, 1e5), vec3(-1e5, 0.5, 3e4)] {
        let mut mesh = Mesh::default();
        let o = at - vec3(0.5 * size, 0.0, 0.5 * size);
        let (e1, e2) = (vec3(0.0, 0.0, size), vec3(size, 0.0, 0.0));
        parallelogram(&mut mesh, o, e1, e2); // normal +y
        parallelogram(&mut mesh, o + vec3(0.0, gap, 0.0), e1, e2);
        let gap = (o.y + gap) - o.y; // the gap f32 can express there
        let s = scene(mesh, vec![]);
        let (accel, _) = build(&s, &crate::settings::Settings::default());
        let mut rng = Sampler::for_sample(5, 0, 0);
        let mut bad = 0;
        for _ in 0..RAYS * 4 {
            let target = o + (0.3 + 0.4 * rng.next_f32()) * e1 + (0.3 + 0.4 * rng.next_f32()) * e2;
            let lower = rng.next_f32() < 0.5;
            // Hit a plane from outside the pair, then head for the other one.
            let (target, out, toward) =
                if lower { (target, -Vec3::Y, Vec3::Y) } else { (target + vec3(0.0, gap, 0.0), Vec3::Y, -Vec3::Y) };
            let Some((sp, prim)) = shoot(&s, accel.as_ref(), target + camera_direction(out, &mut rng), target) else {
                bad += 1;
                continue;
            };
            // Not grazing enough to run off the quad's 1.2-wide margin within the gap.
            let mut dir = direction(toward, &mut rng);
            if dir.dot(toward) < 1e-2 {
                dir = (dir + toward * 1e-2).normalize();
            }
            let ray = Ray::new(offset_origin(sp.position, sp.p_error, sp.geometric_normal, dir), dir);
            let expect = gap / dir.dot(toward);
            match accel.closest_hit(&ray, &mut TraceCounters::default()) {
                Some(h) if (h.prim < 2) != (prim < 2) && (h.t - expect).abs() <= 0.05 * expect + 1e-5 => {}
                other => {
                    bad += 1;
                    if bad <= 3 {
                        eprintln!(
                            "at {at}: from prim {prim} p {} dir {dir}: {other:?}, expected t {expect}",
                            sp.position
                        );
                    }
                }
            }
        }
        assert_eq!(bad, 0, "planes at {at}: {bad} rays leaked or re-hit");
    }
}

/// A Cornell-box light: the emitting quad 0.01 below the ceiling, in the ceiling's leaf. A
/// shadow ray from a point in the room toward a point of the light (found by tracing, with
/// its error bound) stops short enough that no box test reaches the light's leaf: it tests
/// no triangle at all and is not occluded, single rays and packets alike, at scales from 1e-3
/// to 1 (with the range ending within the box tests' `TIE_SCALE` margin of the light, every ray
/// would test the four triangles of the light's leaf). Far from the origin (coordinates 20x the
/// distances) the fused box test's own widening, 2^-20 of `origin * inv`, can exceed the
/// shortening, so some rays test the leaf there: they must still not be occluded.
#[test]
fn shadow_rays_toward_a_light_skip_the_lights_leaf() {
    for (scale, at, near) in [(1.0f32, Vec3::ZERO, true), (1e-3, Vec3::ZERO, true), (1e3, vec3(3e4, -2e4, 1e4), false)]
    {
        let mut mesh = Mesh::default();
        let p = |x: f32, y: f32, z: f32| at + scale * vec3(x, y, z);
        let s2 = 2.0 * scale;
        parallelogram(&mut mesh, p(-1.0, 0.0, -1.0), vec3(0.0, 0.0, s2), vec3(s2, 0.0, 0.0)); // floor, +y
        parallelogram(&mut mesh, p(-1.0, 1.5, -1.0), vec3(s2, 0.0, 0.0), vec3(0.0, 0.0, s2)); // ceiling, -y
        parallelogram(&mut mesh, p(-0.4, 1.49, -0.3), vec3(0.8 * scale, 0.0, 0.0), vec3(0.0, 0.0, 0.6 * scale)); // light
        let s = scene(mesh, vec![]);
        let (accel, _) = build(&s, &crate::settings::Settings::default());
        let mut rng = Sampler::for_sample(11, 0, 0);
        let (mut rays, mut c) = (Vec::new(), TraceCounters::default());
        while rays.len() < RAYS / 5 {
            let (a, b) = rng.next_2d();
            let origin = p(-0.95 + 1.9 * a, 0.05 + 1.3 * rng.next_f32(), -0.95 + 1.9 * b);
            let (a, b) = rng.next_2d();
            let light = p(-0.39 + 0.78 * a, 1.49, -0.29 + 0.58 * b);
            let from_below = light + scale * camera_direction(-Vec3::Y, &mut rng);
            let Some((lp, 4..=5)) = shoot(&s, accel.as_ref(), from_below, light) else {
                panic!("scale {scale}: the light was not found at {light}");
            };
            let dir = (lp.position - origin).normalize();
            let ray = shadow_ray(origin, dir, Some((lp.position, lp.p_error))).expect("the light is far away");
            // Four rays from each point, as the renderer's `-l 4` queues them.
            rays.extend([ray; 4]);
        }
        let mut occluded = vec![false; rays.len()];
        accel.any_hits_packets(&rays, &mut occluded, &mut c);
        let packets = c.prim_tests;
        let singles = rays.iter().filter(|r| accel.any_hit(r, &mut c)).count();
        let blocked = occluded.iter().filter(|&&o| o).count();
        assert_eq!((blocked, singles), (0, 0), "scale {scale}: shadow rays toward the light were occluded");
        if near {
            assert_eq!((packets, c.prim_tests), (0, 0), "scale {scale}: shadow rays tested triangles");
        }
    }
}
