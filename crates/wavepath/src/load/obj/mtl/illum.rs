//! What an MTL material becomes: its illumination model and keys mapped onto wavepath's
//! scattering models (the README's table "What materials become" says the same).
//!
//! | file says | becomes |
//! |---|---|
//! | `illum 4`, `6`, `7`, `9` (glass) | smooth dielectric: index `Ni` (1.5 when absent or not positive), transmittance `Tf` (white when absent); Fresnel alone weighs reflection and refraction (`Ks` unused) |
//! | `Pr` or `Pm` (or their maps), any other model | metallic-roughness (glTF's model): base `Kd`, metalness `Pm` (0), roughness `Pr` (when absent, sqrt of the alpha `Ns` gives below); with `Pc` (and `Pcr`) a clearcoat layer, with `Ps` a sheen layer of colour `Ps` (Blender's sheen roughness 0.5), as glTF's `KHR_materials_clearcoat`/`_sheen` |
//! | `illum 3`, `5`, `8` (mirror) | perfect mirror of reflectance `Ks` (white when absent), no Fresnel term; `Kd` unused |
//! | `illum 2` (or none) with a `Ks` that is not black | `Bsdf::Phong`, shaded by `bsdf/glossy.rs`: Lambertian `Kd` plus a GGX lobe of reflectance `Ks`, alpha = sqrt(2 / (`Ns` + 2)) |
//! | `illum 0`, `1`, `2` with `Ks` black or absent | Lambertian `Kd` (`illum 0`'s unlit colour too: every surface is lit here) |
//! | `illum 10` (shadow matte), or a number outside 0-10 | Lambertian `Kd`, with a warning |
//!
//! The mirror models are Fresnel-free, as the specification's `illum 3` is (`illum 5` and
//! `8` add a Fresnel term to the reflection of the same `Ks`; the two differ only at grazing
//! angles, and Mitsuba's `conductor` of material `none` with `specular_reflectance` `Ks`
//! reflects the same way). Glass uses the exact dielectric Fresnel term for all four models.
//! `illum 8` and `9` differ from `3` and `7` only in not ray-tracing the reflection, which a
//! path tracer always does. `Ka` is read and ignored (no ambient term); `Kd` is 0.5 when
//! absent.

use super::keys::Entry;
use crate::scene::{Bsdf, Layers, Material, Texture, phong_alpha};
use glam::Vec3;

/// Albedo of a material whose block has no `Kd`.
const DEFAULT_KD: f32 = 0.5;
/// Index of refraction of glass whose `Ni` is absent or not positive.
const DEFAULT_NI: f32 = 1.5;

/// The material an entry describes; `notes` gets what could not be followed (without the
/// file name: the caller adds it).
pub fn material(e: &Entry, notes: &mut Vec<String>) -> Material {
    let mut m = Material::diffuse(&e.name, e.kd.unwrap_or(Vec3::splat(DEFAULT_KD)));
    if let Some(ke) = e.ke {
        m.emission = ke;
        // Front face only, as the renderers that read MTL files emit (Mitsuba, pbrt,
        // Blender's importer): the side the face's winding points to.
        m.two_sided_emission = false;
    }
    m.albedo_texture = e.map_kd.clone().map(Texture::obj);
    m.bsdf = bsdf(e, notes);
    m.layers = layers(e, &m.bsdf, notes);
    m
}

/// Blender's sheen roughness (its Principled BSDF's default), which MTL files do not carry.
const SHEEN_ROUGHNESS: f32 = 0.5;

/// The clearcoat and sheen of the PBR extension (`Pc`, `Pcr`, `Ps`) as the layers of the
/// metallic-roughness model; on any other model they have nothing to sit on (a warning).
fn layers(e: &Entry, bsdf: &Bsdf, notes: &mut Vec<String>) -> Option<Box<Layers>> {
    if e.pc.is_none() && e.ps.is_none() {
        return None;
    }
    if !matches!(bsdf, Bsdf::MetallicRoughness { .. }) {
        notes.push(format!("material '{}': Pc/Ps apply to PBR materials (Pr, Pm) only; not applied", e.name));
        return None;
    }
    let pc = e.pc.unwrap_or(0.0).clamp(0.0, 1.0);
    let ps = e.ps.unwrap_or(0.0).clamp(0.0, 1.0);
    Some(Box::new(Layers {
        clearcoat: pc,
        clearcoat_roughness: e.pcr.unwrap_or(0.0).clamp(0.0, 1.0),
        sheen_color: Vec3::splat(ps),
        sheen_roughness: if ps > 0.0 { SHEEN_ROUGHNESS } else { 0.0 },
        ..Layers::default()
    }))
}

fn bsdf(e: &Entry, notes: &mut Vec<String>) -> Bsdf {
    let kd = e.kd.unwrap_or(Vec3::splat(DEFAULT_KD));
    let ks = e.ks.unwrap_or(Vec3::ZERO);
    let illum = e.illum.unwrap_or(2);
    let pbr = e.pr.is_some() || e.pm.is_some() || e.map_pr.is_some() || e.map_pm.is_some();
    match illum {
        4 | 6 | 7 | 9 => {
            let ior = match e.ni {
                Some(n) if n > 0.0 => n,
                Some(n) => {
                    notes.push(format!("material '{}': glass with Ni {n}; using {DEFAULT_NI}", e.name));
                    DEFAULT_NI
                }
                None => DEFAULT_NI,
            };
            Bsdf::Glass { reflectance: Vec3::ONE, transmittance: e.tf.unwrap_or(Vec3::ONE), roughness: 0.0, ior }
        }
        _ if pbr => Bsdf::MetallicRoughness {
            base: kd,
            metallic: e.pm.unwrap_or(0.0),
            // glTF's roughness is the square root of its GGX alpha.
            roughness: e.pr.unwrap_or_else(|| phong_alpha(e.ns.unwrap_or(0.0)).sqrt()),
        },
        3 | 5 | 8 => Bsdf::Mirror { reflectance: e.ks.unwrap_or(Vec3::ONE) },
        0..=2 if ks.max_element() > 0.0 && illum == 2 => {
            Bsdf::Phong { diffuse: kd, specular: ks, shininess: e.ns.unwrap_or(0.0) }
        }
        0..=2 => Bsdf::Diffuse { albedo: kd },
        10 => {
            notes.push(format!("material '{}': illum 10 (shadow matte) rendered as Lambertian Kd", e.name));
            Bsdf::Diffuse { albedo: kd }
        }
        n => {
            notes.push(format!("material '{}': illum {n} is not a model of 0-10; rendered as Lambertian Kd", e.name));
            Bsdf::Diffuse { albedo: kd }
        }
    }
}
