//! Stage 3: at every hit, emission, the direct-light rays and the continuation ray.

use super::Lanes;
use super::lanes;
use super::lanes::hits::list_of;
use super::one_path;
use super::queues::{PathQueue, ShadowQueue};
use crate::bsdf::{Lambert, Model};
use crate::integrator::Transport;

/// Shades every path against its hit: adds emission (and the environment) seen by camera
/// rays, appends the path's shadow rays (throughput applied), and replaces the path's ray by
/// its continuation (`alive`, after Russian roulette) or ends it. Parts whose effect `F`
/// leaves out are not compiled in.
///
/// The paths are first sorted by what shades them ([`Kinds`], pbrt-v4's queues after
/// intersection): where the render's [`Lanes`] has a lane width, the hits on each material
/// model are shaded in lanes by [`super::lanes::hits`], the escaped paths by
/// [`super::lanes::escaped`].
/// Each path's shadow rays stay in the order it made them, so its radiance is the same bits
/// whatever the grouping.
///
/// `aovs`: the output variables' records, when the hits' are made here, from the points the
/// lanes reconstruct (the frame loop decides).
pub fn shade(
    t: &Transport,
    lanes: Lanes,
    q: &mut PathQueue,
    shadow: &mut ShadowQueue,
    kinds: &mut Kinds,
    aovs: Option<&mut super::aov::AovRecords>,
) {
    let Some(width) = lanes.shade else {
        return shade_scalar(t, q, shadow);
    };
    shadow.clear();
    kinds.sort(t, q);
    // The escaped paths' texels are found first and read last, the hits shaded in between
    // (each kind touches only its own paths, so the order changes no bits).
    super::lanes::escaped::look_ahead(width, t, q, &kinds.escaped, &mut kinds.texels);
    super::lanes::hits::shade_hits(width, t, q, &kinds.hits, shadow, aovs);
    super::lanes::escaped::shade_escaped(width, t, q, &kinds.escaped, &kinds.texels);
}

/// A wave's paths by what shades them, as index lists into the path queue.
#[derive(Default)]
pub struct Kinds {
    /// Hits, one list per material model ([`lanes::hits::list_of`]).
    pub hits: [Vec<u32>; lanes::hits::MODELS],
    /// Escaped paths (the environment, light from infinity): their own lane kernel.
    pub escaped: Vec<u32>,
    /// The environment map's texel toward each escaped path (index, sine of its polar
    /// angle), found ahead of the reads.
    pub texels: Vec<(usize, f32)>,
}

impl Kinds {
    fn sort(&mut self, t: &Transport, q: &PathQueue) {
        for list in &mut self.hits {
            list.clear();
        }
        self.escaped.clear();
        // Without a non-Lambertian material every hit is Lambertian (no model looked up).
        let lambert = list_of(&Model::Lambert(Lambert { albedo: glam::Vec3::ZERO }));
        for (i, hit) in q.hit.iter().enumerate() {
            let list = match hit {
                None => &mut self.escaped,
                Some(_) if !t.rules.features.non_diffuse => &mut self.hits[lambert],
                Some(h) => &mut self.hits[list_of(&t.materials.models[t.materials.material_of(h.prim)])],
            };
            list.push(i as u32);
        }
    }
}

