//! Files as exporters write them: OBJ with Latin-1 material names, an empty `usemtl`, several
//! libraries on one `mtllib` line, Windows paths, and line and point elements.

use crate::load::{LoadOptions, load};
use crate::scene::Scene;
use crate::tests::common::temp_dir;
use base64::Engine;
use glam::{Vec3, vec3};
use std::path::Path;

fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) {
    if let Some(parent) = dir.join(name).parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(dir.join(name), contents).unwrap();
}

fn load_ok(path: &Path) -> Scene {
    load(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e:#}"))
}

/// The diffuse albedo of each triangle, in file order.
fn albedos(s: &Scene) -> Vec<Vec3> {
    s.mesh.material_ids.iter().map(|m| s.materials[m as usize].bsdf.diffuse_albedo()).collect()
}

const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

#[test]
fn latin1_material_names_match_their_library() {
    let d = temp_dir("exporters-latin1");
    // "café" and "crème" in Latin-1 (one byte each for é and è), in both files.
    write(&d, "m.mtl", b"newmtl caf\xe9\nKd 0.1 0.2 0.3\nnewmtl cr\xe8me\nKd 0.9 0.8 0.7\n");
    let mut obj = format!("mtllib m.mtl\n{QUAD}").into_bytes();
    obj.extend(b"usemtl caf\xe9\nf 1 2 3\nusemtl cr\xe8me\nf 1 3 4\n");
    write(&d, "a.obj", obj);
    let s = load_ok(&d.join("a.obj"));
    assert_eq!(albedos(&s), [vec3(0.1, 0.2, 0.3), vec3(0.9, 0.8, 0.7)]);
    assert!(
        s.materials.iter().any(|m| m.name == "café"),
        "{:?}",
        s.materials.iter().map(|m| &m.name).collect::<Vec<_>>()
    );
}

#[test]
fn an_empty_usemtl_means_the_default_material() {
    let d = temp_dir("exporters-empty-usemtl");
    write(&d, "m.mtl", "newmtl red\nKd 0.8 0.1 0.1\nnewmtl blue\nKd 0.1 0.1 0.8\n");
    write(&d, "a.obj", format!("mtllib m.mtl\n{QUAD}usemtl red\nf 1 2 3\nusemtl\nf 1 3 4\nusemtl \r\nf 2 3 4\n"));
    let s = load_ok(&d.join("a.obj"));
    assert_eq!(albedos(&s), [vec3(0.8, 0.1, 0.1), Vec3::splat(0.5), Vec3::splat(0.5)]);
}

#[test]
fn one_mtllib_line_can_name_several_libraries_and_windows_paths() {
    let d = temp_dir("exporters-mtllib");
    write(&d, "a.mtl", "newmtl red\nKd 0.8 0.1 0.1\n");
    write(&d, "sub/b.mtl", "newmtl blue\nKd 0.1 0.1 0.8\nmap_Kd .\\tex\\t.png\n");
    write(&d, "a.obj", format!("mtllib a.mtl .\\sub\\b.mtl\n{QUAD}usemtl blue\nf 1 2 3\nusemtl red\nf 1 3 4\n"));
    let s = load_ok(&d.join("a.obj"));
    assert_eq!(albedos(&s), [vec3(0.1, 0.1, 0.8), vec3(0.8, 0.1, 0.1)]);
    let blue = &s.materials[s.mesh.material_ids[0] as usize];
    let tex = blue.albedo_texture.as_ref().expect("the texture is kept");
    assert_eq!(tex.path, d.join("sub").join("./tex/t.png"));
    // A file name with a space still loads when it exists as written.
    write(&d, "with space.mtl", "newmtl green\nKd 0.1 0.8 0.1\n");
    write(&d, "b.obj", format!("mtllib with space.mtl\n{QUAD}usemtl green\nf 1 2 3\n"));
    assert_eq!(albedos(&load_ok(&d.join("b.obj"))), [vec3(0.1, 0.8, 0.1)]);
}

#[test]
fn line_and_point_elements_are_skipped_and_counted() {
    let d = temp_dir("exporters-lines");
    write(&d, "a.obj", format!("{QUAD}f 1 2 3 4\nl 1 2 3\nl 3 4\nl 4 1\np 1\np 2 3\n"));
    let s = load_ok(&d.join("a.obj"));
    assert_eq!(s.mesh.triangles.len(), 2, "the quad only");
    assert!(s.notes.iter().any(|n| n.contains("skipped 3 line and 2 point elements")), "{:?}", s.notes);
    // Only lines: nothing to render, one line saying so.
    write(&d, "lines.obj", format!("{QUAD}l 1 2 3 4 1\n"));
    let e = format!("{:#}", load(&d.join("lines.obj"), &LoadOptions::default()).unwrap_err());
    assert!(e.contains("lines.obj") && e.contains("no faces") && !e.contains('\n'), "{e}");
}

/// A glTF document with one buffer of `bin` (as a data URI) and the given extra JSON members.
fn gltf_doc(version: &str, extra: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"{version}"}},{extra}
          "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}}],
          "bufferViews":[{{"buffer":0,"byteLength":36}}],
          "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}]}}"#
    )
}

