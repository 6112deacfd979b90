//! Which effects a scene calls for under given settings, and why.
//!
//! Derived once before rendering. The wavefront integrator reads the flags once per render
//! (the transport's `Features`): a stage whose effect is off is not run (its time is absent
//! from the stats), a kernel part whose effect is off is skipped. The log and stats list the effects that are on,
//! each with its reason. `--all-effects` forces every flag on (for benchmarks): the image
//! stays the same, because every kernel part is exact when its effect is not needed (it
//! adds zero, finds no light, or stops no path).

use crate::scene::{Camera, Environment, Light, Scene};
use crate::settings::{RouletteKind, Settings, Shading};

/// One effect that is on, and the reason it is on.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Effect {
    pub name: &'static str,
    pub reason: String,
}

/// The effects a render uses: one flag per stage or kernel feature, plus the list (with
/// reasons) that the log, `wavepath info` and the stats show.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Effects {
    /// `--shading normals`: the debug view, no light transport at all.
    pub normal_shading: bool,
    /// Analytic spheres are part of the scene (the accelerator tests them).
    pub spheres: bool,
    /// Emission is seen directly by the camera (emissive materials, counted at depth 0).
    pub emission: bool,
    /// Camera rays that miss see a constant environment.
    pub environment: bool,
    /// Area lights (or emissive triangles standing in for them) are sampled.
    pub area_lights: bool,
    /// Point, directional or spot lights are sampled (one shadow ray each).
    pub delta_lights: bool,
    /// Light from infinity (hemisphere light, constant environment) is sampled.
    pub infinite_light: bool,
    /// Direct light is estimated at path vertices: the shadow stage runs.
    pub direct: bool,
    /// Paths continue past their first hit: the bounce (continuation) kernel runs.
    pub indirect: bool,
    /// Russian roulette can stop paths: the roulette kernel runs.
    pub russian_roulette: bool,
    /// Adaptive sampling: per-pixel convergence bookkeeping between frames.
    pub adaptive: bool,
    /// Mirror materials (delta reflection).
    pub mirror: bool,
    /// Glass or refraction materials (delta reflection and refraction).
    pub glass: bool,
    /// Glossy models (rough conductors, PBR, Phong), with MIS between light and BSDF sampling.
    pub microfacet: bool,
    /// Any of the three: the kernel shades through the BSDF models.
    pub non_diffuse: bool,
    /// An environment map lights the scene (importance-sampled) and camera misses see it.
    pub environment_map: bool,
    /// Some material takes its albedo from an image through the mesh's uv coordinates.
    pub textures: bool,
    /// The camera has an aperture (`-b R > 0`): camera rays start on the lens disk.
    pub thin_lens: bool,
    /// Diffuse surfaces combine light sampling with their BSDF sample by MIS: the lights are
    /// emissive triangles or an environment map, whose light sampling alone leaves fireflies
    /// (an emitter next to a wall). Area, point and hemisphere lights gain nothing from it
    /// (measured: the same variance, 5% more time), so CS184 scenes keep the seed's estimator
    /// (one of the rules [`crate::cs184`] lists).
    pub mis: bool,
    /// Every flag was forced on by `--all-effects`.
    pub forced: bool,
    /// Which light transport runs and why (the log's "Integrator" line).
    pub integrator: Effect,
    /// That light transport: the settings' own, or the rule's choice for `auto`.
    pub integrator_kind: crate::settings::IntegratorKind,
    /// The effects that are on, in a fixed order, with their reasons.
    pub on: Vec<Effect>,
}

