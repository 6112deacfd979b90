//! Hard cases stay numerically stable: cameras inside closed meshes see no background,
//! the Cornell box far from the origin or at extreme scales renders the same image, grazing
//! light and degenerate geometry give finite, correct answers, and no scene produces NaN
//! or Inf at the settings the accuracy study uses.

use crate::accel::{BruteForce, Intersector, TraceCounters, build};
use crate::film::{Accumulator, Film};
use crate::geometry::Ray;
use crate::load::{LoadOptions, default_scene, load};
use crate::render::render_normals;
use crate::sampling::Sampler;
use crate::scene::{Camera, Light, Material, Mesh, Scene};
use crate::settings::IntegratorKind;
use crate::settings::Settings;
use crate::tests::common;
use crate::tests::common::meshgen;
use crate::tests::common::render::sums_with;
use crate::tests::common::{agree, render};
use glam::{Vec3, vec3};

fn settings(w: usize, h: usize, spp: u32, max_depth: u32) -> Settings {
    render::settings(w, h, max_depth, spp)
}

fn render(scene: &Scene, s: &Settings) -> Accumulator {
    let (accel, _) = build(scene, &crate::settings::Settings::default());
    let (acc, st) = sums_with(IntegratorKind::Wavefront, scene, accel.as_ref(), s, &|_| {});
    assert_eq!(st.invalid_samples, 0, "{}: NaN/Inf samples", scene.name);
    assert!(acc.to_film().all_finite(), "{}: non-finite film", scene.name);
    acc
}

fn normals(scene: &Scene, w: usize, h: usize) -> Film {
    let (accel, _) = build(scene, &crate::settings::Settings::default());
    render_normals(scene, &scene.camera, accel.as_ref(), &settings(w, h, 1, 1)).0
}

/// Pixels where the camera ray hit nothing (normal shading is black only there).
fn background_pixels(f: &Film) -> usize {
    assert!(f.all_finite());
    f.pixels.iter().filter(|p| **p == Vec3::ZERO).count()
}

// ---------------------------------------------------------------------------------------
// Watertightness

/// A point inside a closed mesh: the midpoint between entering and leaving along the
/// ray (from outside, toward the centre) with the longest inside span.
fn inside_point(scene: &Scene) -> Vec3 {
    let (accel, _) = build(scene, &crate::settings::Settings::default());
    let (lo, hi) = scene.bounds().unwrap();
    let (c, r) = (0.5 * (lo + hi), (hi - lo).length());
    let mut s = Sampler::for_sample(3, 0, 0);
    let mut best = (0.0f32, c);
    let mut tc = TraceCounters::default();
    for _ in 0..500 {
        let d = Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5).normalize();
        let target = c + (hi - lo) * Vec3::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5) * 0.5;
        let o = target - d * 2.0 * r;
        let Some(h1) = accel.closest_hit(&Ray::new(o, d), &mut tc) else { continue };
        let mut r2 = Ray::new(o, d);
        r2.tmin = h1.t + 1e-4 * r;
        let Some(h2) = accel.closest_hit(&r2, &mut tc) else { continue };
        if h2.t - h1.t > best.0 {
            best = (h2.t - h1.t, o + d * (0.5 * (h1.t + h2.t)));
        }
    }
    assert!(best.0 > 0.0, "{}: found no inside span", scene.name);
    best.1
}

/// Looks from `eye` along the six axes and four diagonals (nclip 0 so no wall is clipped)
/// and counts background pixels.
fn background_from_inside(scene: &Scene, eye: Vec3, res: usize) -> usize {
    let dirs = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z, vec3(1.0, 1.0, 1.0), vec3(-1.0, 0.3, 0.7)];
    let mut total = 0;
    for d in dirs {
        let mut s = scene.clone();
        s.camera = Camera::look_at(eye, eye + d, Vec3::Y, 100.0, 1.0);
        s.camera.nclip = 0.0;
        let bg = background_pixels(&normals(&s, res, res));
        if bg > 0 {
            eprintln!("{}: {bg} background pixels looking along {d}", scene.name);
        }
        total += bg;
    }
    total
}