#[test]
fn gltf_errors_name_the_real_cause() {
    let d = temp_dir("exporters-gltf");
    let err = |name: &str, text: &str| {
        write(&d, name, text);
        let e = format!("{:#}", load(&d.join(name), &LoadOptions::default()).unwrap_err());
        assert!(e.contains(name) && !e.contains('\n'), "{e}");
        e
    };
    let e = err("old.gltf", r#"{"asset":{"version":"1.0"},"meshes":{"m":{}}}"#);
    assert!(e.contains("glTF version '1.0' is not supported; convert the file to glTF 2.0"), "{e}");
    let e = err(
        "meshopt.gltf",
        &gltf_doc(
            "2.0",
            r#""extensionsUsed":["EXT_meshopt_compression"],"extensionsRequired":["EXT_meshopt_compression"],"meshes":[{"primitives":[{"attributes":{"POSITION":7}}]}],"#,
        ),
    );
    assert!(e.contains("requires EXT_meshopt_compression, which wavepath does not support"), "{e}");
    // A triangle and many line primitives: the lines are skipped with one warning, counted.
    let lines = vec![r#"{"attributes":{"POSITION":0},"mode":1}"#; 40].join(",");
    let mesh = format!(
        r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}},{lines}]}}],"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"#
    );
    write(&d, "lines.gltf", gltf_doc("2.0", &mesh));
    let s = load(&d.join("lines.gltf"), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(s.mesh.triangles.len(), 1);
    assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
    assert!(s.notes[0].contains("40 primitives of mode Lines skipped"), "{:?}", s.notes);
}

/// A 2x1 image, red then blue, encoded as `format`.
fn two_texels(format: image::ImageFormat) -> Vec<u8> {
    let img =
        image::RgbImage::from_fn(2, 1, |x, _| if x == 0 { image::Rgb([255, 0, 0]) } else { image::Rgb([0, 0, 255]) });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, format).unwrap();
    out.into_inner()
}

/// The texels a material's albedo texture decoded to (linear: sRGB 255 is 1).
fn texels(s: &Scene, tri: usize) -> Vec<Vec3> {
    let m = &s.materials[s.mesh.material_ids[tri] as usize];
    m.albedo_texture.as_ref().and_then(|t| t.image.as_ref()).expect("a decoded texture").texels.clone()
}

#[test]
fn obj_textures_in_bmp_and_tga_load_and_an_undecodable_one_is_a_warning() {
    let d = temp_dir("exporters-bmp");
    let want = [vec3(1.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0)];
    for (ext, format) in [("bmp", image::ImageFormat::Bmp), ("tga", image::ImageFormat::Tga)] {
        write(&d, &format!("t.{ext}"), two_texels(format));
        write(&d, "m.mtl", format!("newmtl t\nKd 0.3 0.3 0.3\nmap_Kd t.{ext}\n"));
        write(&d, "a.obj", format!("mtllib m.mtl\n{QUAD}vt 0 0\nusemtl t\nf 1/1 2/1 3/1\n"));
        assert_eq!(texels(&load_ok(&d.join("a.obj")), 0), want, "{ext}");
    }
    write(&d, "bad.png", "not a picture");
    write(&d, "m.mtl", "newmtl t\nKd 0.3 0.3 0.3\nmap_Kd bad.png\n");
    let s = load_ok(&d.join("a.obj"));
    assert!(s.notes.iter().any(|n| n.contains("bad.png") && n.contains("using Kd")), "{:?}", s.notes);
    assert_eq!(albedos(&s), [Vec3::splat(0.3)]);
}

