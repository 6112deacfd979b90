//! OBJ, PLY and glTF loaders against the shared scenes and small hand-written files.

use crate::load::{LoadOptions, load};
use crate::scene::{Light, Scene};
use crate::tests::common::{self, temp_dir};
use glam::{Vec3, vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

fn load_ok(path: &Path) -> Scene {
    load(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e:#}"))
}

/// Writes `contents` to `dir/name` and returns the path.
fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, contents).unwrap();
    p
}

/// Asserts that loading fails with a one-line message that names the file.
fn assert_load_error(path: &Path, what: &str) -> String {
    let err = match load(path, &LoadOptions::default()) {
        Ok(_) => panic!("{what}: {} loaded, but should fail", path.display()),
        Err(e) => format!("{e:#}"),
    };
    let name = path.file_name().unwrap().to_str().unwrap();
    assert!(err.contains(name), "{what}: error does not name the file: {err}");
    assert!(!err.contains('\n'), "{what}: error is not one line: {err}");
    err
}

/// The README table: path -> triangle count (None when the column is empty).
fn readme_triangles(scenes: &Path) -> HashMap<String, Option<usize>> {
    let text = std::fs::read_to_string(scenes.join("README.md")).unwrap();
    let mut out = HashMap::new();
    for line in text.lines() {
        let cols: Vec<&str> = line.split('|').map(str::trim).collect();
        // "| path | triangles | size | ..." -> ["", path, triangles, size, ...]
        if cols.len() > 3 && cols[1].contains('.') && !cols[1].contains(' ') {
            out.insert(cols[1].to_string(), cols[2].parse().ok());
        }
    }
    out
}

#[test]
fn every_mesh_file_loads_with_the_readme_triangle_count() {
    let Some(dir) = common::scenes_dir() else { return };
    let table = readme_triangles(&dir);
    let files = common::files_with_ext(&dir, &["obj", "ply", "gltf", "glb"]);
    assert!(files.len() >= 30, "only {} mesh files found", files.len());
    for f in files {
        let rel = f.strip_prefix(&dir).unwrap().to_str().unwrap().replace('\\', "/");
        let scene = load_ok(&f);
        let expected = table.get(&rel).unwrap_or_else(|| panic!("{rel} is not in the README table"));
        let expected = expected.unwrap_or_else(|| panic!("{rel} has no triangle count in the README"));
        assert_eq!(scene.mesh.triangles.len(), expected, "{rel}");
        assert!(!scene.materials.is_empty());
    }
}

/// The peers' OBJ rules (peers/README.md "Mesh"): `v` and `f` records only, indices
/// `i`, `i/t`, `i//n`, `i/t/n`, negative = relative, polygons fanned (v0,v1,v2),(v0,v2,v3).
fn reference_obj_triangles(text: &str) -> Vec<[Vec3; 3]> {
    let mut v: Vec<Vec3> = Vec::new();
    let mut out = Vec::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap();
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => {
                let c: Vec<f32> = w.take(3).map(|x| x.parse().unwrap()).collect();
                v.push(vec3(c[0], c[1], c[2]));
            }
            Some("f") => {
                let idx: Vec<usize> = w
                    .map(|t| {
                        let i: i64 = t.split('/').next().unwrap().parse().unwrap();
                        if i < 0 { (v.len() as i64 + i) as usize } else { i as usize - 1 }
                    })
                    .collect();
                for k in 1..idx.len().saturating_sub(1) {
                    out.push([v[idx[0]], v[idx[k]], v[idx[k + 1]]]);
                }
            }
            _ => {}
        }
    }
    out
}

fn assert_same_triangles(scene: &Scene, reference: &[[Vec3; 3]], what: &str) {
    assert_eq!(scene.mesh.triangles.len(), reference.len(), "{what}: triangle count");
    for (i, r) in reference.iter().enumerate() {
        assert_eq!(&scene.mesh.corners(i), r, "{what}: triangle {i}");
    }
}