fn closed_scene(name: &str, mesh: Mesh) -> Scene {
    let mut s = meshgen::scene_of(mesh, vec![]);
    s.name = name.into();
    s
}

/// A unit cube whose faces are strips: 400 x 1 x 3 cells along x, y, z, so the triangles
/// have aspect ratios up to 400:1; vertices are shared (keyed by grid position), so the
/// mesh is closed.
fn thin_triangle_cube() -> Mesh {
    let n = [400usize, 1, 3];
    let mut m = Mesh::default();
    let mut index = std::collections::HashMap::new();
    let mut vid = |m: &mut Mesh, g: [usize; 3]| -> u32 {
        *index.entry(g).or_insert_with(|| {
            m.positions.push(Vec3::new(
                g[0] as f32 / n[0] as f32,
                g[1] as f32 / n[1] as f32,
                g[2] as f32 / n[2] as f32,
            ));
            m.positions.len() as u32 - 1
        })
    };
    for axis in 0..3 {
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [0, n[axis]] {
            for i in 0..n[a] {
                for j in 0..n[b] {
                    let g = |di: usize, dj: usize| {
                        let mut p = [0; 3];
                        p[axis] = side;
                        p[a] = i + di;
                        p[b] = j + dj;
                        p
                    };
                    let (v00, v10, v11, v01) =
                        (vid(&mut m, g(0, 0)), vid(&mut m, g(1, 0)), vid(&mut m, g(1, 1)), vid(&mut m, g(0, 1)));
                    m.triangles.push([v00, v10, v11]);
                    m.triangles.push([v00, v11, v01]);
                }
            }
        }
    }
    m.material_ids = crate::scene::MaterialIds::uniform(0, m.triangles.len());
    m
}

#[test]
fn camera_inside_generated_closed_meshes_sees_no_background() {
    let ico = closed_scene("icosphere", meshgen::icosphere(24));
    assert_eq!(background_from_inside(&ico, Vec3::new(0.1, -0.2, 0.05), 512), 0);
    let cube = closed_scene("thin-triangle cube", thin_triangle_cube());
    assert_eq!(cube.mesh.triangles.len(), 2 * 2 * (400 + 400 * 3 + 3));
    assert_eq!(background_from_inside(&cube, Vec3::new(0.31, 0.5, 0.52), 512), 0);
    // Eye on a cell boundary and at a vertex-aligned position of the strips.
    assert_eq!(background_from_inside(&cube, Vec3::new(0.5, 0.5, 0.5), 256), 0);
}

