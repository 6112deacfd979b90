//! Alpha cutouts where hits are found: a square of known coverage lets through exactly the
//! rays its texture says (closest hit and any hit, every traversal loop, build, leaf layout and
//! instruction set, and brute force); `BLEND` lets through the fraction its coverage says,
//! within statistical bounds, with the same decision per ray everywhere; opaque geometry's
//! hits do not change.

use crate::accel::cutout::Cutouts;
use crate::accel::{BruteForce, Bvh, BvhBuild, BvhOptions, Intersector, LeafLayout, TraceCounters};
use crate::cpu::Isa;
use crate::geometry::{Hit, Ray};
use crate::scene::alpha::{AlphaImage, AlphaMap};
use crate::scene::texture::{Filter, Wrap};
use crate::scene::{Alpha, AlphaMode, Material, Scene};
use crate::tests::common::meshgen::{icosphere, quad, scene_of};
use crate::tests::common::same_hit;
use glam::{Affine2, Vec2, Vec3, vec2, vec3};
use std::sync::Arc;

/// Texels per side of the coverage map.
const TEX: usize = 8;
/// Rays per side of the grid (a multiple of [`TEX`]: the same number through each texel).
const GRID: usize = 64;

/// The coverage map: texel (x, y) (row y from the top) is 0.25 (cut at 0.5) when
/// (3x + 5y) mod 7 < 3, else 0.75; returns the texels and how many are cut.
fn coverage() -> (Vec<f32>, usize) {
    let texels: Vec<f32> =
        (0..TEX * TEX).map(|i| if (3 * (i % TEX) + 5 * (i / TEX)) % 7 < 3 { 0.25 } else { 0.75 }).collect();
    let cut = texels.iter().filter(|&&a| a < 0.5).count();
    (texels, cut)
}

/// The cut square: corners (+-1, +-1, 0) with uv (0, 0) at (-1, 1) (glTF's frame: v down),
/// material 1 (`alpha`); behind it at z = -1 an opaque square twice as wide (material 0),
/// and beside them an opaque icosphere (material 0).
fn scene(alpha: Alpha) -> Scene {
    let mut mesh = icosphere(4);
    for p in &mut mesh.positions {
        *p = *p * 0.3 + vec3(3.0, 0.0, 0.0);
    }
    let mut uvs = vec![Vec2::ZERO; mesh.positions.len()];
    quad(&mut mesh, [vec3(-2.0, 2.0, -1.0), vec3(-2.0, -2.0, -1.0), vec3(2.0, -2.0, -1.0), vec3(2.0, 2.0, -1.0)], 0);
    uvs.extend([Vec2::ZERO; 4]);
    quad(&mut mesh, [vec3(-1.0, 1.0, 0.0), vec3(-1.0, -1.0, 0.0), vec3(1.0, -1.0, 0.0), vec3(1.0, 1.0, 0.0)], 1);
    uvs.extend([vec2(0.0, 0.0), vec2(0.0, 1.0), vec2(1.0, 1.0), vec2(1.0, 0.0)]);
    mesh.uvs = Some(uvs);
    let mut s = scene_of(mesh, vec![]);
    s.materials =
        vec![Material::diffuse("back", Vec3::splat(0.5)), Material { alpha, ..Material::diffuse("cut", Vec3::ONE) }];
    s
}

/// The first triangle of the cut square (the scene's last two).
fn cut_first(s: &Scene) -> u32 {
    s.mesh.triangles.len() as u32 - 2
}

fn mask() -> Alpha {
    let (texels, _) = coverage();
    let image = AlphaImage { width: TEX, height: TEX, texels };
    let map = AlphaMap {
        path: "test".into(),
        image: Some(Arc::new(image)),
        wrap: [Wrap::Repeat; 2],
        filter: Filter::Nearest,
        flip_v: false,
        transform: Affine2::IDENTITY,
    };
    Alpha { mode: AlphaMode::Mask { cutoff: 0.5 }, factor: 1.0, map: Some(map) }
}

/// The point of the square ray (i, j) of the grid aims at: the centre of cell (i, j) of a
/// `GRID` x `GRID` grid over the square, row j from the top (far from every texel edge).
fn target(i: usize, j: usize) -> Vec3 {
    let c = |k: usize| (k as f32 + 0.5) / GRID as f32;
    vec3(2.0 * c(i) - 1.0, 1.0 - 2.0 * c(j), 0.0)
}

/// A ray and the grid cell (i, j) it aims at.
type Aimed = (Ray, (usize, usize));