/// What the rules look at: the settings and counts of the scene, gathered once.
struct Facts<'a> {
    scene: &'a Scene,
    settings: &'a Settings,
    /// The camera the render sees through, as its plan fits it.
    camera: Camera,
    /// `--shading normals`: no light transport at all.
    normals: bool,
    /// The depth light transport runs to (`-m`, at most 1 with `--shading direct`).
    depth: u32,
    /// Light transport runs and reaches at least one surface.
    lit: bool,
    /// Emission found by camera rays enters the image (`-o 1`, or `-m 0`).
    sees_emission: bool,
    emissive_triangles: usize,
    emissive_spheres: usize,
    /// The environment light, described, when there is one.
    environment: Option<String>,
    mirrors: usize,
    glasses: usize,
    metals: usize,
    /// Metallic-roughness (glTF, MTL `Pr`/`Pm`) and specular-glossiness materials.
    pbr: usize,
    /// Phong materials (MTL `illum 2` with `Ks`, COLLADA `<phong>`/`<blinn>`).
    phong: usize,
    /// Materials with delta lobes only (smooth mirrors and glass).
    delta: usize,
    /// An area light stands in for the emissive triangles (CS184): those are no light.
    area_lights: bool,
    /// Some material absorbs light inside its volume.
    volumes: bool,
}

impl<'a> Facts<'a> {
    fn of(scene: &'a Scene, settings: &'a Settings) -> Facts<'a> {
        let normals = settings.paths.shading == Shading::Normals;
        let depth = if settings.paths.shading == Shading::Direct {
            settings.paths.max_depth.min(1)
        } else {
            settings.paths.max_depth
        };
        let material_count = |kinds: &[&str]| scene.materials.iter().filter(|m| kinds.contains(&m.bsdf.kind())).count();
        Facts {
            scene,
            settings,
            camera: settings.image.camera(&scene.camera),
            normals,
            depth,
            lit: !normals && depth >= 1,
            sees_emission: !normals && (settings.paths.accumulate || depth == 0),
            emissive_triangles: scene
                .mesh
                .material_ids
                .runs()
                .filter(|&(_, _, m)| scene.materials[m as usize].is_emissive())
                .map(|(start, end, _)| end - start)
                .sum(),
            emissive_spheres: scene
                .spheres
                .iter()
                .filter(|s| scene.materials[s.material as usize].is_emissive())
                .count(),
            environment: match &scene.env {
                Environment::Constant(c) if *c != glam::Vec3::ZERO => Some(format!("constant environment {c}")),
                Environment::Map(m) => Some(format!("environment map {}", m.path.display())),
                _ => None,
            },
            mirrors: material_count(&["mirror"]),
            glasses: material_count(&["glass", "refraction"]),
            metals: material_count(&["microfacet"]),
            pbr: material_count(&["metallic-roughness", "specular-glossiness"]),
            phong: material_count(&["phong"]),
            // Mirrors and glass are delta models unless glTF layers make them layered ones.
            delta: scene
                .materials
                .iter()
                .filter(|m| m.layers.is_none() && ["mirror", "glass", "refraction"].contains(&m.bsdf.kind()))
                .count(),
            area_lights: scene.lights.iter().any(|l| matches!(l, Light::Area { .. })),
            volumes: scene.materials.iter().any(|m| m.layers.as_ref().is_some_and(|l| l.sigma_a() != glam::Vec3::ZERO)),
        }
    }

    /// Light sampling (not `-H` hemisphere probes) runs.
    fn samples_lights(&self) -> bool {
        self.lit && !self.settings.paths.hemisphere
    }

    /// Full global illumination to depth `d` or more.
    fn global_to(&self, d: u32) -> bool {
        !self.normals && self.settings.paths.shading == Shading::Global && self.depth >= d
    }
}

/// One row of the table: the effect's name (as the log, `info` and the stats show it), the
/// flag it sets, and its rule: the reason it is on, or `None`. A rule may read the flags of
/// the rows above it.
struct Rule {
    name: &'static str,
    flag: fn(&mut Effects) -> &mut bool,
    rule: fn(&Facts, &Effects) -> Option<String>,
}