/// Edges used by exactly one triangle, after welding equal positions.
fn boundary_edges(m: &Mesh) -> usize {
    let mut weld = std::collections::HashMap::new();
    let id: Vec<u32> = m
        .positions
        .iter()
        .map(|p| {
            let n = weld.len() as u32;
            *weld.entry(p.to_array().map(f32::to_bits)).or_insert(n)
        })
        .collect();
    let mut edges = std::collections::HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (id[t[k] as usize], id[t[(k + 1) % 3] as usize]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    edges.values().filter(|&&c| c == 1).count()
}

// ---------------------------------------------------------------------------------------
// Self-intersection: the same box far away and at extreme scales

fn transformed(scene: &Scene, scale: f32, offset: Vec3) -> Scene {
    let f = |p: Vec3| p * scale + offset;
    let mut s = scene.clone();
    s.mesh.positions.iter_mut().for_each(|p| *p = f(*p));
    for sp in &mut s.spheres {
        sp.center = f(sp.center);
        sp.radius *= scale;
    }
    for l in &mut s.lights {
        match l {
            Light::Point { position, .. } | Light::Spot { position, .. } => *position = f(*position),
            Light::Area { position, dim_x, dim_y, .. } => {
                *position = f(*position);
                *dim_x *= scale;
                *dim_y *= scale;
            }
            Light::Directional { .. } | Light::Hemisphere { .. } => {}
        }
    }
    s.camera.position = f(s.camera.position);
    s.camera.nclip *= scale;
    s.camera.fclip *= scale;
    s.camera.focal_distance *= scale;
    s.camera.lens_radius *= scale;
    s
}

/// Every 4x4 region's mean agrees (the shared z-test, with 2e-3 of slack for rounding that
/// moves with the scale); and no pixel turns black where the original is lit (speckles).
fn assert_same_image(a: &Accumulator, b: &Accumulator, what: &str) {
    agree::assert_regions_agree(a, b, 4, 2e-3, what);
    for (i, (pa, pb)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        let (ma, mb) = (pa.mean(), pb.mean());
        assert!(
            !(ma.max_element() > 0.05 && mb.max_element() < 0.1 * ma.max_element()),
            "{what}: pixel {i} is {mb} where the original is {ma} (black speckle)"
        );
    }
}

fn cornell_boxes() -> Vec<Scene> {
    let mut scenes = vec![default_scene()];
    scenes.extend(common::load_scene("cs184/sky/CBspheres_lambertian.dae"));
    for s in &mut scenes {
        s.camera.fit_aspect(32.0 / 24.0);
    }
    scenes
}

fn assert_transform_invariant(transforms: &[(f32, Vec3)]) {
    for scene in cornell_boxes() {
        let s = settings(32, 24, 64, 3);
        let base = render(&scene, &s);
        for &(scale, offset) in transforms {
            let t = transformed(&scene, scale, offset);
            let img = render(&t, &s);
            assert_same_image(&base, &img, &format!("{} scaled {scale} moved {offset}", scene.name));
        }
    }
}

#[test]
fn cornell_box_at_extreme_scales_renders_the_same() {
    assert_transform_invariant(&[(1e-3, Vec3::ZERO), (1e4, Vec3::ZERO), (1e-3, Vec3::splat(1.0))]);
}

/// Ray origins lifted by a fixed |p| * 2^-18 (32 ulps of the largest coordinate: 0.38 at 1e5,
/// more than the spheres' radius 0.3) started floor points' shadow rays inside a sphere beside
/// them (region means 17% darker); src/geometry/offset.rs lifts them by per-point error bounds.
#[test]
fn cornell_box_far_from_the_origin_renders_the_same() {
    assert_transform_invariant(&[(1.0, Vec3::splat(1e5))]);
}

// ---------------------------------------------------------------------------------------
// Grazing light, parallel rays, degenerate and extreme triangles

/// A floor of `n` x `n` quads on y = 0, side 2 `half`.
fn grid_floor(mesh: &mut Mesh, half: f32, n: usize, y: f32, m: u32) {
    let base = mesh.positions.len() as u32;
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
            mesh.positions.push(vec3(-half + 2.0 * half * u, y, -half + 2.0 * half * v));
        }
    }
    let at = |i: usize, j: usize| base + (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            mesh.triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            mesh.triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
            mesh.material_ids.extend([m, m]);
        }
    }
}

/// A tessellated plane lit at 89.9 degrees from its normal: every pixel has exactly
/// albedo / pi * E cos(89.9 deg); a shadow ray that hits the plane it leaves would make
/// black speckles.
#[test]
fn plane_lit_at_grazing_angle() {
    let mut mesh = Mesh::default();
    grid_floor(&mut mesh, 2.0, 40, 0.0, 0);
    let elevation = 0.1f32.to_radians();
    let radiance = 1000.0;
    let scene = Scene {
        name: "grazing".into(),
        mesh,
        materials: vec![Material::diffuse("grey", Vec3::splat(0.5))],
        lights: vec![Light::Directional {
            direction: vec3(-elevation.cos(), -elevation.sin(), 0.0),
            radiance: Vec3::splat(radiance),
        }],
        camera: Camera::look_at(vec3(0.0, 3.0, 0.01), Vec3::ZERO, Vec3::Y, 40.0, 1.0),
        ..Scene::default()
    };
    let acc = render(&scene, &settings(48, 48, 4, 1));
    let expected = 0.5 / std::f32::consts::PI * radiance * elevation.sin();
    for (i, p) in acc.pixels.iter().enumerate() {
        let m = p.mean();
        assert!((m.x - expected).abs() <= 1e-3 * expected, "pixel {i}: {m} expected {expected}");
    }
}