/// [`shade`] one path at a time (any features): the lane kernels' code at one lane.
pub fn shade_scalar(t: &Transport, q: &mut PathQueue, shadow: &mut ShadowQueue) {
    shadow.clear();
    let mut pending = Vec::new();
    for i in 0..q.len() {
        if let Some(v) = one_path::arrive(t, q, i) {
            let rng = t.streams.vertex_sampler(q.key[i], q.depth[i]);
            lanes::hits::leave_one(t, q, i, &v, rng, &mut pending, shadow);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{BruteForce, TraceCounters};
    use crate::geometry::Ray;
    use crate::integrator::rules::Features;
    use crate::integrator::wavefront::generate::{Wave, generate};
    use crate::integrator::wavefront::queues::ShadowEntry;
    use crate::integrator::wavefront::{Lanes, ShadeWidth};
    use crate::integrator::wavefront::{compact, traverse};
    use crate::scene::{Bsdf, Layers, Light, Scene, Sphere};
    use crate::settings::{RouletteKind, Settings, Shading};
    use glam::Vec3;

    /// The kernel parts, in the order of [`Features`]' fields.
    fn parts(
        emission: bool,
        environment: bool,
        direct: bool,
        indirect: bool,
        roulette: bool,
        non_diffuse: bool,
    ) -> Features {
        Features { emission, environment, direct, indirect, roulette, non_diffuse }
    }

    /// Each path's shadow rays (in the order they were made) and weights, by owner.
    fn by_owner(s: &ShadowQueue, n: usize) -> Vec<Vec<(Ray, Vec3)>> {
        let mut out = vec![Vec::new(); n];
        for k in 0..s.len() {
            out[s.owner()[k] as usize].push((s.ray()[k], s.weight()[k]));
        }
        out
    }

    /// The reference the kernels are checked against: each path shaded one at a time by the
    /// recursive integrator's vertex code (`Transport::direct_rays`, `Transport::scatter` and
    /// their BSDF forms), written independently of the leaving kernel.
    fn shade_by_transport(t: &Transport, q: &mut PathQueue, shadow: &mut ShadowQueue) {
        shadow.clear();
        for i in 0..q.len() {
            let Some(v) = one_path::arrive(t, q, i) else { continue };
            let rng = t.streams.vertex_sampler(q.key[i], q.depth[i]);
            let (depth, tp) = (q.depth[i], q.throughput[i]);
            let push = |shadow: &mut ShadowQueue, d: crate::integrator::DirectRay| {
                shadow.push(ShadowEntry { ray: d.ray, weight: d.weight * tp, owner: i as u32 })
            };
            let next = if t.rules.features.non_diffuse {
                let sh = t.shading(&v, q.ray[i].dir);
                if t.rules.features.direct && t.rules.counts_direct(depth) {
                    t.direct_rays_shaded(&v, &sh, depth, rng, |d| push(shadow, d));
                }
                if t.rules.features.indirect { t.scatter_shaded(&v, &sh, depth, rng) } else { None }
            } else {
                if t.rules.features.direct && t.rules.counts_direct(depth) {
                    t.direct_rays(&v, depth, rng, |d| push(shadow, d));
                }
                if t.rules.features.indirect { t.scatter(&v, depth, rng) } else { None }
            };
            if let Some((ray, w, bounce)) = next {
                let u = || rng.at(crate::integrator::DIM_ROULETTE).next_f32();
                one_path::go_on(t, q, i, depth, ray, w, bounce, u);
            }
        }
    }

    /// Five bounces of a 24x18 wave shaded both ways: every path gets the same continuation,
    /// throughput, radiance and shadow rays, bit for bit; returns the shadow rays made.
    fn compare(parts: Features, scene: &Scene, s: &Settings) -> usize {
        compare_counts(parts, scene, s).0
    }

    /// [`compare`], with the paths that escaped after a bounce.
    fn compare_counts(parts: Features, scene: &Scene, s: &Settings) -> (usize, usize) {
        // Every lane width, and one lane (`shade_scalar`).
        let widths = ShadeWidth::all().into_iter().map(Some).chain([None]);
        let counts: Vec<_> = widths.map(|w| compare_width(parts, scene, s, w)).collect();
        (counts.iter().map(|c| c.0).min().unwrap_or(0), counts.iter().map(|c| c.1).min().unwrap_or(0))
    }

    fn compare_width(parts: Features, scene: &Scene, s: &Settings, width: Option<ShadeWidth>) -> (usize, usize) {
        let mut t = Transport::new(scene, s, &crate::effects::Effects::of(scene, s));
        t.rules.features = parts;
        let lanes = Lanes { camera: None, shade: width };
        let mut kinds = Kinds::default();
        let accel = BruteForce::new(scene);
        let pixels: Vec<u32> = (0..(24 * 18) as u32).collect();
        let wave = Wave { pixels: &pixels, base: 0, batch: 8 };
        let mut q = PathQueue::default();
        generate(&t, None, &mut q, &wave, 24, 18, 8);
        let (mut sl, mut ss) = (ShadowQueue::default(), ShadowQueue::default());
        let mut slot_radiance = vec![Vec3::ZERO; wave.len()];
        let (mut shadow_rays, mut escaped) = (0, 0);
        while !q.is_empty() {
            traverse::traverse(&accel, &mut q, &mut TraceCounters::default());
            escaped += (0..q.len()).filter(|&i| q.hit[i].is_none() && q.depth[i] > 0).count();
            let mut qs = q.clone();
            shade(&t, lanes, &mut q, &mut sl, &mut kinds, None);
            shade_by_transport(&t, &mut qs, &mut ss);
            assert_eq!(q.ray, qs.ray);
            assert_eq!(q.throughput, qs.throughput);
            assert_eq!(q.radiance, qs.radiance);
            assert_eq!(q.alive, qs.alive);
            assert_eq!(q.depth, qs.depth);
            assert_eq!(q.bounce, qs.bounce);
            assert_eq!(by_owner(&sl, q.len()), by_owner(&ss, q.len()));
            shadow_rays += sl.len();
            compact::compact(&t, &mut q, &mut slot_radiance);
        }
        (shadow_rays, escaped)
    }

    fn settings(light_samples: u32, rr_throughput: bool) -> Settings {
        let mut s = Settings::default();
        s.image.width = 24;
        s.image.height = 18;
        s.sampling.spp = 8;
        s.sampling.light_samples = light_samples;
        s.paths.max_depth = 5;
        s.paths.shading = Shading::Global;
        s.paths.roulette.kind = if rr_throughput { RouletteKind::Throughput } else { RouletteKind::Fixed };
        s.paths.roulette.start_depth = 1 + rr_throughput as u32;
        s
    }

    /// Unit normals tilted differently at every vertex.
    fn tilted_normals(scene: &mut Scene) {
        let n = scene.mesh.positions.len();
        let normals =
            (0..n).map(|i| Vec3::new((i as f32 * 0.7).sin(), 1.0, (i as f32 * 1.3).cos()).normalize()).collect();
        scene.mesh.normals = Some(normals);
    }

    /// The default scene's light quad as the only light: one-sided emissive triangles, which
    /// turn MIS on under the standard dialect.
    fn emissive_box() -> Scene {
        let mut scene = crate::load::default_scene();
        scene.lights.clear();
        scene.source.dialect = crate::cs184::Dialect::Standard;
        scene.materials[3].two_sided_emission = false;
        scene
    }

    /// The lane kernel against the one-path-at-a-time kernel: area lights on triangles with
    /// and without corner normals, with spheres and without any.
    #[test]
    fn lanes_match_the_scalar_kernel() {
        let diffuse = parts(true, false, true, true, true, false);
        for (with_normals, with_spheres, rr_throughput) in
            [(false, true, false), (true, true, false), (true, false, false), (true, true, true)]
        {
            let mut scene = crate::load::default_scene();
            assert!(!scene.spheres.is_empty());
            if !with_spheres {
                scene.spheres.clear();
            }
            if with_normals {
                tilted_normals(&mut scene);
            }
            let shadow_rays = compare(diffuse, &scene, &settings(3, rr_throughput));
            assert!(shadow_rays > 1000, "{shadow_rays}");
        }
    }

    /// The same for what the first lane kernel left to the scalar one: emissive triangles
    /// under MIS with a one-sided emitter, a point light beside an area light, vertex colours
    /// (whole vertices gathered), hemisphere sampling, the Sobol and stratified samplers, and
    /// glass and mirror spheres among Lambertian walls (the kinds sorted apart).
    #[test]
    fn lanes_match_the_scalar_kernel_for_every_light_and_vertex() {
        let diffuse = parts(true, false, true, true, true, false);
        let shaded = parts(true, false, true, true, true, true);
        let mut s = settings(2, false);
        let scene = emissive_box();
        assert!(
            Transport::new(&scene, &s, &crate::effects::Effects::of(&scene, &s)).rules.mis,
            "the emissive box should turn MIS on"
        );
        assert!(compare(diffuse, &scene, &s) > 500);
        for sampler in [crate::sampling::SamplerKind::Sobol, crate::sampling::SamplerKind::Stratified] {
            s.sampling.sampler = sampler;
            assert!(compare(diffuse, &scene, &s) > 500);
        }
        s.sampling.sampler = crate::sampling::SamplerKind::Independent;

        let mut point = crate::load::default_scene();
        point.lights.push(Light::Point {
            position: Vec3::new(0.3, 1.2, 0.2),
            intensity: Vec3::splat(2.0),
            attenuation: [1.0, 0.0, 0.0],
        });
        tilted_normals(&mut point);
        assert!(compare(diffuse, &point, &s) > 500);
        // Spot lights (with and without a falloff exponent, a cone that leaves some walls out)
        // and a directional light, under MIS (the emissive box) and without.
        for mut scene in [crate::load::default_scene(), emissive_box()] {
            scene.lights.extend(delta_lights());
            tilted_normals(&mut scene);
            assert!(compare(diffuse, &scene, &s) > 500);
        }

        let mut colours = emissive_box();
        let n = colours.mesh.positions.len();
        colours.mesh.colors = Some((0..n).map(|i| Vec3::new(0.5 + 0.1 * (i % 5) as f32, 0.7, 0.9)).collect());
        assert!(compare(diffuse, &colours, &s) > 500);

        // Hemisphere probes in lanes, with corner normals and with every sampler.
        let mut hemisphere = s.clone();
        hemisphere.paths.hemisphere = true;
        assert!(compare(diffuse, &crate::load::default_scene(), &hemisphere) > 500);
        let mut tilted = crate::load::default_scene();
        tilted_normals(&mut tilted);
        for sampler in [crate::sampling::SamplerKind::Sobol, crate::sampling::SamplerKind::Stratified] {
            hemisphere.sampling.sampler = sampler;
            assert!(compare(diffuse, &tilted, &hemisphere) > 500, "{sampler:?} hemisphere");
        }

        let mut mixed = emissive_box();
        mixed.materials[4].bsdf =
            Bsdf::Glass { reflectance: Vec3::ONE, transmittance: Vec3::ONE, roughness: 0.0, ior: 1.5 };
        let mut mirror = mixed.materials[4].clone();
        mirror.bsdf = Bsdf::Mirror { reflectance: Vec3::splat(0.9) };
        mixed.materials.push(mirror);
        mixed.spheres[1].material = 5;
        assert!(Transport::new(&mixed, &s, &crate::effects::Effects::of(&mixed, &s)).materials.non_diffuse);
        assert!(compare(shaded, &mixed, &s) > 500);
    }

    /// The shaded kinds' kernel (numbers drawn in lanes) against the one-path kernel: walls of
    /// metallic-roughness, Phong and specular-glossiness materials, spheres of a rough
    /// conductor, glass (seen from both sides, total internal reflection), a mirror and a
    /// refraction-only surface, under the emissive quad (MIS, a light that reads a third number) and a
    /// point light, with every sampler, both roulettes, and hemisphere sampling.
    #[test]
    fn shaded_kinds_in_lanes_match_the_scalar_kernel() {
        let mut scene = emissive_box();
        scene.materials[0].bsdf =
            Bsdf::MetallicRoughness { base: Vec3::new(0.8, 0.6, 0.4), metallic: 0.3, roughness: 0.4 };
        scene.materials[1].bsdf =
            Bsdf::Phong { diffuse: Vec3::splat(0.5), specular: Vec3::splat(0.3), shininess: 40.0 };
        scene.materials[2].bsdf =
            Bsdf::SpecularGlossiness { diffuse: Vec3::splat(0.6), specular: Vec3::splat(0.2), glossiness: 0.7 };
        scene.materials[4].bsdf =
            Bsdf::Microfacet { alpha: 0.3, eta: Vec3::new(0.2, 0.9, 1.1), k: Vec3::new(3.9, 2.4, 2.2) };
        scene.lights.push(Light::Point {
            position: Vec3::new(0.3, 1.2, 0.2),
            intensity: Vec3::splat(2.0),
            attenuation: [1.0, 0.0, 0.0],
        });
        scene.lights.extend(delta_lights());
        let mut glass = scene.materials[4].clone();
        glass.bsdf = Bsdf::Glass { reflectance: Vec3::ONE, transmittance: Vec3::ONE, roughness: 0.0, ior: 1.5 };
        let mut mirror = glass.clone();
        mirror.bsdf = Bsdf::Mirror { reflectance: Vec3::new(0.9, 0.8, 0.7) };
        let mut refraction = glass.clone();
        refraction.bsdf = Bsdf::Refraction { transmittance: Vec3::splat(0.9), roughness: 0.0, ior: 2.0 };
        scene.materials.extend([glass, mirror, refraction]);
        scene.spheres[1].material = 5;
        scene.spheres.push(Sphere { center: Vec3::new(-0.5, 1.0, 0.4), radius: 0.2, material: 6 });
        scene.spheres.push(Sphere { center: Vec3::new(0.5, 1.0, -0.4), radius: 0.2, material: 7 });
        tilted_normals(&mut scene);
        compare_every_sampler(&scene, |t| {
            assert!(t.rules.mis && t.materials.non_diffuse);
            assert!(t.lights.set.lights.len() > 4, "a sample of every light kind at each glossy vertex");
        });
    }

    /// Two spot lights (one with a falloff exponent, each a cone narrower than the box) and a
    /// directional light.
    fn delta_lights() -> [Light; 3] {
        [
            Light::Spot {
                position: Vec3::new(-0.2, 1.4, 0.1),
                direction: Vec3::new(0.2, -1.0, 0.1),
                intensity: Vec3::new(1.5, 1.2, 1.0),
                cone_angle: 70.0,
                falloff_exponent: 3.0,
            },
            Light::Spot {
                position: Vec3::new(0.4, 1.0, -0.3),
                direction: Vec3::new(-0.5, -0.6, 0.4),
                intensity: Vec3::splat(0.8),
                cone_angle: 40.0,
                falloff_exponent: 0.0,
            },
            Light::Directional { direction: Vec3::new(0.3, -1.0, -0.2), radiance: Vec3::splat(0.5) },
        ]
    }

    /// [`compare`] of the shaded kinds' kernel with every sampler (Sobol with the throughput
    /// roulette), light sampling and hemisphere sampling; `check` is what the transport
    /// must be for the lanes to be reached.
    fn compare_every_sampler(scene: &Scene, check: impl Fn(&Transport)) {
        let shaded = parts(true, false, true, true, true, true);
        for (sampler, rr_throughput) in [
            (crate::sampling::SamplerKind::Independent, false),
            (crate::sampling::SamplerKind::Sobol, true),
            (crate::sampling::SamplerKind::Stratified, false),
        ] {
            let mut s = settings(2, rr_throughput);
            s.sampling.sampler = sampler;
            check(&Transport::new(scene, &s, &crate::effects::Effects::of(scene, &s)));
            assert!(compare(shaded, scene, &s) > 500, "{sampler:?}");
            let mut hemisphere = s.clone();
            hemisphere.paths.hemisphere = true;
            assert!(compare(shaded, scene, &hemisphere) > 500, "{sampler:?} hemisphere");
        }
    }

    /// The layered glTF model in lanes against the one-path kernel: walls with a clearcoat,
    /// a sheen, a specular colour and a thin transmitting wall; spheres of a transmitting
    /// volume (refraction and total internal reflection, seen from both sides, absorbing)
    /// and of a rough metal under a coat, so that delta and continuous samples mix in one
    /// group; every sampler, both roulettes, hemisphere sampling.
    #[test]
    fn layered_model_in_lanes_matches_the_scalar_kernel() {
        let mut scene = emissive_box();
        let layered = |base: Vec3, metallic: f32, roughness: f32, l: Layers| {
            let mut m = scene.materials[0].clone();
            m.bsdf = Bsdf::MetallicRoughness { base, metallic, roughness };
            m.layers = Some(Box::new(l));
            m
        };
        let coat = layered(
            Vec3::new(0.8, 0.3, 0.2),
            0.0,
            0.5,
            Layers { clearcoat: 0.8, clearcoat_roughness: 0.1, ..Layers::default() },
        );
        let sheen = layered(
            Vec3::new(0.2, 0.3, 0.7),
            0.0,
            0.7,
            Layers {
                sheen_color: Vec3::new(0.9, 0.8, 0.7),
                sheen_roughness: 0.4,
                specular_color: Vec3::new(1.0, 0.8, 0.6),
                specular: 0.7,
                ..Layers::default()
            },
        );
        let thin = layered(Vec3::splat(0.9), 0.0, 0.2, Layers { transmission: 0.6, ..Layers::default() });
        let volume = layered(
            Vec3::ONE,
            0.0,
            0.1,
            Layers {
                transmission: 1.0,
                thickness: 1.0,
                ior: 1.7,
                attenuation_color: Vec3::new(0.9, 0.7, 0.5),
                attenuation_distance: 0.5,
                clearcoat: 0.5,
                sheen_color: Vec3::splat(0.3),
                sheen_roughness: 0.8,
                ..Layers::default()
            },
        );
        let metal = layered(
            Vec3::new(0.9, 0.7, 0.4),
            1.0,
            0.35,
            Layers { clearcoat: 1.0, clearcoat_roughness: 0.3, ..Layers::default() },
        );
        (scene.materials[0], scene.materials[1], scene.materials[2]) = (coat, sheen, thin);
        scene.materials.extend([volume, metal]);
        scene.spheres[0].material = 5;
        scene.spheres[1].material = 6;
        scene.spheres.push(Sphere { center: Vec3::new(0.4, 1.0, -0.3), radius: 0.25, material: 5 });
        tilted_normals(&mut scene);
        compare_every_sampler(&scene, |t| {
            assert!(t.rules.mis);
            assert!(t.materials.models.iter().filter(|m| matches!(m, crate::bsdf::Model::Layered(_))).count() == 5);
        });
    }

    /// The default box without its ceiling and area light, lit from infinity through the
    /// opening (paths escape there after bounces) and by its emissive quad, with glossy walls
    /// (metallic-roughness, Phong) and a Lambertian floor and spheres.
    fn open_box() -> Scene {
        let mut scene = emissive_box();
        scene.mesh.triangles.drain(2..4);
        let ids: Vec<u32> =
            scene.mesh.material_ids.iter().enumerate().filter(|&(k, _)| !(2..4).contains(&k)).map(|(_, m)| m).collect();
        scene.mesh.material_ids = Default::default();
        scene.mesh.material_ids.extend(ids);
        scene.materials[1].bsdf =
            Bsdf::MetallicRoughness { base: Vec3::new(0.8, 0.6, 0.4), metallic: 0.3, roughness: 0.4 };
        scene.materials[2].bsdf =
            Bsdf::Phong { diffuse: Vec3::splat(0.5), specular: Vec3::splat(0.3), shininess: 40.0 };
        tilted_normals(&mut scene);
        scene
    }

    /// A small environment map with one bright texel (importance sampling has work to do).
    fn small_map() -> crate::scene::Environment {
        let (w, h) = (16, 8);
        let texels =
            (0..w * h).map(|i| Vec3::new(0.2 + (i % 3) as f32, 0.5, if i == 37 { 40.0 } else { 0.3 })).collect();
        let map = crate::scene::EnvMap::from_texels("map".into(), w, h, texels).unwrap();
        crate::scene::Environment::Map(std::sync::Arc::new(map))
    }

    /// The light from infinity (the hemisphere sky, a constant environment, an environment
    /// map alone and beside the sky) and point, spot and directional lights, sampled in both
    /// lane kernels, and the escaped paths shaded in lanes, against the one-path kernel: every
    /// ray, weight and radiance bit for bit at both widths, with MIS at the Lambertian
    /// vertices and without, with every sampler.
    #[test]
    fn infinite_and_punctual_lights_in_lanes_match_the_scalar_kernel() {
        let shaded = parts(true, true, true, true, true, true);
        let sky = Light::Hemisphere { radiance: Vec3::new(1.0, 0.9, 0.8) };
        let cases: Vec<(&str, Vec<Light>, crate::scene::Environment)> = vec![
            ("sky", vec![sky.clone()], crate::scene::Environment::None),
            ("constant", vec![], crate::scene::Environment::Constant(Vec3::splat(0.7))),
            ("map", vec![], small_map()),
            ("sky and map", vec![sky.clone()], small_map()),
            (
                "punctual",
                vec![
                    sky,
                    Light::Point {
                        position: Vec3::new(0.3, 1.2, 0.2),
                        intensity: Vec3::splat(2.0),
                        attenuation: [1.0, 0.0, 0.0],
                    },
                    Light::Spot {
                        position: Vec3::new(-0.3, 1.4, 0.1),
                        direction: Vec3::new(0.1, -1.0, 0.2),
                        intensity: Vec3::splat(3.0),
                        cone_angle: 70.0,
                        falloff_exponent: 2.0,
                    },
                    Light::Directional { direction: Vec3::new(0.2, -1.0, -0.3), radiance: Vec3::splat(1.5) },
                ],
                crate::scene::Environment::None,
            ),
        ];
        for (name, lights, env) in cases {
            let mut scene = open_box();
            scene.lights = lights;
            scene.env = env;
            for (sampler, mis) in [
                (crate::sampling::SamplerKind::Independent, true),
                (crate::sampling::SamplerKind::Sobol, false),
                (crate::sampling::SamplerKind::Stratified, true),
            ] {
                let mut s = settings(2, sampler == crate::sampling::SamplerKind::Sobol);
                s.sampling.sampler = sampler;
                s.paths.mis = mis;
                let t = Transport::new(&scene, &s, &crate::effects::Effects::of(&scene, &s));
                assert_eq!(t.rules.mis, mis);
                assert!(t.lights.infinite.is_some());
                assert!(t.materials.non_diffuse);
                let (shadow_rays, escaped) = compare_counts(shaded, &scene, &s);
                assert!(shadow_rays > 500, "{name} {sampler:?}: {shadow_rays}");
                assert!(escaped > 100, "{name} {sampler:?}: {escaped} paths escaped after a bounce");
            }
        }
    }
}
