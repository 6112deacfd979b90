//! glTF materials as glTF means them: metallic-roughness (factors, defaults and its linear
//! texture), specular-glossiness, unlit, material extensions wavepath does not render
//! (accepted with one warning), `KHR_texture_transform` and the uv set a texture names.

use crate::accel::{BruteForce, Intersector, TraceCounters};
use crate::bsdf::Model;
use crate::geometry::Ray;
use crate::integrator::Transport;
use crate::load::{LoadOptions, load};
use crate::scene::texture::Textures;
use crate::scene::{Bsdf, Scene};
use crate::settings::Settings;
use crate::tests::common::temp_dir;
use base64::Engine;
use glam::{Affine2, DMat3, DVec3, Vec2, Vec3, vec2, vec3};
use std::path::Path;

fn b64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// A PNG of `texels` (one row), as a data URI.
fn png_uri(texels: &[[u8; 3]]) -> String {
    let img = image::RgbImage::from_fn(texels.len() as u32, 1, |x, _| image::Rgb(texels[x as usize]));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    format!("data:image/png;base64,{}", b64(&out.into_inner()))
}

/// One triangle with uv sets 0 and 1 (set 0 all zero, set 1 the corners' own), using
/// material 0; `extra` adds top-level members (materials, textures, images, extensions).
fn triangle_doc(extra: &str) -> String {
    let pos = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let uv1 = [[0.1f32, 0.2], [0.9, 0.2], [0.1, 0.8]];
    let mut bytes: Vec<u8> = pos.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    bytes.extend([0u8; 24]);
    bytes.extend(uv1.iter().flatten().flat_map(|c| c.to_le_bytes()));
    format!(
        r#"{{"asset":{{"version":"2.0"}},
          "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1,"TEXCOORD_1":2}},"material":0}}]}}],
          "nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],
          "buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{uri}"}}],
          "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}},{{"buffer":0,"byteOffset":60,"byteLength":24}}],
          "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                       {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}},
                       {{"bufferView":2,"componentType":5126,"count":3,"type":"VEC2"}}],
          {extra}}}"#,
        len = bytes.len(),
        uri = b64(&bytes)
    )
}