/// Floor and walls as fine grids (many BVH nodes whose boxes have zero thickness in y);
/// rays lying exactly in the floor's plane, and just above and below it, parallel to
/// the box slabs, must reach the wall, with the BVH agreeing with brute force.
#[test]
fn rays_parallel_to_slabs_and_triangle_planes() {
    let mut mesh = Mesh::default();
    grid_floor(&mut mesh, 1.0, 50, 0.0, 0);
    // Walls x = +-1.5 and z = +-1.5, spanning y in [-1, 1], as grids rotated from a floor.
    for (axis, sign) in [(0, 1.0f32), (0, -1.0), (2, 1.0), (2, -1.0)] {
        let mut w = Mesh::default();
        grid_floor(&mut w, 1.0, 20, 0.0, 0);
        for p in &mut w.positions {
            let (a, b) = (p.x, p.z);
            *p = if axis == 0 { vec3(1.5 * sign, a, b * 1.5) } else { vec3(b * 1.5, a, 1.5 * sign) };
        }
        mesh.append(w);
    }
    let scene = meshgen::scene_of(mesh, vec![]);
    let (bvh, _) = build(&scene, &crate::settings::Settings::default());
    let brute = BruteForce::new(&scene);
    let mut tc = TraceCounters::default();
    let mut n = 0;
    for y in [0.0f32, 1e-7, -1e-7, 1e-3] {
        for k in 0..41 {
            let c = -1.0 + k as f32 * 0.05; // includes grid lines exactly
            for (o, d, expect_t) in [
                (vec3(-0.25, y, c), Vec3::X, 1.75),
                (vec3(0.25, y, c), -Vec3::X, 1.75),
                (vec3(c, y, 0.0), Vec3::Z, 1.5),
                (vec3(c, y, 0.0), -Vec3::Z, 1.5),
            ] {
                let r = Ray::new(o, d);
                let hb = bvh.closest_hit(&r, &mut tc).unwrap_or_else(|| panic!("BVH: ray {o} {d} escaped"));
                let hf = brute.closest_hit(&r, &mut tc).expect("brute force: ray escaped");
                assert!(
                    hb.t.is_finite() && (hb.t - expect_t).abs() < 1e-4,
                    "ray {o} {d}: t {} expected {expect_t}",
                    hb.t
                );
                assert!((hb.t - hf.t).abs() < 1e-5, "BVH t {} brute force t {}", hb.t, hf.t);
                assert!(bvh.any_hit(&r, &mut tc));
                n += 1;
            }
        }
    }
    assert_eq!(n, 4 * 41 * 4);
}

/// Random rays through a scene: BVH and brute force agree on hit/miss and distance.
fn assert_bvh_matches_brute_force(scene: &Scene, rays: usize) {
    let (bvh, _) = build(scene, &crate::settings::Settings::default());
    let brute = BruteForce::new(scene);
    let (lo, hi) = scene.bounds().unwrap();
    let mut s = Sampler::for_sample(5, 0, 0);
    let mut tc = TraceCounters::default();
    let mut hits = 0;
    for _ in 0..rays {
        let p = |s: &mut Sampler| lo + (hi - lo) * Vec3::new(s.next_f32(), s.next_f32(), s.next_f32());
        let (a, b) = (p(&mut s), p(&mut s));
        let o = a - (b - a) * 2.0;
        let r = Ray::new(o, b - a);
        let (hb, hf) = (bvh.closest_hit(&r, &mut tc), brute.closest_hit(&r, &mut tc));
        match (hb, hf) {
            (Some(x), Some(y)) => {
                assert!(x.t.is_finite() && x.u.is_finite() && x.v.is_finite(), "{}: {x:?}", scene.name);
                assert!((x.t - y.t).abs() <= 1e-5 * y.t.max(1.0), "{}: t {} vs {}", scene.name, x.t, y.t);
                hits += 1;
            }
            (None, None) => {}
            (x, y) => panic!("{}: BVH {x:?} brute force {y:?} for ray {r:?}", scene.name),
        }
    }
    assert!(hits > rays / 10, "{}: only {hits} hits", scene.name);
}