#[test]
fn gltf_images_from_data_uris_and_percent_encoded_names() {
    let d = temp_dir("exporters-gltf-images");
    let png = two_texels(image::ImageFormat::Png);
    write(&d, "Box With Spaces.png", &png);
    let data = format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(&png));
    let want = [vec3(1.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0)];
    for (name, uri) in [("embedded", data.as_str()), ("spaces", "Box%20With%20Spaces.png"), ("ktx2", "missing.ktx2")] {
        let body = format!(
            r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"material":0}}]}}],"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],
               "materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
               "textures":[{{"source":0}}],"images":[{{"uri":"{uri}"}}],"#
        );
        write(&d, &format!("{name}.gltf"), gltf_doc("2.0", &body));
        let s = load_ok(&d.join(format!("{name}.gltf")));
        if name == "ktx2" {
            // An image that cannot be had: the model loads untextured, with a warning.
            assert!(s.notes.iter().any(|n| n.contains("missing.ktx2")), "{:?}", s.notes);
            assert!(s.materials[0].albedo_texture.as_ref().is_none_or(|t| t.image.is_none()));
        } else {
            assert_eq!(texels(&s, 0), want, "{name}");
            assert!(s.notes.is_empty(), "{name}: {:?}", s.notes);
        }
    }
}

/// A glTF document whose one buffer holds `positions` (a data URI), one mesh of primitives
/// `prims` (JSON objects using accessor 0), in the default scene.
fn gltf_positions(positions: &[[f32; 3]], prims: &str) -> String {
    let bytes: Vec<u8> = positions.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    let uri = base64::engine::general_purpose::STANDARD.encode(&bytes);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"meshes":[{{"primitives":[{prims}]}}],"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],
          "buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{uri}"}}],
          "bufferViews":[{{"buffer":0,"byteLength":{len}}}],
          "accessors":[{{"bufferView":0,"componentType":5126,"count":{n},"type":"VEC3","min":[-2,-2,0],"max":[2,2,0]}}]}}"#,
        len = bytes.len(),
        n = positions.len()
    )
}

