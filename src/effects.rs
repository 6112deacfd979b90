//! Which effects a scene calls for under given settings, and why.
//!
//! Derived once before rendering. The wavefront integrator reads the flags once per render
//! to pick a kernel specialised (monomorphised) for exactly these effects: a stage whose
//! effect is off is not run (its time is absent from the stats), a branch whose effect is
//! off is not compiled into the kernel. The log and stats list the effects that are on,
//! each with its reason. `--all-effects` forces every flag on (for benchmarks): the image
//! stays the same, because every kernel part is exact when its effect is not needed (it
//! adds zero, finds no light, or stops no path).

use crate::scene::{Environment, Light, Scene};
use crate::settings::{Settings, Shading};

/// One effect that is on, and the reason it is on.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
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
    /// Rough conductors (microfacet), with MIS between light and BSDF sampling.
    pub microfacet: bool,
    /// Any of the three: the kernel shades through the BSDF models.
    pub non_diffuse: bool,
    // --- Environment map, textures, lens (issue 7) ---
    /// An environment map lights the scene (importance-sampled) and camera misses see it.
    pub environment_map: bool,
    /// Some material takes its albedo from an image through the mesh's uv coordinates.
    pub textures: bool,
    /// The camera has an aperture (`-b R > 0`): camera rays start on the lens disk.
    pub thin_lens: bool,
    // --- end environment map, textures, lens ---
    /// Every flag was forced on by `--all-effects`.
    pub forced: bool,
    /// The effects that are on, in a fixed order, with their reasons.
    pub on: Vec<Effect>,
}

impl Effects {
    pub fn of(scene: &Scene, settings: &Settings) -> Effects {
        let mut e = Effects::default();
        let count = |k: &str| scene.lights.iter().filter(|l| l.kind() == k).count();
        let normals = settings.shading == Shading::Normals;
        let depth = if settings.shading == Shading::Direct { settings.max_depth.min(1) } else { settings.max_depth };
        let lit = !normals && depth >= 1;
        let force = settings.all_effects;
        let forced = |why: Option<String>| why.or_else(|| force.then(|| "forced on by --all-effects".to_string()));
        let mut f = [false; 15];
        // Not forceable: it chooses a different renderer, not a kernel feature.
        if normals {
            f[0] = true;
            e.on.push(Effect { name: "normal-shading", reason: "--shading normals".into() });
        }
        let mut add = |flag: &mut bool, name: &'static str, why: Option<String>| {
            if let Some(reason) = forced(why) {
                *flag = true;
                e.on.push(Effect { name, reason });
            }
        };