/// Zero-area triangles (repeated and collinear corners), slivers 1e-7 wide, and duplicate
/// coincident triangles added to the Cornell box: finite images, BVH equal to brute force,
/// and the duplicates change nothing.
#[test]
fn degenerate_sliver_and_duplicate_triangles() {
    let base = default_scene();
    let mut scene = base.clone();
    scene.mesh.normals = None;
    let mut add = |corners: [Vec3; 3]| {
        let b = scene.mesh.positions.len() as u32;
        scene.mesh.positions.extend(corners);
        scene.mesh.triangles.push([b, b + 1, b + 2]);
        scene.mesh.material_ids.push(0);
    };
    let p = vec3(0.1, 0.7, -0.2);
    add([p, p, p]); // a point
    add([p, p + Vec3::X * 0.5, p + Vec3::X]); // collinear
    add([p, p + Vec3::Y * 0.3, p]); // two equal corners
    for k in 0..20 {
        let q = vec3(-0.9 + 0.09 * k as f32, 0.2, -0.5);
        add([q, q + vec3(0.0, 1.0, 0.0), q + vec3(1e-7, 0.5, 1e-7)]); // slivers
    }
    let mut base_no_normals = base.clone();
    base_no_normals.mesh.normals = None;
    scene.name = "degenerate".into();
    assert_bvh_matches_brute_force(&scene, 20_000);
    let acc = render(&scene, &settings(32, 24, 16, 3));
    assert!(normals(&scene, 64, 48).all_finite());
    assert!(acc.pixels.iter().any(|p| p.mean().max_element() > 0.0));

    // Duplicates: every triangle twice (same corners, new vertices).
    let mut dup = base_no_normals.clone();
    let copy = dup.mesh.clone();
    dup.mesh.append(copy);
    dup.name = "duplicated".into();
    assert_bvh_matches_brute_force(&dup, 20_000);
    let s = settings(32, 24, 32, 3);
    let (a, b) = (render(&base_no_normals, &s), render(&dup, &s));
    assert_same_image(&a, &b, "duplicated triangles");
    let (na, nb) = (normals(&base_no_normals, 64, 48), normals(&dup, 64, 48));
    assert_eq!(na, nb, "duplicates change the normal image");
}

/// A camera looking straight up and straight down the Y axis (its up hint is parallel to
/// the view): a valid frame, and from inside the box every pixel sees a wall.
#[test]
fn camera_looking_straight_along_an_axis() {
    for target in [vec3(0.0, 1.5, 0.0), vec3(0.0, -1.0, 0.0), vec3(0.0, 0.75, -5.0)] {
        let mut scene = default_scene();
        scene.camera = Camera::look_at(vec3(0.0, 0.75, 0.0), target, Vec3::Y, 60.0, 4.0 / 3.0);
        assert!(scene.camera.c2w.is_finite() && (scene.camera.c2w.determinant() - 1.0).abs() < 1e-4);
        let f = normals(&scene, 64, 48);
        if target.z == 0.0 {
            assert_eq!(background_pixels(&f), 0, "looking at {target}");
        }
        render(&scene, &settings(24, 18, 4, 3));
    }
}

// ---------------------------------------------------------------------------------------
// No NaN or Inf anywhere