/// Strips and fans: the triangles the glTF specification defines, all facing +Z (strips
/// alternate their winding to keep it), areas summing to the polygon's.
#[test]
fn gltf_triangle_strips_and_fans() {
    let d = temp_dir("exporters-strips");
    // A zig-zag strip over a 3x1 row of unit squares, and a regular hexagon as a fan.
    let strip: Vec<[f32; 3]> = (0..8).map(|i| [(i / 2) as f32, (1 - i % 2) as f32, 0.0]).collect();
    let hexagon: Vec<[f32; 3]> = (0..6)
        .map(|k| {
            let a = k as f32 * std::f32::consts::PI / 3.0;
            [a.cos(), a.sin(), 0.0]
        })
        .collect();
    for (name, pts, mode, count, area) in [("strip", &strip, 5, 6, 3.0f32), ("fan", &hexagon, 6, 4, 1.5 * 3f32.sqrt())]
    {
        write(
            &d,
            &format!("{name}.gltf"),
            gltf_positions(pts, &format!(r#"{{"attributes":{{"POSITION":0}},"mode":{mode}}}"#)),
        );
        let s = load_ok(&d.join(format!("{name}.gltf")));
        assert_eq!(s.mesh.triangles.len(), count, "{name}");
        let mut total = 0.0;
        for i in 0..count {
            let [a, b, c] = s.mesh.corners(i);
            let n = (b - a).cross(c - a);
            assert!(n.z > 0.0 && n.x.abs() + n.y.abs() < 1e-6, "{name} triangle {i} faces {n}");
            total += 0.5 * n.length();
        }
        assert!((total - area).abs() < 1e-5, "{name}: area {total}");
        assert!(s.notes.is_empty(), "{:?}", s.notes);
    }
}

/// `EXT_mesh_gpu_instancing`: each instance's translation, rotation and scale, then the
/// node's own transform, applied to the mesh.
#[test]
fn gltf_gpu_instancing_places_every_instance() {
    let d = temp_dir("exporters-instancing");
    let tri = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let translations = [[0.0f32, 0.0, 0.0], [5.0, 0.0, 0.0], [0.0, 0.0, -3.0]];
    let s = std::f32::consts::FRAC_1_SQRT_2;
    // Identity; a quarter turn about +Z; a scale of 2.
    let rotations = [[0.0f32, 0.0, 0.0, 1.0], [0.0, 0.0, s, s], [0.0, 0.0, 0.0, 1.0]];
    let scales = [[1.0f32; 3], [1.0; 3], [2.0; 3]];
    let mut bytes = Vec::new();
    for v in tri.iter().chain(&translations) {
        bytes.extend(v.iter().flat_map(|c| c.to_le_bytes()));
    }
    for q in &rotations {
        bytes.extend(q.iter().flat_map(|c| c.to_le_bytes()));
    }
    for v in &scales {
        bytes.extend(v.iter().flat_map(|c| c.to_le_bytes()));
    }
    let uri = base64::engine::general_purpose::STANDARD.encode(&bytes);
    let doc = format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["EXT_mesh_gpu_instancing"],"extensionsRequired":["EXT_mesh_gpu_instancing"],
          "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
          "nodes":[{{"mesh":0,"translation":[0,10,0],"extensions":{{"EXT_mesh_gpu_instancing":{{"attributes":{{"TRANSLATION":1,"ROTATION":2,"SCALE":3}}}}}}}}],
          "scenes":[{{"nodes":[0]}}],
          "buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{uri}"}}],
          "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36}},
                         {{"buffer":0,"byteOffset":72,"byteLength":48}},{{"buffer":0,"byteOffset":120,"byteLength":36}}],
          "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                       {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}},
                       {{"bufferView":2,"componentType":5126,"count":3,"type":"VEC4"}},
                       {{"bufferView":3,"componentType":5126,"count":3,"type":"VEC3"}}]}}"#,
        len = bytes.len()
    );
    write(&d, "inst.gltf", doc);
    let scene = load_ok(&d.join("inst.gltf"));
    assert_eq!(scene.mesh.triangles.len(), 3);
    let want = [
        [vec3(0.0, 10.0, 0.0), vec3(1.0, 10.0, 0.0), vec3(0.0, 11.0, 0.0)],
        [vec3(5.0, 10.0, 0.0), vec3(5.0, 11.0, 0.0), vec3(4.0, 10.0, 0.0)],
        [vec3(0.0, 10.0, -3.0), vec3(2.0, 10.0, -3.0), vec3(0.0, 12.0, -3.0)],
    ];
    for (i, w) in want.iter().enumerate() {
        for (got, want) in scene.mesh.corners(i).iter().zip(w) {
            assert!(got.distance(*want) < 1e-5, "instance {i}: {got} vs {want}");
        }
    }
}

/// A glTF triangle whose buffer `bytes` holds three f32 positions, then three f32 `COLOR_0`s.
fn colour_triangle_gltf(bytes: &[u8]) -> String {
    let uri = base64::engine::general_purpose::STANDARD.encode(bytes);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"COLOR_0":1}}}}]}}],"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],
          "buffers":[{{"byteLength":72,"uri":"data:application/octet-stream;base64,{uri}"}}],
          "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36}}],
          "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                       {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}}]}}"#
    )
}

/// sRGB byte to linear, from the sRGB definition.
fn srgb_byte(b: u8) -> f32 {
    let c = b as f64 / 255.0;
    (if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }) as f32
}