#[test]
fn obj_triangle_numbering_matches_the_peers_rules_on_real_files() {
    let Some(dir) = common::scenes_dir() else { return };
    for rel in ["meshes/lucy_100k.obj", "obj/CornellBox/CornellBox-Original.obj", "meshes/suzanne.obj"] {
        let path = dir.join(rel);
        let reference = reference_obj_triangles(&std::fs::read_to_string(&path).unwrap());
        assert_same_triangles(&load_ok(&path), &reference, rel);
    }
}

#[test]
fn obj_polygons_groups_and_relative_indices_keep_file_order() {
    let d = temp_dir("mesh-loaders-obj_order");
    write(&d, "m.mtl", "newmtl a\nKd 0.5\nnewmtl b\nKd 0.1 0.2 0.3\nKe 1 2 3\nmap_Kd tex/b.png\n");
    let obj = "mtllib m.mtl\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n\
        o first\nusemtl a\nf 1 2 3 4 5\n\
        g second\nusemtl b\nf -5/1 -4/2 -3/3\n\
        usemtl a\nf 1//1 3//1 4//1\n\
        o third\nf 2 3 4 1\n";
    let path = write(&d, "order.obj", obj);
    let scene = load_ok(&path);
    assert_same_triangles(&scene, &reference_obj_triangles(obj), "order.obj");
    let albedo = |t: usize| scene.materials[scene.mesh.material_ids[t] as usize].bsdf.diffuse_albedo();
    // Pentagon (3 triangles, a), one triangle of b, one of a, a quad (2 triangles, still a).
    let expect_b = [false, false, false, true, false, false, false];
    for (t, &is_b) in expect_b.iter().enumerate() {
        let want = if is_b { vec3(0.1, 0.2, 0.3) } else { Vec3::splat(0.5) };
        assert_eq!(albedo(t), want, "triangle {t}");
    }
    let b = &scene.materials[scene.mesh.material_ids[3] as usize];
    assert_eq!(b.emission, vec3(1.0, 2.0, 3.0));
    // An MTL emitter lights the side its faces' winding points to, as MTL readers render it.
    assert!(!b.two_sided_emission);
    assert_eq!(b.albedo_texture.as_ref().unwrap().path, d.join("tex/b.png"));
    // Only some corners have normals: geometric normals are used.
    assert!(scene.mesh.normals.is_none());
}

/// One vertex per distinct corner the faces use (the file has one object and plain `v`
/// indices), triangles in file order with the file's coordinates.
#[test]
fn obj_shares_positions_of_a_big_mesh() {
    let Some(path) = common::scene("meshes/lucy_100k.obj") else { return };
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(!text.lines().any(|l| l.starts_with("o ") || l.starts_with("g ")), "one object");
    let file_positions: Vec<Vec3> = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let c: Vec<f32> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            vec3(c[0], c[1], c[2])
        })
        .collect();
    let faces: Vec<Vec<usize>> = text
        .lines()
        .filter_map(|l| l.strip_prefix("f "))
        .map(|l| l.split_whitespace().map(|c| c.split('/').next().unwrap().parse::<usize>().unwrap() - 1).collect())
        .collect();
    assert!(faces.iter().all(|f| f.len() == 3), "triangles only");
    let used: std::collections::HashSet<usize> = faces.iter().flatten().copied().collect();
    let scene = load_ok(&path);
    assert_eq!(scene.mesh.positions.len(), used.len(), "one vertex per distinct corner");
    assert_eq!(scene.mesh.triangles.len(), faces.len());
    for (i, f) in faces.iter().enumerate() {
        let want = [file_positions[f[0]], file_positions[f[1]], file_positions[f[2]]];
        assert_eq!(scene.mesh.corners(i), want, "triangle {i}");
    }
    assert!(scene.mesh.normals.is_none(), "no vn lines: no normals");
}