        let ns = scene.spheres.len();
        add(&mut f[1], "spheres", (ns > 0).then(|| format!("{ns} analytic sphere(s)")));
        let sees_emission = !normals && (settings.accumulate || depth == 0);
        let emissive_tris =
            scene.mesh.material_ids.iter().filter(|&&m| scene.materials[m as usize].is_emissive()).count();
        let emissive_spheres =
            scene.spheres.iter().filter(|s| scene.materials[s.material as usize].is_emissive()).count();
        add(
            &mut f[2],
            "emission",
            (sees_emission && emissive_tris + emissive_spheres > 0)
                .then(|| format!("{emissive_tris} emissive triangle(s), {emissive_spheres} emissive sphere(s)")),
        );
        let env = match &scene.env {
            Environment::Constant(c) if *c != glam::Vec3::ZERO => Some(format!("constant environment {c}")),
            Environment::Map(m) => Some(format!("environment map {}", m.path.display())),
            _ => None,
        };
        add(
            &mut f[3],
            "environment",
            env.clone().filter(|_| sees_emission).map(|c| format!("{c} seen by camera misses")),
        );
        let areas = count("area");
        let area_reason = if areas > 0 {
            Some(format!("{areas} area light(s), {} sample(s) each", settings.light_samples))
        } else if emissive_tris > 0 {
            Some(format!("{emissive_tris} emissive triangle(s) sampled by area, {} sample(s)", settings.light_samples))
        } else {
            None
        };
        add(&mut f[4], "area-lights", area_reason.filter(|_| lit && !settings.hemisphere));
        let delta = scene.lights.iter().filter(|l| l.is_delta()).count();
        add(
            &mut f[5],
            "delta-lights",
            (lit && !settings.hemisphere && delta > 0)
                .then(|| format!("{delta} point/directional/spot light(s), one shadow ray each")),
        );
        let hemi_light = scene.lights.iter().any(|l| matches!(l, Light::Hemisphere { .. }));
        add(
            &mut f[6],
            "infinite-light",
            (lit && !settings.hemisphere && (hemi_light || env.is_some()))
                .then(|| "hemisphere light or environment sampled".into()),
        );
        let direct_reason = if !lit {
            None
        } else if settings.hemisphere {
            Some("-H: uniform hemisphere probes".to_string())
        } else if f[4] || f[5] || f[6] {
            Some("light sampling: the scene has lights".to_string())
        } else {
            None
        };
        add(&mut f[7], "direct-light", direct_reason);
        let n_of = |kinds: &[&str]| scene.materials.iter().filter(|m| kinds.contains(&m.bsdf.kind())).count();
        let (mirrors, glasses, metals) = (n_of(&["mirror"]), n_of(&["glass", "refraction"]), n_of(&["microfacet"]));
        add(
            &mut f[11],
            "mirror",
            (lit && mirrors > 0).then(|| format!("{mirrors} mirror material(s): delta reflection, no shadow rays")),
        );
        add(
            &mut f[12],
            "glass",
            (lit && glasses > 0)
                .then(|| format!("{glasses} glass/refraction material(s): Fresnel reflection and refraction")),
        );
        add(
            &mut f[13],
            "microfacet",
            (lit && metals > 0)
                .then(|| format!("{metals} rough conductor(s): Beckmann microfacets, MIS of light and BSDF samples")),
        );
        let any_material = f[11] || f[12] || f[13];
        add(&mut f[14], "non-diffuse-shading", any_material.then(|| "BSDF models in the shade kernel".to_string()));
        let indirect = if !normals && settings.shading == Shading::Global && depth > 1 {
            Some(format!("-m {depth} > 1"))
        } else if lit && mirrors + glasses + metals > 0 {
            Some("light found by rays from mirror, glass or glossy surfaces".to_string())
        } else {
            None
        };
        add(&mut f[8], "indirect", indirect);
        add(
            &mut f[9],
            "russian-roulette",
            (!normals && settings.shading == Shading::Global && depth > 2 && settings.rr_continue < 1.0)
                .then(|| format!("-m {depth} > 2 and --rr {} < 1", settings.rr_continue)),
        );
        add(&mut f[10], "adaptive-sampling", settings.adaptive.map(|(b, t)| format!("-a {b} {t}")));
        // --- Environment map, textures, lens (issue 7) ---
        let mut g = [false; 3];
        let mut add = |flag: &mut bool, name: &'static str, why: Option<String>| {
            if let Some(reason) = forced(why) {
                *flag = true;
                e.on.push(Effect { name, reason });
            }
        };
        add(
            &mut g[0],
            "environment-map",
            match &scene.env {
                Environment::Map(m) if !normals => {
                    Some(format!("{} ({}x{}), importance-sampled by luminance", m.path.display(), m.width, m.height))
                }
                _ => None,
            },
        );
        let textured = scene.materials.iter().filter(|m| m.albedo_texture.is_some()).count();
        add(
            &mut g[1],
            "textures",
            (!normals && textured > 0 && scene.mesh.uvs.is_some())
                .then(|| format!("{textured} material(s) with an albedo texture")),
        );
        let r = scene.camera.lens_radius;
        add(
            &mut g[2],
            "thin-lens",
            (r > 0.0).then(|| format!("lens radius {r}, focal distance {}", scene.camera.focal_distance)),
        );
        [e.environment_map, e.textures, e.thin_lens] = g;
        // --- end environment map, textures, lens ---
        [
            e.normal_shading,
            e.spheres,
            e.emission,
            e.environment,
            e.area_lights,
            e.delta_lights,
            e.infinite_light,
            e.direct,
            e.indirect,
            e.russian_roulette,
            e.adaptive,
            e.mirror,
            e.glass,
            e.microfacet,
            e.non_diffuse,
        ] = f;
        e.forced = force;
        e
    }

    pub fn names(&self) -> Vec<&'static str> {
        self.on.iter().map(|e| e.name).collect()
    }
}
