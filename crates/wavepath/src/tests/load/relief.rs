//! Relief maps through the loaders: a flat square with a known normal map (glTF with its
//! own tangents or MikkTSpace ones, MTL `norm`) or height map (MTL `bump -bm`) renders in
//! the normals view as the tilted plane the map encodes, pixel by pixel; and the uvs such a
//! map is read through survive the front ends' freeing of unread uvs.

use crate::accel::BruteForce;
use crate::load::{LoadOptions, load};
use crate::render::{render, render_normals};
use crate::scene::{Camera, Scene};
use crate::settings::{Settings, Shading};
use crate::tests::common::{self, temp_dir};
use base64::Engine;
use glam::{Vec3, vec3};
use std::path::Path;

fn b64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// A PNG of one row of RGB texels.
fn png(texels: &[[u8; 3]]) -> Vec<u8> {
    let img = image::RgbImage::from_fn(texels.len() as u32, 1, |x, _| image::Rgb(texels[x as usize]));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// The unit square in z = 0 (normal +z) as a glTF file with a normal texture of one texel;
/// uv = (x, 1 - y), glTF's v down the image, so the image's up is +y. `tangents`: with a
/// TANGENT attribute (+x, w = 1), else the loader derives MikkTSpace ones.
fn square_gltf(texel: [u8; 3], scale: f32, tangents: bool) -> String {
    let pos = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let nrm = [[0.0f32, 0.0, 1.0]; 4];
    let uv = [[0.0f32, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let tan = [[1.0f32, 0.0, 0.0, 1.0]; 4];
    let idx: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bytes: Vec<u8> = pos.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    bytes.extend(nrm.iter().flatten().flat_map(|c| c.to_le_bytes()));
    bytes.extend(uv.iter().flatten().flat_map(|c| c.to_le_bytes()));
    bytes.extend(tan.iter().flatten().flat_map(|c| c.to_le_bytes()));
    bytes.extend(idx.iter().flat_map(|c| c.to_le_bytes()));
    let tangent_attr = if tangents { r#","TANGENT":3"# } else { "" };
    format!(
        r#"{{"asset":{{"version":"2.0"}},
          "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2{tangent_attr}}},"indices":4,"material":0}}]}}],
          "nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],
          "buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{uri}"}}],
          "bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":48}},
                         {{"buffer":0,"byteOffset":96,"byteLength":32}},{{"buffer":0,"byteOffset":128,"byteLength":64}},
                         {{"buffer":0,"byteOffset":192,"byteLength":12}}],
          "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                       {{"bufferView":1,"componentType":5126,"count":4,"type":"VEC3"}},
                       {{"bufferView":2,"componentType":5126,"count":4,"type":"VEC2"}},
                       {{"bufferView":3,"componentType":5126,"count":4,"type":"VEC4"}},
                       {{"bufferView":4,"componentType":5123,"count":6,"type":"SCALAR"}}],
          "materials":[{{"normalTexture":{{"index":0,"scale":{scale}}}}}],
          "textures":[{{"source":0}}],"images":[{{"uri":"data:image/png;base64,{img}"}}]}}"#,
        len = bytes.len(),
        uri = b64(&bytes),
        img = b64(&png(&[texel]))
    )
}

/// Renders `scene` in the normals view from above the square's middle (every pixel sees
/// it) and checks each pixel against `n`, the expected unit normal.
fn assert_normals(scene: &mut Scene, n: Vec3, within: impl Fn(f32) -> bool, what: &str) {
    scene.camera = Camera::look_at(vec3(0.5, 0.5, 2.0), vec3(0.5, 0.5, 0.0), Vec3::Y, 10.0, 1.0);
    let s = common::render::settings(12, 12, 1, 1);
    let (film, _) = render_normals(scene, &scene.camera, &BruteForce::new(scene), &s);
    let want = n * 0.5 + Vec3::splat(0.5);
    let mut checked = 0;
    for (i, p) in film.pixels.iter().enumerate() {
        let x = 0.5 + ((i % 12) as f32 + 0.5 - 6.0) / 12.0 * 2.0 * 2.0 * 5f32.to_radians().tan();
        if !within(x) {
            continue;
        }
        checked += 1;
        assert!((*p - want).abs().max_element() < 2e-5, "{what}: pixel {i} is {p}, want {want}");
    }
    assert!(checked > 50, "{what}: only {checked} pixels checked");
}