/// Every effect, in the order the log lists them. `--all-effects` forces every row but the
/// first on (normal shading chooses another renderer, not a kernel feature).
const RULES: &[Rule] = &[
    Rule {
        name: "normal-shading",
        flag: |e| &mut e.normal_shading,
        rule: |f, _| f.normals.then(|| "--shading normals".into()),
    },
    Rule {
        name: "spheres",
        flag: |e| &mut e.spheres,
        rule: |f, _| {
            let n = f.scene.spheres.len();
            (n > 0).then(|| format!("{n} analytic sphere(s)"))
        },
    },
    Rule {
        name: "emission",
        flag: |e| &mut e.emission,
        rule: |f, _| {
            (f.sees_emission && f.emissive_triangles + f.emissive_spheres > 0).then(|| {
                format!("{} emissive triangle(s), {} emissive sphere(s)", f.emissive_triangles, f.emissive_spheres)
            })
        },
    },
    Rule {
        name: "environment",
        flag: |e| &mut e.environment,
        rule: |f, _| f.environment.clone().filter(|_| f.sees_emission).map(|c| format!("{c} seen by camera misses")),
    },
    Rule {
        name: "area-lights",
        flag: |e| &mut e.area_lights,
        rule: |f, _| {
            let areas = f.scene.lights.iter().filter(|l| l.kind() == "area").count();
            let samples = f.settings.sampling.light_samples;
            if !f.samples_lights() {
                None
            } else if areas > 0 {
                Some(format!("{areas} area light(s), {samples} sample(s) each"))
            } else if f.emissive_triangles > 0 {
                Some(format!("{} emissive triangle(s) sampled by area, {samples} sample(s)", f.emissive_triangles))
            } else {
                None
            }
        },
    },
    Rule {
        name: "delta-lights",
        flag: |e| &mut e.delta_lights,
        rule: |f, _| {
            let delta = f.scene.lights.iter().filter(|l| l.is_delta()).count();
            (f.samples_lights() && delta > 0)
                .then(|| format!("{delta} point/directional/spot light(s), one shadow ray each"))
        },
    },
    Rule {
        name: "infinite-light",
        flag: |e| &mut e.infinite_light,
        rule: |f, _| {
            let hemisphere_light = f.scene.lights.iter().any(|l| matches!(l, Light::Hemisphere { .. }));
            (f.samples_lights() && (hemisphere_light || f.environment.is_some()))
                .then(|| "hemisphere light or environment sampled".into())
        },
    },
    Rule {
        name: "direct-light",
        flag: |e| &mut e.direct,
        rule: |f, e| {
            if !f.lit {
                None
            } else if f.settings.paths.hemisphere {
                Some("-H: uniform hemisphere probes".into())
            } else if e.area_lights || e.delta_lights || e.infinite_light {
                Some("light sampling: the scene has lights".into())
            } else {
                None
            }
        },
    },
    Rule {
        name: "mirror",
        flag: |e| &mut e.mirror,
        rule: |f, _| {
            (f.lit && f.mirrors > 0)
                .then(|| format!("{} mirror material(s): delta reflection, no shadow rays", f.mirrors))
        },
    },
    Rule {
        name: "glass",
        flag: |e| &mut e.glass,
        rule: |f, _| {
            (f.lit && f.glasses > 0)
                .then(|| format!("{} glass/refraction material(s): Fresnel reflection and refraction", f.glasses))
        },
    },
    Rule {
        name: "microfacet",
        flag: |e| &mut e.microfacet,
        rule: |f, _| {
            let mut what = Vec::new();
            if f.metals > 0 {
                what.push(format!("{} rough conductor(s): Beckmann microfacets", f.metals));
            }
            if f.pbr > 0 {
                what.push(format!("{} PBR material(s): diffuse base under GGX specular", f.pbr));
            }
            if f.phong > 0 {
                what.push(format!("{} Phong material(s): diffuse plus GGX specular", f.phong));
            }
            (f.lit && !what.is_empty()).then(|| format!("{}; MIS of light and BSDF samples", what.join(", ")))
        },
    },
    Rule {
        name: "non-diffuse-shading",
        flag: |e| &mut e.non_diffuse,
        rule: |_, e| (e.mirror || e.glass || e.microfacet).then(|| "BSDF models in the shade kernel".into()),
    },
    Rule {
        name: "indirect",
        flag: |e| &mut e.indirect,
        rule: |f, _| {
            if f.global_to(2) {
                Some(format!("-m {} > 1", f.depth))
            } else if f.lit && f.mirrors + f.glasses + f.metals + f.pbr + f.phong > 0 {
                Some("light found by rays from mirror, glass or glossy surfaces".into())
            } else {
                None
            }
        },
    },
    Rule {
        name: "russian-roulette",
        flag: |e| &mut e.russian_roulette,
        rule: |f, _| {
            let p = f.settings.paths.roulette.continue_prob;
            let from = f.settings.paths.roulette.start_depth.max(1);
            if !f.global_to(from + 2) {
                None
            } else if f.settings.paths.roulette.kind == RouletteKind::Throughput {
                Some(format!("-m {} > {}, continue by path throughput from depth {from}", f.depth, from + 1))
            } else {
                (p < 1.0).then(|| format!("-m {} > {} and --rr {p} < 1 from depth {from}", f.depth, from + 1))
            }
        },
    },
    Rule {
        name: "adaptive-sampling",
        flag: |e| &mut e.adaptive,
        rule: |f, _| f.settings.sampling.adaptive.map(|(b, t)| format!("-a {b} {t}")),
    },
    Rule {
        name: "environment-map",
        flag: |e| &mut e.environment_map,
        rule: |f, _| match &f.scene.env {
            Environment::Map(m) if !f.normals => {
                Some(format!("{} ({}x{}), importance-sampled by luminance", m.path.display(), m.width, m.height))
            }
            _ => None,
        },
    },
    Rule {
        name: "textures",
        flag: |e| &mut e.textures,
        rule: |f, _| {
            let textured = f.scene.materials.iter().filter(|m| m.albedo_texture.is_some()).count();
            (!f.normals && textured > 0 && f.scene.mesh.uvs.is_some())
                .then(|| format!("{textured} material(s) with an albedo texture"))
        },
    },
    Rule {
        name: "thin-lens",
        flag: |e| &mut e.thin_lens,
        rule: |f, _| {
            let camera = &f.camera;
            (camera.lens_radius > 0.0)
                .then(|| format!("lens radius {}, focal distance {}", camera.lens_radius, camera.focal_distance))
        },
    },
];

