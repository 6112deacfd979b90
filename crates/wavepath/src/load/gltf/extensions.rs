//! What a glTF material adds to the core model: its normal map, the material extensions
//! that add lobes (transmission, ior, volume, specular, clearcoat, sheen: read into
//! [`Layers`]) and the specular-glossiness texture. Clearcoat and sheen are read from the
//! extension's JSON (the gltf crate has no accessors for them); the others through the
//! crate's.

use super::{Images, texture_of, uv_transform};
use crate::scene::{Layers, Material, Relief, ReliefMap, SpecularGlossinessMap};
use glam::{Affine2, Vec3};
use serde_json::Value;

/// The extensions read here (the loader's list of known extensions includes them).
pub const READ: [&str; 6] = [
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_volume",
    "KHR_materials_specular",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
];

/// Textures of `m` read here, each with whether it holds linear data, for the loader to
/// decode with the material's others.
pub fn textures<'a>(m: &gltf::Material<'a>) -> Vec<(gltf::texture::Texture<'a>, bool)> {
    let mut v = Vec::new();
    if let Some(n) = m.normal_texture() {
        v.push((n.texture(), true));
    }
    if let Some(t) = m.transmission().and_then(|t| t.transmission_texture()) {
        v.push((t.texture(), true));
    }
    if let Some(t) = m.pbr_specular_glossiness().and_then(|sg| sg.specular_glossiness_texture()) {
        v.push((t.texture(), false));
    }
    v
}

/// `base` (the core material the loader made of `m`) with what `m`'s normal map,
/// extensions and specular-glossiness texture add.
pub fn extend(mut base: Material, m: &gltf::Material, images: &Images) -> Material {
    if let Some(n) = m.normal_texture() {
        let transform = raw_transform(n.extension_value("KHR_texture_transform"));
        let texture = texture_of(n.texture(), transform, images, true, Vec3::ONE);
        if texture.image.is_some() {
            base.relief = Some(ReliefMap { texture, relief: Relief::Normal { scale: n.scale() } });
        }
    }
    if let Some(sg) = m.pbr_specular_glossiness()
        && let Some(info) = sg.specular_glossiness_texture()
    {
        let transform =
            info.texture_transform().map_or(Affine2::IDENTITY, |t| uv_transform(t.offset(), t.rotation(), t.scale()));
        let specular = texture_of(info.texture(), transform, images, false, Vec3::from(sg.specular_factor()));
        let mut glossiness = texture_of(info.texture(), transform, images, true, Vec3::splat(sg.glossiness_factor()));
        let source = images.by_texture.get(info.texture().index()).copied().flatten();
        glossiness.image = source.and_then(|i| images.gloss_alpha.get(i).cloned().flatten());
        if specular.image.is_some() && glossiness.image.is_some() {
            base.specular_glossiness_texture = Some(Box::new(SpecularGlossinessMap { specular, glossiness }));
        }
    }
    if m.pbr_specular_glossiness().is_some() || m.unlit() {
        return base;
    }
    let mut layers = Layers::default();
    let mut any = false;
    if let Some(t) = m.transmission() {
        any = true;
        layers.transmission = t.transmission_factor().clamp(0.0, 1.0);
        layers.transmission_texture = t.transmission_texture().map(|info| {
            let transform = info
                .texture_transform()
                .map_or(Affine2::IDENTITY, |t| uv_transform(t.offset(), t.rotation(), t.scale()));
            texture_of(info.texture(), transform, images, true, Vec3::splat(layers.transmission))
        });
    }
    if let Some(ior) = m.ior() {
        any = true;
        // ior 0 is the specification's "reflect everything" limit; below 1 is not defined.
        layers.ior = if ior == 0.0 { 1e4 } else { ior.max(1.0) };
    }
    if let Some(v) = m.volume() {
        any = true;
        layers.thickness = v.thickness_factor().max(0.0);
        layers.attenuation_color = Vec3::from(v.attenuation_color()).clamp(Vec3::ZERO, Vec3::ONE);
        layers.attenuation_distance = v.attenuation_distance();
    }
    if let Some(s) = m.specular() {
        any = true;
        layers.specular = s.specular_factor().clamp(0.0, 1.0);
        layers.specular_color = Vec3::from(s.specular_color_factor()).max(Vec3::ZERO);
    }
    if let Some(c) = m.extension_value("KHR_materials_clearcoat") {
        any = true;
        layers.clearcoat = number(c, "clearcoatFactor", 0.0).clamp(0.0, 1.0);
        layers.clearcoat_roughness = number(c, "clearcoatRoughnessFactor", 0.0).clamp(0.0, 1.0);
    }
    if let Some(s) = m.extension_value("KHR_materials_sheen") {
        any = true;
        layers.sheen_color = colour(s, "sheenColorFactor", Vec3::ZERO).clamp(Vec3::ZERO, Vec3::ONE);
        layers.sheen_roughness = number(s, "sheenRoughnessFactor", 0.0).clamp(0.0, 1.0);
    }
    if any {
        base.layers = Some(Box::new(layers));
    }
    base
}

fn number(v: &Value, key: &str, default: f32) -> f32 {
    v.get(key).and_then(Value::as_f64).map_or(default, |x| x as f32)
}

fn colour(v: &Value, key: &str, default: Vec3) -> Vec3 {
    let Some(a) = v.get(key).and_then(Value::as_array) else { return default };
    let c: Vec<f32> = a.iter().filter_map(Value::as_f64).map(|x| x as f32).collect();
    if c.len() == 3 { Vec3::new(c[0], c[1], c[2]) } else { default }
}

/// A `KHR_texture_transform` object read from its JSON (on a normal texture the crate has
/// no accessor for it).
fn raw_transform(v: Option<&Value>) -> Affine2 {
    let Some(v) = v else { return Affine2::IDENTITY };
    let pair = |key: &str, d: [f32; 2]| {
        v.get(key)
            .and_then(Value::as_array)
            .and_then(|a| Some([a.first()?.as_f64()? as f32, a.get(1)?.as_f64()? as f32]))
            .unwrap_or(d)
    };
    uv_transform(pair("offset", [0.0, 0.0]), number(v, "rotation", 0.0), pair("scale", [1.0, 1.0]))
}
