//! Which effects a scene calls for under given settings, and why.
//!
//! Derived once before rendering; a stage or kernel for an effect that is off never runs,
//! and the log and stats list the effects that are on with their reasons.

use crate::scene::{Bsdf, Light, Scene};
use crate::settings::{Settings, Shading};

/// One effect that is on, and the reason it is on.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Effect {
    pub name: &'static str,
    pub reason: String,
}

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Effects {
    pub on: Vec<Effect>,
}

impl Effects {
    pub fn of(scene: &Scene, settings: &Settings) -> Effects {
        let mut on = Vec::new();
        let mut add = |name: &'static str, reason: String| on.push(Effect { name, reason });
        let count = |k: &str| scene.lights.iter().filter(|l| l.kind() == k).count();
        let lit = settings.shading != Shading::Normals && settings.max_depth >= 1;
        if settings.shading == Shading::Normals {
            add("normal-shading", "--shading normals".into());
        }
        if !scene.spheres.is_empty() {
            add("spheres", format!("{} analytic sphere(s)", scene.spheres.len()));
        }
        let emissive_tris =
            scene.mesh.material_ids.iter().filter(|&&m| scene.materials[m as usize].is_emissive()).count();
        if settings.shading != Shading::Normals && emissive_tris > 0 {
            add("emission", format!("{emissive_tris} emissive triangle(s)"));
        }
        if lit {
            if count("area") > 0 {
                add(
                    "area-lights",
                    format!("{} area light(s), {} sample(s) each", count("area"), settings.light_samples),
                );
            }
            let delta = scene.lights.iter().filter(|l| l.is_delta()).count();
            if delta > 0 {
                add("delta-lights", format!("{delta} point/directional/spot light(s)"));
            }
            if scene.lights.iter().any(|l| matches!(l, Light::Hemisphere { .. })) {
                add("hemisphere-light", "ambient light in the scene".into());
            }
        }
        if settings.shading == Shading::Global && settings.max_depth > 1 {
            add("indirect", format!("-m {} > 1", settings.max_depth));
            if settings.max_depth > 2 && settings.rr_continue < 1.0 {
                add("russian-roulette", format!("-m {} > 2 and --rr {} < 1", settings.max_depth, settings.rr_continue));
            }
        }
        if let Some((b, t)) = settings.adaptive {
            add("adaptive-sampling", format!("-a {b} {t}"));
        }
        let specular = scene.materials.iter().filter(|m| !matches!(m.bsdf, Bsdf::Diffuse { .. })).count();
        if specular > 0 {
            add("non-diffuse-materials", format!("{specular} material(s) parsed; rendered as diffuse for now"));
        }
        Effects { on }
    }

    pub fn names(&self) -> Vec<&'static str> {
        self.on.iter().map(|e| e.name).collect()
    }
}