#[test]
fn obj_without_its_mtl_loads_with_the_default_material() {
    let d = temp_dir("mesh-loaders-obj_no_mtl");
    let path = write(&d, "nomtl.obj", "mtllib missing.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let scene = load_ok(&path);
    assert_eq!(scene.materials.len(), 1);
    assert_eq!(scene.materials[0], crate::scene::Material::default());
    // No emitter and no light: the hemisphere light is added, and a framing camera.
    assert!(matches!(scene.lights[..], [Light::Hemisphere { .. }]));
}

/// Reads a binary little-endian PLY with float x y z vertices and uchar/int face lists.
fn read_simple_binary_ply(bytes: &[u8]) -> (Vec<[f32; 3]>, Vec<Vec<i32>>) {
    let end = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let header = std::str::from_utf8(&bytes[..end]).unwrap();
    let count = |name: &str| -> usize {
        let l = header.lines().find(|l| l.starts_with(&format!("element {name} "))).unwrap();
        l.split_whitespace().nth(2).unwrap().parse().unwrap()
    };
    assert!(header.contains("property list uchar int vertex_indices"));
    assert_eq!(header.matches("property float").count(), 3, "x y z only");
    let (nv, nf) = (count("vertex"), count("face"));
    let f32_at = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
    let verts = (0..nv).map(|i| [0, 1, 2].map(|k| f32_at(end + 12 * i + 4 * k))).collect();
    let mut faces = Vec::with_capacity(nf);
    let mut o = end + 12 * nv;
    for _ in 0..nf {
        let n = bytes[o] as usize;
        faces.push(
            (0..n).map(|k| i32::from_le_bytes(bytes[o + 1 + 4 * k..o + 5 + 4 * k].try_into().unwrap())).collect(),
        );
        o += 1 + 4 * n;
    }
    assert_eq!(o, bytes.len());
    (verts, faces)
}

fn ply_header(format: &str, nv: usize, nf: usize) -> String {
    format!(
        "ply\nformat {format} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
    )
}

#[test]
fn ply_ascii_and_both_binary_byte_orders_give_the_same_mesh() {
    let Some(src) = common::scene("meshes/kitten_25k.ply") else { return };
    let (verts, faces) = read_simple_binary_ply(&std::fs::read(&src).unwrap());
    let d = temp_dir("mesh-loaders-ply_formats");
    let mut ascii = ply_header("ascii", verts.len(), faces.len());
    let mut be = ply_header("binary_big_endian", verts.len(), faces.len()).into_bytes();
    for v in &verts {
        // `{:?}` prints the shortest text that reads back as the same f32.
        ascii += &format!("{:?} {:?} {:?}\n", v[0], v[1], v[2]);
        v.iter().for_each(|c| be.extend(c.to_be_bytes()));
    }
    for f in &faces {
        ascii += &format!("{} {}\n", f.len(), f.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(" "));
        be.push(f.len() as u8);
        f.iter().for_each(|i| be.extend(i.to_be_bytes()));
    }
    let le = load_ok(&src);
    let a = load_ok(&write(&d, "kitten_ascii.ply", ascii));
    let b = load_ok(&write(&d, "kitten_be.ply", be));
    assert_eq!(le.mesh, a.mesh);
    assert_eq!(le.mesh, b.mesh);
    // And the mesh is the file's: positions and fan-triangulated faces in order.
    let expect: Vec<[u32; 3]> =
        faces.iter().flat_map(|f| (1..f.len() - 1).map(move |k| [f[0] as u32, f[k] as u32, f[k + 1] as u32])).collect();
    assert_eq!(le.mesh.triangles, expect);
    assert_eq!(le.mesh.positions, verts.iter().map(|&p| Vec3::from(p)).collect::<Vec<_>>());
}

#[test]
fn ply_polygons_normals_uvs_and_doubles() {
    let d = temp_dir("mesh-loaders-ply_attrs");
    let text = "ply\nformat ascii 1.0\ncomment quad and triangle\nelement vertex 5\nproperty double x\nproperty double y\n\
        property double z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float s\nproperty float t\n\
        element face 2\nproperty list uchar uint vertex_index\nelement extra 1\nproperty int whatever\nend_header\n\
        0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n2 2 0 0 0 1 0.5 0.5\n4 0 1 2 3\n3 1 4 2\n7\n";
    let s = load_ok(&write(&d, "attrs.ply", text));
    assert_eq!(s.mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
    assert_eq!(s.mesh.normals.as_ref().unwrap()[4], Vec3::Z);
    assert_eq!(s.mesh.uvs.as_ref().unwrap()[2], glam::vec2(1.0, 1.0));
    assert_eq!(s.mesh.positions[4], vec3(2.0, 2.0, 0.0));
}

/// A one-triangle glTF; `nodes` and `extra` are spliced in. The buffer holds the three
/// positions and then `indices` as u16 (when given), as a data URI unless `uri` names a file.
fn gltf_with(nodes: &str, extra: &str, indices: Option<&[u16]>, uri: Option<&str>) -> String {
    let mut bin = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        v.iter().for_each(|c| bin.extend(c.to_le_bytes()));
    }
    let (idx_attr, idx_accessor, idx_view) = match indices {
        Some(ix) => {
            ix.iter().for_each(|i| bin.extend(i.to_le_bytes()));
            (
                r#","indices":1"#.to_string(),
                format!(r#",{{"bufferView":1,"componentType":5123,"count":{},"type":"SCALAR"}}"#, ix.len()),
                format!(r#",{{"buffer":0,"byteOffset":36,"byteLength":{}}}"#, 2 * ix.len()),
            )
        }
        None => Default::default(),
    };
    let uri = uri.map_or_else(|| format!("data:application/octet-stream;base64,{}", base64(&bin)), str::to_string);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{nodes}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}{idx_attr}}}]}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}{idx_accessor}],
        "bufferViews":[{{"buffer":0,"byteLength":36}}{idx_view}],
        "buffers":[{{"byteLength":{},"uri":"{uri}"}}]{extra}}}"#,
        bin.len()
    )
}