fn load_doc(dir: &Path, name: &str, doc: &str) -> Scene {
    std::fs::write(dir.join(name), doc).unwrap();
    load(&dir.join(name), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e:#}"))
}

#[test]
fn gltf_materials_map_onto_their_models() {
    let d = temp_dir("gltf-materials");
    // Factors as written; an empty material takes the specification's defaults (metallic 1,
    // roughness 1, white); unlit emits its base colour; specular-glossiness keeps its own
    // parameters. Two extensions wavepath does not render (one required) cost one warning.
    let doc = triangle_doc(
        r#""extensionsUsed":["KHR_materials_unlit","KHR_materials_pbrSpecularGlossiness","KHR_materials_anisotropy","KHR_materials_iridescence"],
           "extensionsRequired":["KHR_materials_unlit","KHR_materials_pbrSpecularGlossiness","KHR_materials_iridescence"],
           "materials":[
             {"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.4,0.2,1],"metallicFactor":0.25,"roughnessFactor":0.6}},
             {},
             {"pbrMetallicRoughness":{"baseColorFactor":[0.3,0.6,0.9,1]},"extensions":{"KHR_materials_unlit":{}}},
             {"extensions":{"KHR_materials_pbrSpecularGlossiness":{"diffuseFactor":[0.5,0.5,0.25,1],"specularFactor":[0.2,0.3,0.4],"glossinessFactor":0.7}}},
             {"pbrMetallicRoughness":{"metallicFactor":0},"extensions":{"KHR_materials_anisotropy":{"anisotropyStrength":1},"KHR_materials_iridescence":{"iridescenceFactor":1}}},
             {"emissiveFactor":[1,1,1],"doubleSided":true},
             {"emissiveFactor":[1,1,1],"doubleSided":true,"extensions":{"KHR_materials_unlit":{}}}
           ]"#,
    );
    let s = load_doc(&d, "m.gltf", &doc);
    let m = &s.materials;
    assert_eq!(m[0].bsdf, Bsdf::MetallicRoughness { base: vec3(0.8, 0.4, 0.2), metallic: 0.25, roughness: 0.6 });
    assert_eq!(m[1].bsdf, Bsdf::MetallicRoughness { base: Vec3::ONE, metallic: 1.0, roughness: 1.0 });
    assert_eq!((m[2].bsdf.diffuse_albedo(), m[2].emission), (Vec3::ZERO, vec3(0.3, 0.6, 0.9)));
    assert_eq!(
        m[3].bsdf,
        Bsdf::SpecularGlossiness { diffuse: vec3(0.5, 0.5, 0.25), specular: vec3(0.2, 0.3, 0.4), glossiness: 0.7 }
    );
    assert_eq!(m[4].bsdf, Bsdf::MetallicRoughness { base: Vec3::ONE, metallic: 0.0, roughness: 1.0 });
    // Emission from the front face only unless the material is double-sided.
    let two_sided: Vec<bool> = m.iter().take(7).map(|m| m.two_sided_emission).collect();
    assert_eq!(two_sided, [false, false, false, false, false, true, true]);
    assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
    let note = &s.notes[0];
    assert!(note.contains("KHR_materials_anisotropy, KHR_materials_iridescence") && note.contains("m.gltf"), "{note}");
}

/// The metallic-roughness texture is linear data: blue scales metalness, green roughness,
/// and what a shaded point sees is texel x factor.
#[test]
fn metallic_roughness_texture_is_linear_and_scales_the_factors() {
    let d = temp_dir("gltf-mr-texture");
    let uri = png_uri(&[[0, 128, 255], [0, 255, 0]]);
    let doc = triangle_doc(&format!(
        r#""materials":[{{"pbrMetallicRoughness":{{"metallicFactor":0.5,"roughnessFactor":0.8,
               "metallicRoughnessTexture":{{"index":0,"texCoord":1}}}}}}],
           "samplers":[{{"magFilter":9728}}],"textures":[{{"source":0,"sampler":0}}],"images":[{{"uri":"{uri}"}}]"#
    ));
    let s = load_doc(&d, "mr.gltf", &doc);
    let t = Textures::new(&s);
    // Nearest texel: u < 0.5 reads the first, u > 0.5 the second; no sRGB curve applied.
    let first = t.metal_rough(0, vec2(0.25, 0.5)).expect("a metallic-roughness texture");
    let second = t.metal_rough(0, vec2(0.75, 0.5)).unwrap();
    assert!((first - vec2(0.5, 0.8 * 128.0 / 255.0)).abs().max_element() < 1e-6, "{first}");
    assert!((second - vec2(0.0, 0.8)).abs().max_element() < 1e-6, "{second}");
    // The texture names uv set 1: the mesh carries it.
    assert_eq!(s.mesh.uvs.as_deref(), Some(&[vec2(0.1, 0.2), vec2(0.9, 0.2), vec2(0.1, 0.8)][..]));
    // A shaded point takes its texel's values: at (x, y) the uv is (0.1 + 0.8 x, 0.2 + 0.6 y),
    // so (0.2, 0.2) reads the first texel and (0.7, 0.1) the second. White base:
    // f0 = lerp(0.04, 1, metallic), alpha = roughness^2.
    let t = Transport::new(&s, &Settings::default(), &crate::effects::Effects::of(&s, &Settings::default()));
    let accel = BruteForce::new(&s);
    for (x, y, metallic, roughness) in [(0.2, 0.2, 0.5, 0.8 * 128.0 / 255.0), (0.7, 0.1, 0.0, 0.8)] {
        let ray = Ray { origin: vec3(x, y, 1.0), dir: -Vec3::Z, tmin: 0.0, tmax: f32::INFINITY };
        let hit = accel.closest_hit(&ray, &mut TraceCounters::default()).expect("the triangle");
        let v = t.vertex(&ray, &hit);
        let Model::Pbr(p) = t.shading(&v, ray.dir).model else { panic!("not the glTF model") };
        let f0 = 0.04 + 0.96 * metallic;
        assert!((p.f0 - Vec3::splat(f0)).abs().max_element() < 1e-5, "({x}, {y}): f0 {}", p.f0);
        assert!((p.alpha - roughness * roughness).abs() < 1e-5, "({x}, {y}): alpha {}", p.alpha);
    }
}