/// Vertex colours from OBJ (`v x y z r g b`, as written), PLY (bytes, sRGB) and glTF
/// (`COLOR_0`, linear floats); a mesh without them has none.
#[test]
fn vertex_colours_are_read_from_every_format() {
    let d = temp_dir("exporters-colours");
    write(&d, "c.obj", "v 0 0 0 1 0.5 0.25\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n");
    let s = load_ok(&d.join("c.obj"));
    assert_eq!(s.mesh.colors.as_deref(), Some(&[vec3(1.0, 0.5, 0.25), vec3(0.0, 1.0, 0.0), vec3(0.0, 0.0, 1.0)][..]));
    write(
        &d,
        "c.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n\
         property list uchar int vertex_indices\nend_header\n0 0 0 255 128 64\n1 0 0 0 10 200\n0 1 0 1 2 3\n3 0 1 2\n",
    );
    let s = load_ok(&d.join("c.ply"));
    let want = [[255, 128, 64], [0, 10, 200], [1, 2, 3]].map(|c: [u8; 3]| Vec3::from(c.map(srgb_byte)));
    let got = s.mesh.colors.clone().expect("PLY colours");
    for (g, w) in got.iter().zip(&want) {
        assert!((*g - *w).abs().max_element() < 1e-6, "{g} vs {w}");
    }
    let mut bytes: Vec<u8> =
        [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    bytes
        .extend([[0.5f32, 0.25, 1.0], [1.0, 1.0, 1.0], [0.0, 0.0, 0.0]].iter().flatten().flat_map(|c| c.to_le_bytes()));
    write(&d, "c.gltf", colour_triangle_gltf(&bytes));
    let s = load_ok(&d.join("c.gltf"));
    assert_eq!(s.mesh.colors.as_deref(), Some(&[vec3(0.5, 0.25, 1.0), Vec3::ONE, Vec3::ZERO][..]));
    write(&d, "plain.obj", format!("{QUAD}f 1 2 3\n"));
    assert!(load_ok(&d.join("plain.obj")).mesh.colors.is_none());
}

/// Vertex colours no render can use leave the mesh loaded, with a warning naming the file,
/// in every format that carries colours: a NaN or infinite colour (trimesh's `nancolor.obj`
/// has a vertex of `nan nan nan`) leaves its vertex uncoloured (white), a negative channel
/// is read as 0, every other vertex keeps its colour. A NaN position is still refused, in
/// one line.
#[test]
fn unusable_vertex_colours_are_dropped_with_a_warning() {
    use crate::load::ply::{BULK_READER, GENERAL_READER};
    let d = temp_dir("exporters-nan-colours");
    let warned = |s: &Scene, file: &str, what: &str| {
        s.notes.iter().any(|n| n.starts_with("warning: ") && n.contains(file) && n.contains(what))
    };

    write(
        &d,
        "nan.obj",
        "v 0 0 0 0.5 0.5 0.5\nv 1 0 0 nan nan nan\nv 1 1 0 0.2 0.4 0.6\nv 0 1 0 -0.25 0.5 1\nf 1 2 3 4\n",
    );
    let s = load_ok(&d.join("nan.obj"));
    assert_eq!(s.mesh.triangles.len(), 2);
    let want = [Vec3::splat(0.5), Vec3::ONE, vec3(0.2, 0.4, 0.6), vec3(0.0, 0.5, 1.0)];
    assert_eq!(s.mesh.colors.as_deref(), Some(&want[..]));
    assert!(warned(&s, "nan.obj", "1 of 4 vertex colours are NaN or infinite"), "{:?}", s.notes);
    assert!(warned(&s, "nan.obj", "1 of 4 vertex colours have a negative channel"), "{:?}", s.notes);

    // PLY, binary floats: triangles go to the bulk reader, a quad to the general one.
    let colours = [[0.5f32, 0.25, 1.0], [0.1, f32::NAN, 0.3], [0.0, 0.0, f32::INFINITY], [0.2, 0.2, 0.2]];
    let corners = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    for (name, faces, reader) in [
        ("tris.ply", &[&[0, 1, 2][..], &[0, 2, 3][..]][..], BULK_READER),
        ("quad.ply", &[&[0, 1, 2, 3][..]][..], GENERAL_READER),
    ] {
        let mut ply = format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nproperty float red\nproperty float green\nproperty float blue\nelement face {}\n\
             property list uchar int vertex_indices\nend_header\n",
            faces.len()
        )
        .into_bytes();
        for (p, c) in corners.iter().zip(&colours) {
            ply.extend(p.iter().chain(c).flat_map(|x| x.to_le_bytes()));
        }
        for f in faces {
            ply.push(f.len() as u8);
            ply.extend(f.iter().flat_map(|&i: &i32| i.to_le_bytes()));
        }
        write(&d, name, ply);
        let s = load_ok(&d.join(name));
        assert_eq!(s.source.reader, reader, "{name}");
        assert_eq!(s.mesh.triangles.len(), 2, "{name}");
        let want = [vec3(0.5, 0.25, 1.0), Vec3::ONE, Vec3::ONE, Vec3::splat(0.2)];
        assert_eq!(s.mesh.colors.as_deref(), Some(&want[..]), "{name}");
        assert!(warned(&s, name, "2 of 4 vertex colours are NaN or infinite"), "{name}: {:?}", s.notes);
    }

    // glTF: COLOR_0 as f32.
    let mut bytes: Vec<u8> = corners[..3].iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    bytes.extend(
        [[0.5f32, 0.25, 1.0], [f32::NAN, 1.0, 1.0], [0.0, 1.0, 0.0]].iter().flatten().flat_map(|c| c.to_le_bytes()),
    );
    write(&d, "nan.gltf", colour_triangle_gltf(&bytes));
    let s = load_ok(&d.join("nan.gltf"));
    assert_eq!(s.mesh.triangles.len(), 1);
    assert_eq!(s.mesh.colors.as_deref(), Some(&[vec3(0.5, 0.25, 1.0), Vec3::ONE, Vec3::Y][..]));
    assert!(warned(&s, "nan.gltf", "1 of 3 vertex colours are NaN or infinite"), "{:?}", s.notes);

    // A NaN position, coloured or not, is still an error of one line naming the file.
    write(&d, "nanpos.obj", "v 0 0 0 1 1 1\nv nan 0 0 1 1 1\nv 0 1 0 1 1 1\nf 1 2 3\n");
    let e = format!("{:#}", load(&d.join("nanpos.obj"), &LoadOptions::default()).expect_err("a NaN position"));
    assert!(e.contains("nanpos.obj") && e.contains("NaN") && !e.contains('\n'), "{e}");
}