fn load_file(dir: &Path, name: &str, text: &str) -> Scene {
    std::fs::write(dir.join(name), text).unwrap();
    load(&dir.join(name), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e:#}"))
}

/// The tangent-space normal a texel encodes, x and y scaled, in the square's frame
/// (tangent +x, bitangent +y = up in the image, normal +z).
fn encoded(texel: [u8; 3], scale: f32) -> Vec3 {
    let c = |v: u8| 2.0 * v as f32 / 255.0 - 1.0;
    vec3(c(texel[0]) * scale, c(texel[1]) * scale, c(texel[2])).normalize()
}

#[test]
fn gltf_normal_map_tilts_the_plane_it_encodes() {
    let d = temp_dir("relief-gltf");
    let texel = [200u8, 90, 230];
    for (tangents, scale) in [(true, 1.0f32), (false, 1.0), (true, 0.5)] {
        let mut s = load_file(&d, "n.gltf", &square_gltf(texel, scale, tangents));
        let t = s.mesh.tangents.as_deref().expect("tangents for a normal-mapped mesh");
        for v in t {
            assert!((v.truncate() - Vec3::X).length() < 1e-5 && v.w == 1.0, "tangent {v} (file's: {tangents})");
        }
        assert_normals(&mut s, encoded(texel, scale), |_| true, &format!("tangents {tangents}, scale {scale}"));
    }
}

#[test]
fn mtl_normal_and_bump_maps_tilt_the_plane() {
    let d = temp_dir("relief-obj");
    // OBJ uv = (x, y): v up, as the image's up.
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl m\nf 1/1/1 2/2/1 3/3/1 4/4/1\n";
    let texel = [60u8, 170, 220];
    std::fs::write(d.join("n.png"), png(&[texel])).unwrap();
    std::fs::write(d.join("m.mtl"), "newmtl m\nKd 0.5 0.5 0.5\nnorm n.png\n").unwrap();
    let mut s = load_file(&d, "a.obj", obj);
    assert!(s.mesh.tangents.is_none(), "OBJ normal maps use the uv parametrisation, no stored tangents");
    assert_normals(&mut s, encoded(texel, 1.0), |_| true, "norm");

    // A height ramp: texel k is 32 k (8 texels), so between the first and the last texel
    // centres h rises by 32/255 per texel (1/8 of u), times -bm. The displaced surface
    // z = bm h(x) has the normal (-dz/dx, 0, 1).
    let ramp: Vec<[u8; 3]> = (0..8).map(|k| [32 * k as u8; 3]).collect();
    std::fs::write(d.join("h.png"), png(&ramp)).unwrap();
    let bm = 0.25f32;
    std::fs::write(d.join("m.mtl"), format!("newmtl m\nKd 0.5 0.5 0.5\nbump -bm {bm} h.png\n")).unwrap();
    let mut s = load_file(&d, "b.obj", obj);
    let slope = bm * 32.0 / 255.0 * 8.0;
    assert_normals(&mut s, vec3(-slope, 0.0, 1.0).normalize(), |x| (0.15..0.85).contains(&x), "bump");
}

/// Both front ends free the uvs no map reads (`Scene::drop_unused_uvs`) before they render.
/// A normal map is read through them: a square of one constant base colour whose only map is
/// a normal map keeps them, and renders other than the same square without the map, in the
/// default shading and in the normals view.
#[test]
fn a_normal_map_alone_keeps_the_uvs_it_is_read_through() {
    let d = temp_dir("relief-uvs");
    let text = square_gltf([200, 90, 230], 1.0, true).replace(
        r#""materials":[{"normalTexture""#,
        r#""materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.6,0.4,1],"metallicFactor":0},"normalTexture""#,
    );
    let mut mapped = load_file(&d, "n.gltf", &text);
    assert!(mapped.materials[0].albedo_texture.is_none() && mapped.materials[0].relief.is_some());
    let mut plain = mapped.clone();
    plain.materials[0].relief = None;
    for s in [&mut mapped, &mut plain] {
        s.drop_unused_uvs();
        s.camera = Camera::look_at(vec3(0.5, 0.5, 2.0), vec3(0.5, 0.5, 0.0), Vec3::Y, 10.0, 1.0);
    }
    assert!(mapped.mesh.uvs.is_some(), "the normal map's uvs were freed");
    assert!(plain.mesh.uvs.is_none(), "no map reads the uvs of the square without one");
    for shading in [Settings::for_scene(&mapped).paths.shading, Shading::Normals] {
        let image = |s: &Scene| {
            let settings = Settings::for_scene(s).with(|t| {
                (t.image.width, t.image.height, t.sampling.spp) = (32, 32, 4);
                t.paths.shading = shading;
            });
            render(s, &BruteForce::new(s), &settings).unwrap_or_else(|e| panic!("{e:#}")).0.pixels
        };
        let (a, b) = (image(&mapped), image(&plain));
        let diffs: Vec<f32> = a.iter().zip(&b).map(|(p, q)| (*p - *q).abs().max_element()).collect();
        let mean = diffs.iter().sum::<f32>() / diffs.len() as f32;
        // The map tilts the normal 17 degrees away from the sky (about 30% less light) and
        // 38 degrees in all: far beyond the noise of 4 samples, averaged over the image.
        assert!(mean > 0.03, "{shading:?}: the map changes the image by {mean} on average");
        if shading == Shading::Normals {
            // Every pixel sees the square, so every pixel's normal is the map's.
            assert!(diffs.iter().all(|&d| d > 0.1), "{shading:?}: {diffs:?}");
        }
    }
}