/// Why diffuse vertices use MIS, if they do: light sampling runs, paths continue past their
/// first hit, `--no-mis` is not given, and some light is sampled in a way MIS improves.
fn mis_reason(f: &Facts) -> Option<String> {
    if !(f.samples_lights() && f.global_to(2) && f.settings.paths.mis && f.settings.paths.accumulate) {
        return None;
    }
    let areas = f.scene.lights.iter().any(|l| l.kind() == "area");
    let what = match (&f.scene.env, !areas && f.emissive_triangles > 0) {
        (_, true) => format!("{} emissive triangle(s) as lights", f.emissive_triangles),
        (Environment::Map(_), false) => "an environment map".to_string(),
        _ => return None,
    };
    Some(format!("{what}: light and BSDF samples combined at diffuse surfaces (--no-mis: light sampling alone)"))
}

/// The light transport the render runs, and the reason: what `--integrator` asks for, or
/// for `auto` the scene's rule. path+light is chosen where the scene has caustics light
/// tracing draws: smooth mirrors or glass that carry light from emissive triangles onto
/// diffuse surfaces, whose paths a path tracer finds only when a bounce happens to hit the
/// emitter through them. Everything path+light refuses (a lens, adaptive sampling, light from
/// infinity, absorbing volumes, the last bounce alone) keeps the path tracer, as do scenes
/// without such caustics (docs/decisions.md, "path+light: light tracing for caustics only").
fn integrator_choice(f: &Facts) -> (crate::settings::IntegratorKind, Effect) {
    use crate::settings::IntegratorKind as K;
    let kind = f.settings.execution.integrator;
    let reason = match kind {
        K::Auto => return auto_choice(f),
        K::Wavefront => "--integrator path: the path tracer".into(),
        K::Recursive => "--integrator recursive: the path tracer's single-ray reference".into(),
        K::Light => "--integrator light: light tracing alone (surfaces seen through mirrors or glass stay dark)".into(),
        K::Bdpt => "--integrator bdpt: camera and light subpaths joined by every connection, weighted by MIS".into(),
        K::Vcm => "--integrator vcm: bdpt plus merging with nearby light vertices, weighted by MIS".into(),
        K::PathLight => {
            "--integrator path+light: the path tracer plus light tracing of caustics, weighted by MIS".into()
        }
    };
    let name = if kind == K::Wavefront { "path" } else { kind.name() };
    (kind, Effect { name, reason })
}