/// KHR_texture_transform's matrix, built here as the extension writes it (3x3, offset x
/// rotation x scale, rotation rows [cos sin; -sin cos]), against the loaded texture's, and a
/// lookup that the offset moves onto the other texel; its texCoord override picks the set.
#[test]
fn texture_transform_and_its_uv_set() {
    let d = temp_dir("gltf-texture-transform");
    let uri = png_uri(&[[255, 0, 0], [0, 0, 255]]);
    let (offset, rotation, scale) = ([0.5f64, 0.25], 0.3f64, [2.0f64, 0.5]);
    let doc = triangle_doc(&format!(
        r#""extensionsUsed":["KHR_texture_transform"],"extensionsRequired":["KHR_texture_transform"],
           "materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0,
               "extensions":{{"KHR_texture_transform":{{"offset":[{},{}],"rotation":{rotation},"scale":[{},{}],"texCoord":1}}}}}}}}}}],
           "samplers":[{{"magFilter":9728}}],"textures":[{{"source":0,"sampler":0}}],"images":[{{"uri":"{uri}"}}]"#,
        offset[0], offset[1], scale[0], scale[1]
    ));
    let s = load_doc(&d, "tt.gltf", &doc);
    assert!(s.notes.is_empty(), "{:?}", s.notes);
    let tex = s.materials[0].albedo_texture.clone().expect("a base colour texture");
    let (c, sn) = (rotation.cos(), rotation.sin());
    let t = DMat3::from_cols(DVec3::X, DVec3::Y, DVec3::new(offset[0], offset[1], 1.0));
    let r = DMat3::from_cols(DVec3::new(c, -sn, 0.0), DVec3::new(sn, c, 0.0), DVec3::Z);
    let sc = DMat3::from_diagonal(DVec3::new(scale[0], scale[1], 1.0));
    let m = t * r * sc;
    for uv in [vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(0.3, 0.7), vec2(-2.0, 5.0)] {
        let want = m * DVec3::new(uv.x as f64, uv.y as f64, 1.0);
        let got = tex.transform.transform_point2(uv);
        assert!((got.as_dvec2() - want.truncate()).abs().max_element() < 1e-5, "{uv}: {got} vs {want}");
    }
    // The override names set 1.
    assert_eq!(s.mesh.uvs.as_ref().unwrap()[1], vec2(0.9, 0.2));
    // Offset only: u 0.25 + 0.5 reads the blue texel, u 0.75 + 0.5 wraps onto the red one.
    let shifted = crate::scene::Texture { transform: Affine2::from_translation(Vec2::new(0.5, 0.0)), ..tex };
    assert_eq!(shifted.albedo(vec2(0.25, 0.5)), Some(vec3(0.0, 0.0, 1.0)));
    assert_eq!(shifted.albedo(vec2(0.75, 0.5)), Some(vec3(1.0, 0.0, 0.0)));
}