/// Rays toward the grid's cells: parallel ones (each from its own origin, traced alone or
/// three in flight), and from one point (a pinhole: runs of them are traced as coherent
/// packets, and their shadow-ray copies as shadow packets).
fn ray_sets() -> Vec<(&'static str, Vec<Aimed>)> {
    let cells = || (0..GRID).flat_map(|j| (0..GRID).map(move |i| (i, j)));
    let parallel = cells().map(|(i, j)| (Ray::new(target(i, j) + vec3(0.0, 0.0, 3.0), vec3(0.0, 0.0, -1.0)), (i, j)));
    let eye = vec3(0.05, -0.03, 25.0);
    let pinhole = cells().map(|(i, j)| (Ray::new(eye, target(i, j) - eye), (i, j)));
    vec![("parallel", parallel.collect()), ("pinhole", pinhole.collect())]
}

/// Every way the tree answers closest hits (one by one, as a batch, as a batch with rays in
/// flight) and any hits (one by one, as a queue, as packets), against `want`.
fn check_all_paths(scene: &Scene, rays: &[Ray], want: &[Option<Hit>], what: &str) {
    let mut c = TraceCounters::default();
    let layouts = [LeafLayout::Corners, LeafLayout::Packed];
    for (build, leaves) in [BvhBuild::Sah, BvhBuild::Fast].into_iter().flat_map(|b| layouts.map(|l| (b, l))) {
        for isa in [Isa::Scalar, Isa::Sse, Isa::Avx2] {
            for cached in [true, false] {
                let bvh = Bvh::build_with(scene, BvhOptions { build, leaves }).with_isa(isa).assume_cached(cached);
                let what = format!("{what} {build:?} {leaves:?} {isa:?} cached {cached}");
                let mut batch = vec![None; rays.len()];
                bvh.closest_hits(rays, &mut batch, &mut c);
                let (mut any, mut packets) = (vec![false; rays.len()], vec![false; rays.len()]);
                bvh.any_hits(rays, &mut any, &mut c);
                bvh.any_hits_packets(rays, &mut packets, &mut c);
                for (i, r) in rays.iter().enumerate() {
                    let single = bvh.closest_hit(r, &mut c);
                    assert!(same_hit(single, want[i]), "{what} ray {i}: {single:?}, want {:?}", want[i]);
                    assert!(same_hit(batch[i], want[i]), "{what} batch ray {i}: {:?}, want {:?}", batch[i], want[i]);
                    assert_eq!(any[i], want[i].is_some(), "{what} any-hit ray {i}");
                    assert_eq!(packets[i], want[i].is_some(), "{what} packet ray {i}");
                    assert_eq!(bvh.any_hit(r, &mut c), want[i].is_some(), "{what} single any-hit ray {i}");
                }
            }
        }
    }
}

/// Copies of `rays` that stop just before the back square (shadow rays toward it): they hit
/// something exactly where the cut square is there.
fn to_back(rays: &[Ray]) -> Vec<Ray> {
    rays.iter().map(|r| Ray { tmax: (-1.0 - r.origin.z) / r.dir.z * 0.999, ..*r }).collect()
}

#[test]
fn a_mask_lets_through_exactly_its_cut_texels_on_every_path() {
    let s = scene(mask());
    assert!(Cutouts::of(&s).is_some());
    let (texels, cut) = coverage();
    assert!(cut > 10 && cut < 50, "{cut} of 64 texels cut");
    let first = cut_first(&s);
    for (name, set) in ray_sets() {
        let rays: Vec<Ray> = set.iter().map(|(r, _)| *r).collect();
        let brute = BruteForce::new(&s);
        let mut c = TraceCounters::default();
        let want: Vec<Option<Hit>> = rays.iter().map(|r| brute.closest_hit(r, &mut c)).collect();
        // Brute force against the texture, ray by ray: through the cut texels to the back
        // square, on the square elsewhere.
        let mut through = 0;
        for ((_, (i, j)), h) in set.iter().zip(&want) {
            let texel = texels[(j * TEX / GRID) * TEX + i * TEX / GRID];
            let h = h.expect("every ray hits the back square at least");
            let on_square = h.prim >= first;
            assert_eq!(on_square, texel >= 0.5, "{name} ray ({i}, {j}): {h:?} where coverage is {texel}");
            through += !on_square as usize;
        }
        // Exactly the cut texels' share of the grid (each texel takes (GRID / TEX)^2 rays).
        assert_eq!(through * TEX * TEX, cut * GRID * GRID, "{name}");
        check_all_paths(&s, &rays, &want, name);
        // Shadow rays that end before the back square: occluded exactly where the square is.
        let short = to_back(&rays);
        let want_short: Vec<Option<Hit>> = short.iter().map(|r| brute.closest_hit(r, &mut c)).collect();
        assert_eq!(want_short.iter().filter(|h| h.is_none()).count() * TEX * TEX, cut * GRID * GRID, "{name} short");
        check_all_paths(&s, &short, &want_short, &format!("{name} short"));
    }
}