/// [`integrator_choice`] for `auto`.
fn auto_choice(f: &Facts) -> (crate::settings::IntegratorKind, Effect) {
    use crate::settings::IntegratorKind as K;
    let emitters = if f.area_lights { 0 } else { f.emissive_triangles };
    let path = |reason: String| (K::Wavefront, Effect { name: "path", reason });
    if f.delta == 0 || emitters == 0 {
        return path(
            "path tracer: no caustics for light tracing (no smooth mirror or glass lit by emissive triangles)".into(),
        );
    }
    if !f.global_to(2) {
        return path(format!(
            "path tracer: light reaches no caustic at this depth (-m {}; a caustic needs 2 bounces)",
            f.depth
        ));
    }
    let s = f.settings;
    let environment = f.environment.is_some() || f.scene.lights.iter().any(|l| matches!(l, Light::Hemisphere { .. }));
    let blocker = if f.camera.lens_radius > 0.0 || f.camera.orthographic {
        Some("the camera has a lens or is orthographic")
    } else if s.sampling.adaptive.is_some() {
        Some("adaptive sampling measures each pixel by its own samples")
    } else if environment {
        Some("light from infinity starts no light subpath yet")
    } else if f.volumes {
        Some("light subpaths do not cross absorbing volumes yet")
    } else if !s.paths.accumulate {
        Some("the last bounce alone (-o 0) is the path tracer's")
    } else {
        None
    };
    let what =
        format!("{} smooth mirror or glass material(s) carry light from {emitters} emissive triangle(s)", f.delta);
    match blocker {
        Some(why) => path(format!("path tracer: {what} (caustics), but {why}; path+light is not chosen")),
        None => (
            K::PathLight,
            Effect {
                name: "path+light",
                reason: format!(
                    "{what}: light tracing draws the caustics, the path tracer everything else \
                     (4.5x Mitsuba 3 at equal error on the harness's spheres-box, the path tracer 1.1x; --integrator path forces it)"
                ),
            },
        ),
    }
}

impl Effects {
    /// Runs the table: each rule in order, its flag set and its reason listed when it is on.
    pub fn of(scene: &Scene, settings: &Settings) -> Effects {
        let facts = Facts::of(scene, settings);
        let force = settings.execution.all_effects;
        let mut e = Effects { forced: force, ..Effects::default() };
        for (i, row) in RULES.iter().enumerate() {
            let why = (row.rule)(&facts, &e);
            let why =
                if i == 0 { why } else { why.or_else(|| force.then(|| "forced on by --all-effects".to_string())) };
            if let Some(reason) = why {
                *(row.flag)(&mut e) = true;
                e.on.push(Effect { name: row.name, reason });
            }
        }
        // A choice of estimator, not a kernel part: never forced, since it changes the image.
        if let Some(reason) = mis_reason(&facts) {
            e.mis = true;
            e.on.push(Effect { name: "mis", reason });
        }
        (e.integrator_kind, e.integrator) = integrator_choice(&facts);
        e
    }

    pub fn names(&self) -> Vec<&'static str> {
        self.on.iter().map(|e| e.name).collect()
    }
}