/// An icosphere written as a Draco-compressed glTF primitive (by draco-core's encoder,
/// positions quantised to 14 bits, uvs to 12): it loads with the same triangles, each
/// matching an original one within the quantisation step, facing outward, and uvs that
/// follow their positions; a truncated stream is a one-line error naming the extension.
#[test]
fn draco_compressed_primitives_decode_to_their_mesh() {
    use draco_core::{
        DataType, EncoderBuffer, EncoderOptions, FaceIndex, GeometryAttributeType, Mesh, MeshEncoder, PointAttribute,
    };
    let sphere = crate::tests::common::meshgen::icosphere(4);
    let n = sphere.positions.len();
    let uv_of = |p: Vec3| vec2(0.5 + 0.5 * p.x, 0.5 + 0.5 * p.y);
    let mut mesh = Mesh::new();
    let mut pos = PointAttribute::new();
    pos.init(GeometryAttributeType::Position, 3, DataType::Float32, false, n);
    let mut uv = PointAttribute::new();
    uv.init(GeometryAttributeType::TexCoord, 2, DataType::Float32, false, n);
    for (i, p) in sphere.positions.iter().enumerate() {
        for (c, v) in p.to_array().iter().enumerate() {
            pos.buffer_mut().write((3 * i + c) * 4, &v.to_le_bytes());
        }
        for (c, v) in uv_of(*p).to_array().iter().enumerate() {
            uv.buffer_mut().write((2 * i + c) * 4, &v.to_le_bytes());
        }
    }
    let (pos_id, uv_id) = (mesh.add_attribute(pos), mesh.add_attribute(uv));
    mesh.set_num_faces(sphere.triangles.len());
    for (f, t) in sphere.triangles.iter().enumerate() {
        mesh.set_face(FaceIndex(f as u32), t.map(|i| i.into()));
    }
    let mut options = EncoderOptions::new();
    options.set_attribute_quantization(pos_id, 14);
    options.set_attribute_quantization(uv_id, 12);
    let mut encoder = MeshEncoder::new();
    encoder.set_mesh(mesh);
    let mut out = EncoderBuffer::new();
    encoder.encode(&options, &mut out).expect("draco encode");
    let bytes = out.data().to_vec();
    let doc = |bytes: &[u8]| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_draco_mesh_compression"],"extensionsRequired":["KHR_draco_mesh_compression"],
              "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,
                 "extensions":{{"KHR_draco_mesh_compression":{{"bufferView":0,"attributes":{{"POSITION":{pos_id},"TEXCOORD_0":{uv_id}}}}}}}}}]}}],
              "nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],
              "buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{uri}"}}],
              "bufferViews":[{{"buffer":0,"byteLength":{len}}}],
              "accessors":[{{"componentType":5126,"count":{n},"type":"VEC3","min":[-1,-1,-1],"max":[1,1,1]}},
                           {{"componentType":5126,"count":{n},"type":"VEC2"}},
                           {{"componentType":5125,"count":{idx},"type":"SCALAR"}}]}}"#,
            len = bytes.len(),
            uri = b64(bytes),
            idx = 3 * sphere.triangles.len()
        )
    };
    let d = temp_dir("gltf-draco");
    let s = load_doc(&d, "draco.gltf", &doc(&bytes));
    assert_eq!(s.mesh.triangles.len(), sphere.triangles.len());
    let step = 2.0 / (1 << 14) as f32;
    let original: Vec<[Vec3; 3]> = (0..sphere.triangles.len()).map(|i| sphere.corners(i)).collect();
    for i in 0..s.mesh.triangles.len() {
        let c = s.mesh.corners(i);
        let centroid = (c[0] + c[1] + c[2]) / 3.0;
        let near = original
            .iter()
            .min_by(|a, b| {
                let d = |t: &&[Vec3; 3]| ((t[0] + t[1] + t[2]) / 3.0).distance(centroid);
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        for p in c {
            let closest = near.iter().map(|q| q.distance(p)).fold(f32::INFINITY, f32::min);
            assert!(closest <= step, "triangle {i}: corner {p} is {closest} from the original's");
        }
        assert!((c[1] - c[0]).cross(c[2] - c[0]).dot(centroid) > 0.0, "triangle {i} turned inward");
    }
    let uvs = s.mesh.uvs.as_ref().expect("uvs decoded");
    for (p, t) in s.mesh.positions.iter().zip(uvs) {
        assert!((uv_of(*p) - *t).abs().max_element() < 1e-3, "uv {t} at {p}");
    }
    // Damaged: the stream cut in half.
    let path = d.join("cut.gltf");
    std::fs::write(&path, doc(&bytes[..bytes.len() / 2])).unwrap();
    let e = format!("{:#}", load(&path, &LoadOptions::default()).unwrap_err());
    assert!(e.contains("cut.gltf") && e.contains("KHR_draco_mesh_compression") && !e.contains('\n'), "{e}");
}

/// Textures whose only image is in an extension: WebP (`EXT_texture_webp`, required) is
/// decoded; KTX2 (`KHR_texture_basisu`, required) cannot be: the model loads with its
/// factors and one warning naming the extension.
#[test]
fn extension_images_webp_decoded_ktx2_a_warning() {
    let d = temp_dir("gltf-ext-images");
    let img =
        image::RgbImage::from_fn(2, 1, |x, _| if x == 0 { image::Rgb([255, 0, 0]) } else { image::Rgb([0, 0, 255]) });
    let mut webp = std::io::Cursor::new(Vec::new());
    img.write_to(&mut webp, image::ImageFormat::WebP).unwrap();
    let webp_uri = format!("data:image/webp;base64,{}", b64(&webp.into_inner()));
    let with = |ext: &str, uri: &str| {
        triangle_doc(&format!(
            r#""extensionsUsed":["{ext}"],"extensionsRequired":["{ext}"],
               "materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.5,0.25,1,1],"baseColorTexture":{{"index":0}}}}}}],
               "textures":[{{"extensions":{{"{ext}":{{"source":0}}}}}}],"images":[{{"uri":"{uri}"}}]"#
        ))
    };
    let s = load_doc(&d, "webp.gltf", &with("EXT_texture_webp", &webp_uri));
    assert!(s.notes.is_empty(), "{:?}", s.notes);
    let t = s.materials[0].albedo_texture.as_ref().and_then(|t| t.image.clone()).expect("the WebP image");
    assert_eq!(t.texels, vec![vec3(1.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0)]);
    let s = load_doc(&d, "ktx2.gltf", &with("KHR_texture_basisu", "x.ktx2"));
    assert!(s.materials[0].albedo_texture.as_ref().is_none_or(|t| t.image.is_none()));
    assert_eq!(s.materials[0].bsdf.diffuse_albedo(), vec3(0.5, 0.25, 1.0));
    let warned: Vec<&String> = s.notes.iter().filter(|n| n.contains("KHR_texture_basisu")).collect();
    assert!(
        !warned.is_empty() && s.notes.iter().all(|n| n.contains("ktx2.gltf") && !n.contains('\n')),
        "{:?}",
        s.notes
    );
}