#[test]
fn opaque_geometry_is_hit_as_without_cutouts() {
    let cut = scene(mask());
    let opaque = scene(Alpha::OPAQUE);
    // Nothing cut: no table, the loops without the test.
    assert!(Cutouts::of(&opaque).is_none());
    // A mask whose factor alone passes its cutoff is opaque too; one that never passes is not.
    let solid = Alpha { mode: AlphaMode::Mask { cutoff: 0.5 }, factor: 0.5, map: None };
    assert!(Cutouts::of(&scene(solid)).is_none());
    let gone = Alpha { mode: AlphaMode::Mask { cutoff: 0.5 }, factor: 0.49, map: None };
    assert!(Cutouts::of(&scene(gone)).is_some());
    // An emitter is never cut.
    let mut lit = scene(mask());
    lit.materials[1].emission = Vec3::ONE;
    assert!(Cutouts::of(&lit).is_none());
    let first = cut_first(&cut);
    // Random rays through the icosphere, the squares and around them: wherever the opaque
    // scene's hit is on opaque geometry in front of the cut square (or the square is not on
    // the way), the hit is the same bit for bit.
    let mut x = crate::tests::common::Xorshift(99);
    let mut p = |s: f32| vec3(x.unit() - 0.5, x.unit() - 0.5, x.unit() - 0.5) * s;
    let rays: Vec<Ray> = (0..3000)
        .map(|_| {
            let o = p(10.0) + vec3(0.0, 0.0, 4.0);
            Ray::new(o, p(4.0) + vec3(1.5, 0.0, 0.0) - o)
        })
        .collect();
    let (mut c, mut compared) = (TraceCounters::default(), 0);
    let (bo, bc) = (Bvh::build(&opaque), Bvh::build(&cut));
    for r in &rays {
        let want = bo.closest_hit(r, &mut c);
        if want.is_some_and(|h| h.prim < first) {
            compared += 1;
            let got = bc.closest_hit(r, &mut c);
            // The cut square can only take a hit away where the opaque scene had it.
            assert!(same_hit(got, want), "{r:?}: {got:?} vs {want:?}");
        }
    }
    assert!(compared > 500, "{compared} rays hit opaque geometry first");
}

/// `BLEND` at coverage 0.3: about 70% of the rays pass (each ray's decision is a hash of the
/// ray and the triangle), the same rays on every path and for any hit as for closest hit.
#[test]
fn blend_passes_the_share_its_coverage_says_on_every_path() {
    let coverage = 0.3;
    let s = scene(Alpha { mode: AlphaMode::Blend, factor: coverage, map: None });
    let first = cut_first(&s);
    for (name, set) in ray_sets() {
        let rays: Vec<Ray> = set.iter().map(|(r, _)| *r).collect();
        let brute = BruteForce::new(&s);
        let mut c = TraceCounters::default();
        let want: Vec<Option<Hit>> = rays.iter().map(|r| brute.closest_hit(r, &mut c)).collect();
        let n = rays.len() as f64;
        let met = want.iter().filter(|h| h.is_some_and(|h| h.prim >= first)).count() as f64;
        // Binomial: 5.3 standard deviations, a false failure once in 10^7 runs per set.
        let sd = (coverage as f64 * (1.0 - coverage as f64) / n).sqrt();
        assert!((met / n - coverage as f64).abs() < 5.3 * sd, "{name}: {met} of {n} met, coverage {coverage}");
        check_all_paths(&s, &rays, &want, name);
        let short = to_back(&rays);
        let want_short: Vec<Option<Hit>> = short.iter().map(|r| brute.closest_hit(r, &mut c)).collect();
        // The same decision for the shadow copies (the hash reads the ray's origin and
        // direction, not its range).
        for (a, b) in want.iter().zip(&want_short) {
            assert_eq!(a.is_some_and(|h| h.prim >= first), b.is_some(), "{name}");
        }
        check_all_paths(&s, &short, &want_short, &format!("{name} short"));
    }
}