/// Russian roulette with a continue probability of 1e-3 divides surviving throughput by
/// 1e-3: estimates must stay finite, and the image must still be lit.
#[test]
fn tiny_roulette_probability_stays_finite() {
    let mut scenes = vec![default_scene()];
    scenes.extend(common::load_scene("cs184/sky/CBspheres_lambertian.dae"));
    for mut scene in scenes {
        scene.camera.fit_aspect(24.0 / 18.0);
        for depth in [5, 64] {
            let mut s = settings(24, 18, 16, depth);
            s.paths.roulette.continue_prob = 1e-3;
            let acc = render(&scene, &s);
            let lit = |a: &Accumulator| a.pixels.iter().filter(|p| p.mean().max_element() > 0.0).count();
            // Direct light does not depend on roulette (it never stops the first bounce), so
            // every pixel lit with the default probability is lit here too.
            let normal = render(&scene, &settings(24, 18, 16, depth));
            eprintln!("{} -m {depth}: {} lit pixels with --rr 1e-3, {} with 0.65", scene.name, lit(&acc), lit(&normal));
            assert_eq!(lit(&acc), lit(&normal), "{} -m {depth}", scene.name);
        }
    }
}

/// The cases that take seconds each (skipped by `cargo test --release -- --skip slow`).
mod slow {
    use super::*;

    /// Closed meshes from the scenes folder (the Stanford bunny has holes in its base, so the
    /// closed, manifold dragon and Spot stand in for it; see the boundary-edge check).
    #[test]
    fn camera_inside_closed_scanned_meshes_sees_no_background() {
        for rel in ["meshes/spot.obj", "meshes/dragon_100k.obj"] {
            let Some(scene) = common::load_scene(rel) else { return };
            assert_eq!(boundary_edges(&scene.mesh), 0, "{rel} is not closed");
            let eye = inside_point(&scene);
            assert_eq!(background_from_inside(&scene, eye, 512), 0, "{rel}");
        }
    }

    /// A box 10^4 times longer than wide, as a few huge-aspect triangles and as a strip of
    /// 10^4 cells: traversal agrees with brute force and renders stay finite.
    #[test]
    fn extreme_aspect_ratio_meshes() {
        for cells in [1usize, 10_000] {
            let mut m = Mesh::default();
            // Top and bottom of a 1e4 x 1 x 1 slab as strips along x.
            for (y, flip) in [(0.0f32, false), (1.0, true)] {
                let b = m.positions.len() as u32;
                for i in 0..=cells {
                    let x = 1e4 * i as f32 / cells as f32;
                    m.positions.extend([vec3(x, y, 0.0), vec3(x, y, 1.0)]);
                }
                for i in 0..cells as u32 {
                    let (a0, a1, b0, b1) = (b + 2 * i, b + 2 * i + 1, b + 2 * i + 2, b + 2 * i + 3);
                    if flip {
                        m.triangles.extend([[a0, b1, b0], [a0, a1, b1]]);
                    } else {
                        m.triangles.extend([[a0, b0, b1], [a0, b1, a1]]);
                    }
                }
            }
            m.material_ids = crate::scene::MaterialIds::uniform(0, m.triangles.len());
            let mut scene = meshgen::scene_of(m, vec![]);
            scene.name = format!("slab of {cells} cells");
            scene.lights = vec![Light::Hemisphere { radiance: Vec3::ONE }];
            scene.camera = Camera::look_at(vec3(5000.0, 3.0, 4.0), vec3(5000.0, 0.5, 0.5), Vec3::Y, 60.0, 4.0 / 3.0);
            assert_bvh_matches_brute_force(&scene, 20_000);
            let acc = render(&scene, &settings(32, 24, 8, 3));
            assert!(acc.pixels.iter().any(|p| p.mean().max_element() > 0.0));
        }
    }

    /// Every scene file in WAVEPATH_SCENES loads and renders finite at the study's settings
    /// (24x18, 2 spp, -m 5), with light sampling and with hemisphere sampling.
    #[test]
    fn no_nan_or_inf_on_any_scene() {
        let Some(dir) = common::scenes_dir() else { return };
        let files = common::files_with_ext(&dir, &["dae", "obj", "ply", "gltf", "glb"]);
        assert!(!files.is_empty());
        for f in &files {
            let mut scene = load(f, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e:#}"));
            scene.camera.fit_aspect(24.0 / 18.0);
            for hemisphere in [false, true] {
                let mut s = settings(24, 18, 2, 5);
                s.paths.hemisphere = hemisphere;
                render(&scene, &s);
            }
        }
    }
}