fn tiny_gltf(nodes: &str, extra: &str) -> String {
    gltf_with(nodes, extra, None, None)
}

fn base64(data: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            s.push(if k <= c.len() { A[(n >> (18 - 6 * k)) as usize & 63] as char } else { '=' });
        }
    }
    s
}

#[test]
fn gltf_node_transforms_are_flattened_to_world_space() {
    let d = temp_dir("mesh-loaders-gltf_nodes");
    // Root: translate (1,2,3), scale 2. Child: rotate 90 degrees about +Z, holds the mesh.
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let nodes =
        format!(r#"{{"translation":[1,2,3],"scale":[2,2,2],"children":[1]}},{{"rotation":[0,0,{h},{h}],"mesh":0}}"#);
    let s = load_ok(&write(&d, "nodes.gltf", tiny_gltf(&nodes, "")));
    // Rz(90): (1,0,0)->(0,1,0), (0,1,0)->(-1,0,0); then x2, then +(1,2,3).
    let want = [vec3(1.0, 2.0, 3.0), vec3(1.0, 4.0, 3.0), vec3(-1.0, 2.0, 3.0)];
    for (got, want) in s.mesh.corners(0).iter().zip(want) {
        assert!(got.distance(want) < 1e-5, "{got} vs {want}");
    }
    // No camera, no emitter: framing camera and hemisphere light.
    assert!(matches!(s.lights[..], [Light::Hemisphere { .. }]));
}

#[test]
fn gltf_indexed_primitive_follows_its_indices() {
    let d = temp_dir("mesh-loaders-gltf_indexed");
    let s = load_ok(&write(&d, "ix.gltf", gltf_with(r#"{"mesh":0}"#, "", Some(&[2, 0, 1]), None)));
    assert_eq!(s.mesh.corners(0), [vec3(0.0, 1.0, 0.0), Vec3::ZERO, Vec3::X]);
}

#[test]
fn gltf_camera_and_punctual_lights() {
    let d = temp_dir("mesh-loaders-gltf_lights");
    let h = std::f32::consts::FRAC_1_SQRT_2;
    // Root holds the mesh and four children: camera turned 90 degrees about +Y (looks down -X),
    // a point light, a directional light pointing down (-Z turned to -Y) and a spot light.
    let nodes = format!(
        r#"{{"mesh":0,"children":[1,2,3,4]}},
        {{"camera":0,"translation":[5,0,0],"rotation":[0,{h},0,{h}]}},
        {{"translation":[0,3,0],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}},
        {{"rotation":[{nh},0,0,{h}],"extensions":{{"KHR_lights_punctual":{{"light":1}}}}}},
        {{"translation":[1,1,1],"extensions":{{"KHR_lights_punctual":{{"light":2}}}}}}"#,
        nh = -h
    );
    let extra = r#","cameras":[{"type":"perspective","perspective":{"yfov":0.5,"znear":0.05,"zfar":50,"aspectRatio":2.0}}],
        "extensionsUsed":["KHR_lights_punctual"],
        "extensions":{"KHR_lights_punctual":{"lights":[
          {"type":"point","color":[1,0.5,0.25],"intensity":8},
          {"type":"directional","intensity":2},
          {"type":"spot","intensity":3,"spot":{"outerConeAngle":0.5}}]}}"#;
    let s = load_ok(&write(&d, "lights.gltf", tiny_gltf(&nodes, extra)));
    let c = s.camera;
    assert!(c.position.distance(vec3(5.0, 0.0, 0.0)) < 1e-6);
    assert!((c.c2w * -Vec3::Z).distance(-Vec3::X) < 1e-6, "camera looks down -X");
    assert!((c.c2w * Vec3::Y).distance(Vec3::Y) < 1e-6);
    assert!((c.vfov_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    assert!((c.nclip - 0.05).abs() < 1e-7 && (c.fclip - 50.0).abs() < 1e-5);
    let expected_h = 2.0 * ((0.25f32).tan() * 2.0).atan().to_degrees();
    assert!((c.hfov_deg - expected_h).abs() < 1e-3);
    assert_eq!(s.lights.len(), 3, "{:?}", s.lights);
    match s.lights[0] {
        Light::Point { position, intensity, .. } => {
            assert_eq!(position, vec3(0.0, 3.0, 0.0));
            assert_eq!(intensity, vec3(8.0, 4.0, 2.0));
        }
        ref l => panic!("{l:?}"),
    }
    match s.lights[1] {
        Light::Directional { direction, radiance } => {
            assert!(direction.distance(-Vec3::Y) < 1e-6, "{direction}");
            assert_eq!(radiance, Vec3::splat(2.0));
        }
        ref l => panic!("{l:?}"),
    }
    match s.lights[2] {
        Light::Spot { position, direction, intensity, cone_angle, .. } => {
            assert_eq!((position, direction, intensity), (Vec3::ONE, -Vec3::Z, Vec3::splat(3.0)));
            assert!((cone_angle - 1.0f32.to_degrees()).abs() < 1e-4, "full cone angle in degrees");
        }
        ref l => panic!("{l:?}"),
    }
}

#[test]
fn gltf_emissive_strength_multiplies_the_emissive_factor() {
    let Some(path) = common::scene("gltf/CornellBox-Original/CornellBox-Original.gltf") else { return };
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let s = load_ok(&path);
    let mut checked = 0;
    for (i, m) in json["materials"].as_array().unwrap().iter().enumerate() {
        let factor = m["emissiveFactor"]
            .as_array()
            .map_or(Vec3::ZERO, |f| Vec3::from_array([0, 1, 2].map(|k| f[k].as_f64().unwrap() as f32)));
        let strength = m["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"].as_f64();
        if strength.is_some() {
            checked += 1;
        }
        let want = factor * strength.unwrap_or(1.0) as f32;
        assert!(s.materials[i].emission.distance(want) < 1e-5, "material {i}: {} vs {want}", s.materials[i].emission);
        let base = &m["pbrMetallicRoughness"]["baseColorFactor"];
        let albedo = Vec3::from_array([0, 1, 2].map(|k| base[k].as_f64().unwrap_or(1.0) as f32));
        assert!(s.materials[i].bsdf.diffuse_albedo().distance(albedo) < 1e-6);
    }
    assert!(checked > 0, "the file has a material with emissive strength");
    assert!(s.materials.iter().any(|m| m.emission.max_element() > 1.0), "strength > 1 applied");
    assert!(s.lights.is_empty(), "an emitter: no hemisphere light added");
}

#[test]
fn gltf_external_texture_is_recorded_and_embedded_is_decoded() {
    let d = temp_dir("mesh-loaders-gltf_tex");
    let extra = r#","materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
        "textures":[{"source":0}],"images":[{"uri":"albedo.png"}]"#;
    let text = tiny_gltf(r#"{"mesh":0}"#, extra).replace(r#""attributes""#, r#""material":0,"attributes""#);
    let s = load_ok(&write(&d, "tex.gltf", text));
    let t = s.materials[0].albedo_texture.as_ref().unwrap();
    // The file is missing: recorded (with a warning), nothing decoded.
    assert_eq!((&t.path, t.image.is_none()), (&d.join("albedo.png"), true));
    let glb = common::scene("gltf/BoxTextured.glb").expect("WAVEPATH_SCENES must point at the scenes");
    let textured: Vec<_> = load_ok(&glb).materials.into_iter().filter_map(|m| m.albedo_texture).collect();
    assert_eq!(textured.len(), 1);
    // The embedded PNG (256x256 Cesium logo) is decoded from its buffer view.
    let img = textured[0].image.as_ref().expect("embedded image decoded");
    assert_eq!((img.width, img.height), (256, 256));
}

// ------------------------------------------------------------------ bad input

#[test]
fn bad_missing_files() {
    let d = temp_dir("mesh-loaders-missing");
    for name in ["nothing.obj", "nothing.ply", "nothing.gltf", "nothing.glb"] {
        assert_load_error(&d.join(name), "missing file");
    }
}

#[test]
fn bad_gltf_missing_bin() {
    let d = temp_dir("mesh-loaders-missing_bin");
    let text = gltf_with(r#"{"mesh":0}"#, "", None, Some("gone.bin"));
    assert_load_error(&write(&d, "nobin.gltf", text), "missing .bin");
}

#[test]
fn bad_truncated_files() {
    let d = temp_dir("mesh-loaders-truncated");
    if let Some(ply) = common::scene("meshes/kitten_25k.ply") {
        let bytes = std::fs::read(ply).unwrap();
        assert_load_error(&write(&d, "half.ply", &bytes[..bytes.len() / 2]), "truncated binary ply");
        assert_load_error(&write(&d, "header_only.ply", &bytes[..200]), "truncated header");
    }
    let ascii = format!("{}0 0 0\n1 0 0\n", ply_header("ascii", 3, 1));
    assert_load_error(&write(&d, "short.ply", ascii), "truncated ascii ply");
    if let Some(glb) = common::scene("gltf/dragon_100k.glb") {
        let bytes = std::fs::read(glb).unwrap();
        assert_load_error(&write(&d, "half.glb", &bytes[..bytes.len() / 2]), "truncated glb");
        assert_load_error(&write(&d, "tiny.glb", &bytes[..10]), "glb header cut");
    }
    // A .bin shorter than the buffer the .gltf declares.
    write(&d, "short.bin", [0u8; 20]);
    let text = gltf_with(r#"{"mesh":0}"#, "", None, Some("short.bin"));
    assert_load_error(&write(&d, "shortbin.gltf", text), "short .bin");
}

#[test]
fn bad_non_numeric_and_non_finite_coordinates() {
    let d = temp_dir("mesh-loaders-nan");
    let e = assert_load_error(&write(&d, "word.obj", "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n"), "word in obj");
    assert!(e.contains("line 2"), "{e}");
    for (name, v) in [("nan.obj", "nan"), ("inf.obj", "inf"), ("bigexp.obj", "1e999")] {
        assert_load_error(&write(&d, name, format!("v 0 0 0\nv 1 {v} 0\nv 0 1 0\nf 1 2 3\n")), name);
    }
    let ply = format!("{}0 0 0\n1 NaN 0\n0 1 0\n3 0 1 2\n", ply_header("ascii", 3, 1));
    assert_load_error(&write(&d, "nan.ply", ply), "nan in ply");
    let ply = format!("{}0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", ply_header("ascii", 3, 1));
    assert_load_error(&write(&d, "word.ply", ply), "word in ply");
}

#[test]
fn bad_mtl_values() {
    let d = temp_dir("mesh-loaders-bad_mtl");
    write(&d, "bad.mtl", "newmtl a\nKd 0.5 green 0.5\n");
    let e = assert_load_error(&write(&d, "badmtl.obj", "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "mtl");
    assert!(e.contains("bad.mtl") && e.contains("line 2"), "{e}");
}

#[test]
fn bad_indices_out_of_range() {
    let d = temp_dir("mesh-loaders-indices");
    assert_load_error(&write(&d, "far.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"), "obj index");
    assert_load_error(&write(&d, "neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9\n"), "obj negative");
    assert_load_error(&write(&d, "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"), "obj zero");
    assert_load_error(
        &write(&d, "huge.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-99999999999 2/1 3/1\n"),
        "obj huge uv",
    );
    let ply = format!("{}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", ply_header("ascii", 3, 1));
    assert_load_error(&write(&d, "far.ply", ply), "ply index");
    let ply = format!("{}0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n", ply_header("ascii", 3, 1));
    assert_load_error(&write(&d, "neg.ply", ply), "ply negative");
    let text = gltf_with(r#"{"mesh":0}"#, "", Some(&[0, 1, 5]), None);
    let e = assert_load_error(&write(&d, "far.gltf", text), "gltf index");
    assert!(e.contains("index 5"), "{e}");
}

#[test]
fn bad_empty_meshes() {
    let d = temp_dir("mesh-loaders-empty");
    assert_load_error(&write(&d, "empty.obj", ""), "empty obj");
    assert_load_error(&write(&d, "points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n"), "no faces");
    assert_load_error(&write(&d, "empty.ply", ply_header("ascii", 0, 0)), "empty ply");
    assert_load_error(&write(&d, "noply.ply", "solid stl\n"), "not a ply");
    let no_mesh = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{}]}"#;
    assert_load_error(&write(&d, "empty.gltf", no_mesh), "empty gltf");
    assert_load_error(&write(&d, "garbage.gltf", "{not json"), "bad json");
}

#[test]
fn bad_counts_larger_than_the_data() {
    let d = temp_dir("mesh-loaders-counts");
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let text = format!("{}0 0 0\n", ply_header(format, 4_000_000_000, 1));
        let e = assert_load_error(&write(&d, &format!("huge_{format}.ply"), text), format);
        assert!(e.contains("4000000000"), "{e}");
    }
    let text = format!("{}0 0 0\n", ply_header("ascii", 1, 99_999_999_999_999_999));
    assert_load_error(&write(&d, "hugefaces.ply", text), "huge face count");
    let text = "ply\nformat ascii 1.0\nelement vertex 123456789012345678901234567890\nproperty float x\nend_header\n";
    assert_load_error(&write(&d, "overflow.ply", text), "count overflows u64");
}