/// A vertex colour multiplies the base colour: a plane of albedo 0.8 coloured (1, 0.5, 0.25)
/// at every vertex under the hemisphere light of radiance 1.5 has radiance 0.8 x colour x 1.5
/// (the irradiance pi L times albedo / pi).
#[test]
fn vertex_colours_multiply_the_base_colour_in_a_render() {
    let d = temp_dir("exporters-colour-render");
    let h = 10.0;
    write(
        &d,
        "plane.obj",
        format!(
            "mtllib m.mtl\nv {h} 0 {h} 1 0.5 0.25\nv {h} 0 -{h} 1 0.5 0.25\nv -{h} 0 -{h} 1 0.5 0.25\nv -{h} 0 {h} 1 0.5 0.25\nusemtl grey\nf 1 2 3 4\n"
        ),
    );
    write(&d, "m.mtl", "newmtl grey\nKd 0.8 0.8 0.8\n");
    let mut scene = load_ok(&d.join("plane.obj"));
    scene.lights = vec![crate::scene::Light::Hemisphere { radiance: Vec3::splat(1.5) }];
    scene.camera = crate::scene::Camera::look_at(vec3(0.0, 3.0, 0.5), Vec3::ZERO, Vec3::Y, 40.0, 4.0 / 3.0);
    let acc = crate::tests::common::render::wavefront(&scene, &crate::tests::common::render::settings(32, 24, 1, 16)).0;
    let want = (vec3(1.0, 0.5, 0.25) * 0.8 * 1.5).as_dvec3();
    let (_, checked) =
        crate::tests::common::agree::assert_regions_match(&acc, 8, |_, _| Some(want), 1e-4, "coloured plane");
    assert_eq!(checked, 32 * 24);
}

