//! glTF material extensions read into the layered model, each from a small file written
//! here: the values as written, the specification's defaults where a member is absent, no
//! warning for the ones read, and the specular-glossiness texture (specular colour in RGB,
//! glossiness in alpha).

use crate::bsdf::Model;
use crate::load::{LoadOptions, load};
use crate::scene::texture::Textures;
use crate::scene::{Layers, Scene};
use crate::tests::common::temp_dir;
use base64::Engine;
use glam::{vec2, vec3};

fn b64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// One triangle with uvs, in a glTF file with its buffer in a `.bin` beside it; `extra`
/// adds top-level members.
fn write_triangle(dir: &std::path::Path, name: &str, extra: &str) -> Scene {
    let pos = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let uv = [[0.25f32, 0.5], [0.25, 0.5], [0.25, 0.5]];
    let mut bytes: Vec<u8> = pos.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    bytes.extend(uv.iter().flatten().flat_map(|c| c.to_le_bytes()));
    std::fs::write(dir.join("t.bin"), &bytes).unwrap();
    let doc = format!(
        r#"{{"asset":{{"version":"2.0"}},
          "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"material":0}}]}}],
          "nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],
          "buffers":[{{"byteLength":{len},"uri":"t.bin"}}],
          "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}}],
          "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                       {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}}],
          {extra}}}"#,
        len = bytes.len()
    );
    std::fs::write(dir.join(name), doc).unwrap();
    load(&dir.join(name), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e:#}"))
}

#[test]
fn each_material_extension_is_read() {
    let d = temp_dir("gltf-khr");
    let s = write_triangle(
        &d,
        "k.gltf",
        r#""extensionsUsed":["KHR_materials_transmission","KHR_materials_ior","KHR_materials_volume","KHR_materials_specular","KHR_materials_clearcoat","KHR_materials_sheen"],
           "materials":[
             {"extensions":{
               "KHR_materials_transmission":{"transmissionFactor":0.75},
               "KHR_materials_ior":{"ior":1.33},
               "KHR_materials_volume":{"thicknessFactor":0.2,"attenuationDistance":0.5,"attenuationColor":[0.9,0.8,0.7]},
               "KHR_materials_specular":{"specularFactor":0.6,"specularColorFactor":[1.0,0.5,0.25]},
               "KHR_materials_clearcoat":{"clearcoatFactor":0.9,"clearcoatRoughnessFactor":0.3},
               "KHR_materials_sheen":{"sheenColorFactor":[0.2,0.4,0.6],"sheenRoughnessFactor":0.7}}},
             {"extensions":{"KHR_materials_transmission":{},"KHR_materials_volume":{},"KHR_materials_clearcoat":{},"KHR_materials_sheen":{}}},
             {}
           ]"#,
    );
    assert!(s.notes.is_empty(), "no warning for extensions that are read: {:?}", s.notes);
    let l = s.materials[0].layers.as_deref().expect("layers");
    let want = Layers {
        transmission: 0.75,
        transmission_texture: None,
        ior: 1.33,
        thickness: 0.2,
        attenuation_color: vec3(0.9, 0.8, 0.7),
        attenuation_distance: 0.5,
        specular: 0.6,
        specular_color: vec3(1.0, 0.5, 0.25),
        clearcoat: 0.9,
        clearcoat_roughness: 0.3,
        sheen_color: vec3(0.2, 0.4, 0.6),
        sheen_roughness: 0.7,
    };
    assert_eq!(*l, want);
    // sigma = -ln(c) / distance.
    let sigma = l.sigma_a();
    assert!((sigma - vec3(-(0.9f32.ln()), -(0.8f32.ln()), -(0.7f32.ln())) / 0.5).abs().max_element() < 1e-6);
    // Present but empty: the specification's defaults (no transmission, a thin wall, clear,
    // no coat, no sheen), which leave the core model's reflection unchanged.
    assert_eq!(*s.materials[1].layers.as_deref().unwrap(), Layers::default());
    assert!(s.materials[2].layers.is_none() && s.mesh.tangents.is_none(), "a plain material adds nothing");
    // The layered model is what shades them.
    assert!(matches!(Model::of_material(&s.materials[0]), Model::Layered(_)));
    assert!(matches!(Model::of_material(&s.materials[2]), Model::Pbr(_)));
}

/// Layers with the defaults reflect exactly as the core model does (the same BRDF).
#[test]
fn default_layers_are_the_core_model() {
    let (base, metallic, roughness) = (vec3(0.8, 0.5, 0.2), 0.3, 0.45);
    let core = crate::bsdf::Pbr::metallic_roughness(base, metallic, roughness);
    let layered = crate::bsdf::Layered::new(base, metallic, roughness, 0.0, &Layers::default());
    for (wo, wi) in [(vec3(0.3, 0.1, 0.9), vec3(-0.5, 0.2, 0.7)), (vec3(0.0, 0.6, 0.5), vec3(0.1, -0.6, 0.4))] {
        let (wo, wi) = (wo.normalize(), wi.normalize());
        let (a, b) = (core.eval(wo, wi), layered.eval(wo, wi));
        assert!((a - b).abs().max_element() < 1e-6 * a.max_element().max(1.0), "{a} vs {b}");
    }
}

#[test]
fn specular_glossiness_texture_is_read() {
    let d = temp_dir("gltf-sg-texture");
    // One RGBA texel: specular (sRGB) 128, 64, 255 and glossiness (alpha, linear) 51.
    let img = image::RgbaImage::from_pixel(1, 1, image::Rgba([128, 64, 255, 51]));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    let uri = format!("data:image/png;base64,{}", b64(&out.into_inner()));
    let s = write_triangle(
        &d,
        "sg.gltf",
        &format!(
            r#""extensionsUsed":["KHR_materials_pbrSpecularGlossiness"],
               "materials":[{{"extensions":{{"KHR_materials_pbrSpecularGlossiness":{{"specularFactor":[0.5,1,1],"glossinessFactor":0.5,
                 "specularGlossinessTexture":{{"index":0}}}}}}}}],
               "textures":[{{"source":0}}],"images":[{{"uri":"{uri}"}}]"#
        ),
    );
    assert!(s.notes.is_empty(), "{:?}", s.notes);
    let t = Textures::new(&s);
    let (spec, gloss) = t.specular_glossiness(0, vec2(0.25, 0.5)).expect("the texture");
    let srgb = crate::scene::texture::srgb_to_linear;
    let want = vec3(0.5 * srgb(128.0 / 255.0), srgb(64.0 / 255.0), 1.0);
    assert!((spec - want).abs().max_element() < 1e-6, "{spec} vs {want}");
    assert!((gloss - 0.5 * 51.0 / 255.0).abs() < 1e-6, "{gloss}");
}