/// `KHR_mesh_quantization`: normalised i16 positions (scaled back by the node, as encoders
/// write them), i8 normals and u16 uvs, each decoded as the glTF specification defines.
#[test]
fn gltf_quantised_attributes() {
    let d = temp_dir("exporters-quantised");
    let mut bytes = Vec::new();
    // Positions: (0,0,0), (32767,0,0), (0,-32768,0) as i16 x3, padded to 8 bytes per vertex.
    for p in [[0i16, 0, 0], [32767, 0, 0], [0, -32768, 0]] {
        bytes.extend(p.iter().flat_map(|c| c.to_le_bytes()));
        bytes.extend([0u8, 0]);
    }
    // Normals: (0, 0, 127) as i8 x3, padded to 4 bytes.
    for _ in 0..3 {
        bytes.extend([0u8, 0, 127, 0]);
    }
    // Uvs: (0,0), (65535,0), (0,32768) as u16 x2.
    for t in [[0u16, 0], [65535, 0], [0, 32768]] {
        bytes.extend(t.iter().flat_map(|c| c.to_le_bytes()));
    }
    let uri = base64::engine::general_purpose::STANDARD.encode(&bytes);
    write(
        &d,
        "q.gltf",
        format!(
            r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_mesh_quantization"],"extensionsRequired":["KHR_mesh_quantization"],
              "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2}}}}]}}],
              "nodes":[{{"mesh":0,"scale":[4,4,4]}}],"scenes":[{{"nodes":[0]}}],
              "buffers":[{{"byteLength":48,"uri":"data:application/octet-stream;base64,{uri}"}}],
              "bufferViews":[{{"buffer":0,"byteLength":24,"byteStride":8}},{{"buffer":0,"byteOffset":24,"byteLength":12,"byteStride":4}},
                             {{"buffer":0,"byteOffset":36,"byteLength":12}}],
              "accessors":[{{"bufferView":0,"componentType":5122,"normalized":true,"count":3,"type":"VEC3","min":[0,-32768,0],"max":[32767,0,0]}},
                           {{"bufferView":1,"componentType":5120,"normalized":true,"count":3,"type":"VEC3"}},
                           {{"bufferView":2,"componentType":5123,"normalized":true,"count":3,"type":"VEC2"}}]}}"#
        ),
    );
    let s = load_ok(&d.join("q.gltf"));
    // Normalised i16: 32767 -> 1, -32768 -> max(-32768 / 32767, -1) = -1; then the node's scale 4.
    assert_eq!(s.mesh.corners(0), [Vec3::ZERO, vec3(4.0, 0.0, 0.0), vec3(0.0, -4.0, 0.0)]);
    assert_eq!(s.mesh.normals.as_deref(), Some(&[Vec3::Z; 3][..]));
    let uvs = s.mesh.uvs.clone().expect("uvs");
    assert_eq!(uvs[1], glam::Vec2::new(1.0, 0.0));
    assert!((uvs[2].y - 32768.0 / 65535.0).abs() < 1e-7);
}

/// `emissiveTexture`: decoded (sRGB) with the factor times the strength; under a black factor
/// the texture emits nothing and is not kept.
#[test]
fn gltf_emissive_textures_load_with_factor_and_strength() {
    let d = temp_dir("exporters-emissive");
    let png = two_texels(image::ImageFormat::Png);
    let data = format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(&png));
    for (factor, want) in [("[1,0.5,1]", Some(vec3(3.0, 1.5, 3.0))), ("[0,0,0]", None)] {
        let body = format!(
            r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"material":0}}]}}],"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],
               "extensionsUsed":["KHR_materials_emissive_strength"],
               "materials":[{{"emissiveFactor":{factor},"emissiveTexture":{{"index":0}},
                              "extensions":{{"KHR_materials_emissive_strength":{{"emissiveStrength":3}}}}}}],
               "textures":[{{"source":0}}],"images":[{{"uri":"{data}"}}],"#
        );
        write(&d, "e.gltf", gltf_doc("2.0", &body));
        let s = load_ok(&d.join("e.gltf"));
        let t = s.materials[0].emission_texture.as_ref();
        assert_eq!(t.map(|t| t.factor), want, "factor {factor}");
        if let Some(t) = t {
            assert_eq!(t.image.as_ref().unwrap().texels, [vec3(1.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0)]);
        }
    }
}

/// PLY errors are sentences with the line and its text, not the parser's debug output.
#[test]
fn ply_errors_are_sentences() {
    let d = temp_dir("exporters-ply-errors");
    let head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n\
                element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    for (name, text, want) in [
        (
            "word.ply",
            format!("{head}0 0 0\n1 0 abc\n3 0 1 1\n"),
            "line 11 ('1 0 abc', element 'vertex'): not the values the header declares",
        ),
        (
            "short.ply",
            format!("{head}0 0 0\n1 0 0\n3 0 1\n"),
            "line 12 ('3 0 1', element 'face'): expected 3 list elements, but found only 2",
        ),
        (
            "header.ply",
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty floaty x\nend_header\n".to_string(),
            "header line 4: 'property floaty x' is not a valid header line",
        ),
    ] {
        write(&d, name, text);
        let e = format!("{:#}", load(&d.join(name), &LoadOptions::default()).unwrap_err());
        assert!(e.ends_with(want) && e.contains(name), "{e}");
        assert!(!e.contains("String:") && !e.contains('{') && !e.contains('\n'), "{e}");
    }
}
