//! COLLADA loader: the CS184 scenes (counts against the shared README, lights, materials,
//! cameras, normals) and hand-written documents for transforms, primitives and bad input.

use crate::load::collada::parse_str;
use crate::load::{CameraMode, LoadOptions, load};
use crate::scene::{Bsdf, Light, Scene};
use crate::tests::common;
use glam::{Vec3, vec3};
use std::path::Path;

fn file_mode() -> LoadOptions {
    LoadOptions { camera: CameraMode::File, ..LoadOptions::default() }
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

// ---------------------------------------------------------------------------------------
// The shared CS184 scenes
// ---------------------------------------------------------------------------------------

#[test]
fn every_cs184_file_loads_in_every_mode() {
    let Some(dir) = common::scene("cs184") else { return };
    let files = common::files_with_ext(&dir, &["dae"]);
    assert!(files.len() >= 40, "expected the CS184 scenes in {}", dir.display());
    for f in &files {
        for opts in [
            LoadOptions::default(),
            LoadOptions { camera: CameraMode::File, smooth_normals: false, ..LoadOptions::default() },
        ] {
            let s = load(f, &opts).unwrap_or_else(|e| panic!("{e}"));
            assert!(s.primitive_count() > 0, "{}", f.display());
            s.validate().unwrap();
        }
    }
}

/// Per README row: (path, triangles, spheres noted as "N sphere(s)").
fn readme_dae_rows(scenes: &Path) -> Vec<(String, usize, usize)> {
    let text = std::fs::read_to_string(scenes.join("README.md")).unwrap();
    let mut rows = Vec::new();
    for line in text.lines().filter(|l| l.starts_with("| cs184/")) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if !cells[1].ends_with(".dae") {
            continue;
        }
        let tris = cells[2].parse().unwrap_or_else(|_| panic!("triangle cell in {line}"));
        let notes = cells[cells.len() - 2];
        let spheres = notes
            .split(" sphere(s)")
            .next()
            .filter(|_| notes.contains(" sphere(s)"))
            .map(|s| s.rsplit(' ').next().unwrap().parse().unwrap())
            .unwrap_or(0);
        rows.push((cells[1].to_owned(), tris, spheres));
    }
    rows
}

/// Sphere geometries defined, and node instances of them, read from the file directly.
fn sphere_geometries_and_instances(text: &str) -> (usize, usize) {
    let doc = roxmltree::Document::parse(text).unwrap();
    let is_sphere = |g: roxmltree::Node| {
        g.descendants().any(|n| n.has_tag_name("sphere")) && !g.children().any(|c| c.has_tag_name("mesh"))
    };
    let spheres: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("geometry") && is_sphere(*n))
        .map(|n| n.attribute("id").unwrap())
        .collect();
    let instances = doc
        .descendants()
        .filter(|n| n.has_tag_name("instance_geometry"))
        .filter(|n| spheres.contains(&n.attribute("url").unwrap().trim_start_matches('#')))
        .count();
    (spheres.len(), instances)
}

#[test]
fn counts_match_the_readme_table() {
    let Some(dir) = common::scenes_dir() else { return };
    let rows = readme_dae_rows(&dir);
    let on_disk = common::files_with_ext(&dir.join("cs184"), &["dae"]);
    assert_eq!(rows.len(), on_disk.len(), "every .dae on disk has a README row");
    for (rel, tris, spheres) in rows {
        let path = dir.join(&rel);
        let s = load(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.mesh.triangles.len(), tris, "{rel}: triangles");
        // The README notes count sphere geometries; a geometry may be instanced several times.
        let (defined, instanced) = sphere_geometries_and_instances(&std::fs::read_to_string(&path).unwrap());
        assert_eq!(defined, spheres, "{rel}: README sphere note");
        assert_eq!(s.spheres.len(), instanced, "{rel}: sphere instances");
    }
}

#[test]
fn meshedit_counts() {
    let (Some(beetle), Some(planck)) =
        (common::load_scene("cs184/meshedit/beetle.dae"), common::load_scene("cs184/meshedit/maxplanck.dae"))
    else {
        return;
    };
    assert_eq!(beetle.mesh.triangles.len(), 7558);
    assert_eq!(planck.mesh.triangles.len(), 50801);
}

#[test]
fn cbspheres_lambertian_geometry_light_and_cameras() {
    let Some(s) = common::load_scene("cs184/sky/CBspheres_lambertian.dae") else { return };
    // Sphere1 matrix translation (-0.4, 0.3, 0.3), Sphere2 (0.4, -0.3, 0.3), both in Z-up.
    // x' = -x, y' = z, z' = y gives (0.4, 0.3, 0.3) and (-0.4, 0.3, -0.3); scale 1, radius .3.
    assert_eq!(s.spheres.len(), 2);
    assert!(close(s.spheres[0].center, vec3(0.4, 0.3, 0.3), 1e-6), "{:?}", s.spheres[0]);
    assert!(close(s.spheres[1].center, vec3(-0.4, 0.3, -0.3), 1e-6), "{:?}", s.spheres[1]);
    for sp in &s.spheres {
        assert!((sp.radius - 0.3).abs() < 1e-6);
    }
    // Area node: diag(0.6, 0.8, 1) and translation z = 1.49 (Z-up) -> y = 1.49, facing -Y.
    assert_eq!(s.lights.len(), 1);
    let Light::Area { position, direction, dim_x, dim_y, radiance } = s.lights[0] else {
        panic!("expected an area light, got {:?}", s.lights[0]);
    };
    assert!(close(radiance, Vec3::splat(10.0), 0.0));
    assert!(close(position, vec3(0.0, 1.49, 0.0), 1e-6), "{position}");
    assert!(close(direction, vec3(0.0, -1.0, 0.0), 1e-6), "{direction}");
    let mut dims = [dim_x.length(), dim_y.length()];
    dims.sort_by(f32::total_cmp);
    assert!((dims[0] - 0.6).abs() < 1e-6 && (dims[1] - 0.8).abs() < 1e-6, "{dims:?}");
    assert!(dim_x.dot(direction).abs() < 1e-6 && dim_y.dot(direction).abs() < 1e-6);

    // CS184 placement: camera node at (0, 3, 0) Z-up looking along -Y, so the quirk point
    // M (0,0,-1,1) = (0, 2, 0) -> (0, 0, 2) Y-up: the camera sits on +Z of the box centre.
    let (lo, hi) = s.bounds().unwrap();
    let c = 0.5 * (lo + hi);
    let cam = s.camera;
    let expect = c + Vec3::Z * 1.5 * (hi - lo).length();
    assert!(close(cam.position, expect, 1e-4), "{} vs {expect}", cam.position);
    let view = -cam.c2w.z_axis;
    assert!(close(view, (c - cam.position).normalize(), 1e-5));
    assert!(cam.c2w.y_axis.y > 0.99, "up stays +Y");
    assert!((cam.hfov_deg - 49.13434).abs() < 1e-4);
    let vfov = 2.0 * ((49.13434f32.to_radians() / 2.0).tan() / 1.333333).atan().to_degrees();
    assert!((cam.vfov_deg - vfov).abs() < 1e-3);
    assert_eq!((cam.nclip, cam.fclip), (0.1, 100.0));

    // File mode: the node's own placement, converted: (0, 3, 0) Z-up -> (0, 0, 3), looking -Z.
    let f = load(&common::scene("cs184/sky/CBspheres_lambertian.dae").unwrap(), &file_mode()).unwrap();
    assert!(close(f.camera.position, vec3(0.0, 0.0, 3.0), 1e-6), "{}", f.camera.position);
    assert!(close(-f.camera.c2w.z_axis, vec3(0.0, 0.0, -1.0), 1e-6));
    assert!(close(f.camera.c2w.y_axis, Vec3::Y, 1e-6));
}

#[test]
fn lights_of_cbempty_and_bunny() {
    let (Some(empty), Some(bunny)) =
        (common::load_scene("cs184/sky/CBempty.dae"), common::load_scene("cs184/sky/bunny.dae"))
    else {
        return;
    };
    assert!(matches!(empty.lights.as_slice(), [Light::Point { intensity, .. }] if *intensity == Vec3::splat(5.0)));
    assert!(bunny.lights.iter().any(|l| matches!(l, Light::Hemisphere { radiance } if *radiance == Vec3::ONE)));
}

#[test]
fn legacy_cmu462_sphere_is_a_mirror() {
    let Some(s) = common::load_scene("cs184/basic/sphere_mirror.dae") else { return };
    assert_eq!(s.spheres.len(), 1);
    let m = &s.materials[s.spheres[0].material as usize];
    assert_eq!(m.bsdf, Bsdf::Mirror { reflectance: Vec3::ONE });
}

#[test]
fn cbspheres_has_mirror_and_glass() {
    let Some(s) = common::load_scene("cs184/sky/CBspheres.dae") else { return };
    let kinds: Vec<&Bsdf> = s.spheres.iter().map(|sp| &s.materials[sp.material as usize].bsdf).collect();
    assert!(kinds.iter().any(|b| matches!(b, Bsdf::Mirror { .. })), "{kinds:?}");
    assert!(kinds.iter().any(|b| matches!(b, Bsdf::Glass { ior, .. } if *ior == 1.45)), "{kinds:?}");
    assert!(s.materials.iter().any(|m| m.is_emissive()), "the light mesh emits");
}

#[test]
fn microfacet_parameters_come_from_the_file() {
    let Some(path) = common::scene("cs184/sky/CBbunny_microfacet_cu.dae") else { return };
    let text = std::fs::read_to_string(&path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let mf = doc.descendants().find(|n| n.has_tag_name("microfacet")).unwrap();
    let nums = |tag: &str| -> Vec<f32> {
        let n = mf.children().find(|c| c.has_tag_name(tag)).unwrap();
        n.text().unwrap().split_whitespace().map(|t| t.parse().unwrap()).collect()
    };
    let want = Bsdf::Microfacet {
        alpha: nums("alpha")[0],
        eta: Vec3::from_slice(&nums("eta")),
        k: Vec3::from_slice(&nums("k")),
    };
    let s = load(&path, &LoadOptions::default()).unwrap();
    assert!(s.materials.iter().any(|m| m.bsdf == want), "{:?}", s.materials);
}

#[test]
fn smooth_normals_are_unit_and_point_out_of_a_closed_cube() {
    let Some(s) = common::load_scene("cs184/simple/cube.dae") else { return };
    let normals = s.mesh.normals.as_ref().unwrap();
    let used: std::collections::BTreeSet<u32> = s.mesh.triangles.iter().flatten().copied().collect();
    let centroid = used.iter().map(|&i| s.mesh.positions[i as usize]).sum::<Vec3>() / used.len() as f32;
    for &i in &used {
        let (p, n) = (s.mesh.positions[i as usize], normals[i as usize]);
        assert!((n.length() - 1.0).abs() < 1e-5);
        assert!(n.dot((p - centroid).normalize()) > 0.5, "vertex {i}: normal {n} at {p}");
    }
    // The same on a big mesh: every normal is unit length.
    if let Some(b) = common::load_scene("cs184/sky/bunny.dae") {
        assert!(b.mesh.normals.unwrap().iter().all(|n| (n.length() - 1.0).abs() < 1e-4));
    }
}

#[test]
fn file_normals_keep_order_and_counts() {
    let Some(path) = common::scene("cs184/sky/CBspheres_lambertian.dae") else { return };
    let smooth = load(&path, &LoadOptions::default()).unwrap();
    let flat = load(&path, &LoadOptions { smooth_normals: false, ..LoadOptions::default() }).unwrap();
    assert_eq!(smooth.mesh.triangles.len(), flat.mesh.triangles.len());
    for i in 0..flat.mesh.triangles.len() {
        assert_eq!(smooth.mesh.corners(i), flat.mesh.corners(i), "triangle {i} keeps its corners");
    }
    assert_eq!(smooth.mesh.material_ids, flat.mesh.material_ids);
    // The ceiling (first geometry, local normal 0 -1 0, node matrix ~ the inverse axis swap)
    // keeps the file's downward normal.
    let n = flat.mesh.normals.as_ref().unwrap();
    let t = flat.mesh.triangles[0];
    assert!(close(n[t[0] as usize], vec3(0.0, -1.0, 0.0), 1e-5), "{}", n[t[0] as usize]);
    assert!(flat.mesh.uvs.is_some(), "TEXCOORD kept");
}

// ---------------------------------------------------------------------------------------
// Hand-written documents
// ---------------------------------------------------------------------------------------

/// A COLLADA document with the given up axis, library contents and visual-scene nodes.
pub(super) fn doc(up: &str, geometries: &str, nodes: &str) -> String {
    format!(
        r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><up_axis>{up}</up_axis></asset>
  <library_effects>
    <effect id="red-fx"><profile_COMMON><technique sid="common"><lambert>
      <diffuse><color>0.8 0.1 0.1 1</color></diffuse></lambert></technique></profile_COMMON></effect>
  </library_effects>
  <library_materials><material id="red" name="red"><instance_effect url="#red-fx"/></material></library_materials>
  <library_geometries>{geometries}</library_geometries>
  <library_visual_scenes><visual_scene id="Scene">{nodes}</visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#Scene"/></scene>
</COLLADA>"##
    )
}

/// A mesh geometry `id` with positions and one primitive element (verbatim).
pub(super) fn mesh(id: &str, positions: &[f32], extra_sources: &str, vertices_extra: &str, prim: &str) -> String {
    let n = positions.len();
    let text: Vec<String> = positions.iter().map(|v| v.to_string()).collect();
    format!(
        r##"<geometry id="{id}"><mesh>
  <source id="{id}-pos"><float_array id="{id}-pos-array" count="{n}">{}</float_array>
    <technique_common><accessor source="#{id}-pos-array" count="{}" stride="3">
      <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
  {extra_sources}
  <vertices id="{id}-vtx"><input semantic="POSITION" source="#{id}-pos"/>{vertices_extra}</vertices>
  {prim}
</mesh></geometry>"##,
        text.join(" "),
        n / 3
    )
}

pub(super) fn node(id: &str, transforms: &str, geometry: &str, children: &str) -> String {
    format!(
        r##"<node id="{id}">{transforms}<instance_geometry url="#{geometry}"><bind_material><technique_common>
          <instance_material symbol="mat" target="#red"/></technique_common></bind_material></instance_geometry>{children}</node>"##
    )
}

pub(super) const TRI: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
pub(super) const ONE_TRI: &str = r##"<triangles material="mat" count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>0 1 2</p></triangles>"##;

pub(super) fn parse(text: &str) -> Scene {
    parse_str(text, "test.dae", &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn translate_rotate_scale_and_nested_nodes_compose() {
    let g = mesh("g", &TRI, "", "", ONE_TRI);
    // Parent: translate (1,2,3) then rotate 90 deg about Z. Child: scale 2.
    // In the parent's frame the child's point (1,0,0) -> (2,0,0); the rotation takes it to
    // (0,2,0); the translation to (1,4,3). Y_UP: no axis conversion.
    let child = node("c", r##"<scale>2 2 2</scale>"##, "g", "");
    let parent = node("p", r##"<translate>1 2 3</translate><rotate>0 0 1 90</rotate>"##, "g", &child);
    let s = parse(&doc("Y_UP", &g, &parent));
    assert_eq!(s.mesh.triangles.len(), 2);
    // Parent instance first (document order), then the child's.
    let [a, b, _] = s.mesh.corners(0);
    assert!(close(a, vec3(1.0, 2.0, 3.0), 1e-6) && close(b, vec3(1.0, 3.0, 3.0), 1e-6), "{a} {b}");
    let [a, b, c] = s.mesh.corners(1);
    assert!(close(a, vec3(1.0, 2.0, 3.0), 1e-6), "{a}");
    assert!(close(b, vec3(1.0, 4.0, 3.0), 1e-5), "{b}");
    assert!(close(c, vec3(-1.0, 2.0, 3.0), 1e-5), "{c}");
    assert_eq!(s.materials[s.mesh.material_ids[0] as usize].bsdf, Bsdf::Diffuse { albedo: vec3(0.8, 0.1, 0.1) });
}

/// A rotation about a zero-length axis turns nothing: skipped with one warning naming it,
/// the rest of the node's transform kept.
#[test]
fn a_zero_length_rotation_axis_is_a_warning() {
    let g = mesh("g", &TRI, "", "", ONE_TRI);
    let s = parse(&doc("Y_UP", &g, &node("n", "<translate>1 2 3</translate><rotate>0 0 0 90</rotate>", "g", "")));
    let plain = parse(&doc("Y_UP", &g, &node("n", "<translate>1 2 3</translate>", "g", "")));
    assert_eq!(s.mesh.positions, plain.mesh.positions);
    assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
    assert!(
        s.notes[0].starts_with("warning: test.dae: line") && s.notes[0].contains("rotation axis has zero length"),
        "{:?}",
        s.notes
    );
}

#[test]
fn z_up_and_x_up_conversions() {
    let g = mesh("g", &TRI, "", "", ONE_TRI);
    let n = node("n", r##"<translate>1 2 3</translate>"##, "g", "");
    let z = parse(&doc("Z_UP", &g, &n));
    assert!(close(z.mesh.corners(0)[0], vec3(-1.0, 3.0, 2.0), 0.0));
    let x = parse(&doc("X_UP", &g, &n));
    assert!(close(x.mesh.corners(0)[0], vec3(2.0, 1.0, -3.0), 0.0));
}

#[test]
fn polygons_and_polylists_are_fan_triangulated_in_order() {
    // A pentagon (polylist vcount 5) and a quad (<polygons>), then a triangle list.
    let pos: Vec<f32> = (0..6).flat_map(|i| [i as f32, (i * i) as f32, 0.0]).collect();
    let prims = r##"
      <polylist material="mat" count="2"><input semantic="VERTEX" source="#g-vtx" offset="0"/>
        <vcount>5 3</vcount><p>0 1 2 3 4  5 4 3</p></polylist>
      <polygons material="mat" count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>5 4 3 2</p></polygons>
      <triangles count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>2 1 0</p></triangles>"##;
    let g = mesh("g", &pos, "", "", prims);
    let s = parse(&doc("Y_UP", &g, &node("n", "", "g", "")));
    let got: Vec<[u32; 3]> = s.mesh.triangles.clone();
    // Positions are shared 1:1 (no uvs), so indices are the file's.
    let want = vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [5, 4, 3], [5, 4, 3], [5, 3, 2], [2, 1, 0]];
    assert_eq!(got, want);
    // The triangles without a material symbol take the instance's first bound material.
    assert!(s.mesh.material_ids.iter().all(|m| s.materials[m as usize].name == "red"));
}

#[test]
fn separate_index_streams_split_vertices_by_normal() {
    // A quad as two triangles with one normal per face (index 0 and 1) and per-corner uvs.
    let pos = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0];
    let extra = r##"
      <source id="g-n"><float_array id="g-n-a" count="6">0 0 1 0 0 2</float_array>
        <technique_common><accessor source="#g-n-a" count="2" stride="3"/></technique_common></source>
      <source id="g-uv"><float_array id="g-uv-a" count="9">0 0 9 1 0 9 1 1 9</float_array>
        <technique_common><accessor source="#g-uv-a" count="3" stride="3"/></technique_common></source>"##;
    let prim = r##"<polylist material="mat" count="2">
        <input semantic="VERTEX" source="#g-vtx" offset="0"/>
        <input semantic="NORMAL" source="#g-n" offset="1"/>
        <input semantic="TEXCOORD" source="#g-uv" offset="3" set="0"/>
        <vcount>3 3</vcount><p>0 0 7 0  1 0 7 1  2 0 7 2   0 1 7 1  2 1 7 2  3 1 7 1</p></polylist>"##;
    let g = mesh("g", &pos, extra, "", prim);
    let text = doc("Y_UP", &g, &node("n", "", "g", ""));
    let flat = parse_str(&text, "t.dae", &LoadOptions { smooth_normals: false, ..LoadOptions::default() }).unwrap();
    assert_eq!(flat.mesh.triangles.len(), 2);
    // Corners of the shared edge 0-2 differ by normal: 6 distinct (position, normal, uv).
    assert_eq!(flat.mesh.positions.len(), 6);
    assert!(flat.mesh.normals.as_ref().unwrap().iter().all(|n| close(*n, Vec3::Z, 1e-6)));
    let uvs = flat.mesh.uvs.as_ref().unwrap();
    let t1 = flat.mesh.triangles[1];
    assert_eq!(uvs[t1[2] as usize], glam::vec2(1.0, 0.0), "stride-3 accessor: S and T of entry 1");
    // Smooth: the normal index is ignored; corners share by (position, uv), and position 0
    // has two uvs: 5 vertices.
    let smooth = parse(&text);
    assert_eq!(smooth.mesh.positions.len(), 5);
    for i in 0..2 {
        assert_eq!(smooth.mesh.corners(i), flat.mesh.corners(i));
    }
}

#[test]
fn spheres_instanced_twice_scale_by_the_x_column() {
    let g = r##"<geometry id="s"><extra><technique profile="CGL"><sphere><radius>.5</radius></sphere></technique></extra></geometry>"##;
    let nodes = [
        node("a", r##"<matrix>2 0 0 1  0 2 0 2  0 0 2 3  0 0 0 1</matrix>"##, "s", ""),
        node("b", r##"<translate>0 0 -1</translate>"##, "s", ""),
    ]
    .concat();
    let s = parse(&doc("Z_UP", g, &nodes));
    assert_eq!(s.spheres.len(), 2);
    assert!(close(s.spheres[0].center, vec3(-1.0, 3.0, 2.0), 0.0) && s.spheres[0].radius == 1.0);
    assert!(close(s.spheres[1].center, vec3(0.0, -1.0, 0.0), 0.0) && s.spheres[1].radius == 0.5);
    assert_eq!(s.materials[s.spheres[0].material as usize].name, "red");
}

#[test]
fn unbound_symbol_gets_a_default_material_and_no_camera_gets_a_framing() {
    let prim = r##"<triangles material="elsewhere" count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>0 1 2</p></triangles>"##;
    let g = mesh("g", &TRI, "", "", prim);
    let s = parse(&doc("Y_UP", &g, &node("n", "", "g", "")));
    let m = &s.materials[s.mesh.material_ids[0] as usize];
    assert_eq!(m.bsdf, Bsdf::Diffuse { albedo: Vec3::splat(0.5) });
    let (lo, hi) = s.bounds().unwrap();
    assert!(close(s.camera.position, crate::scene::Camera::framing(lo, hi).position, 0.0));
}

// ---------------------------------------------------------------------------------------
// Bad input: an error naming the file and the problem, on one line, never a panic
// ---------------------------------------------------------------------------------------

#[track_caller]
pub(super) fn rejects(text: &str, needle: &str) {
    match parse_str(text, "bad.dae", &LoadOptions::default()) {
        Ok(_) => panic!("accepted bad input (expected '{needle}')"),
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("bad.dae: "), "{msg}");
            assert!(!msg.contains('\n'), "one line: {msg}");
            assert!(msg.contains(needle), "'{msg}' should mention '{needle}'");
        }
    }
}

fn one_mesh(positions_text: &str, count: usize, prim: &str) -> String {
    let g = format!(
        r##"<geometry id="g"><mesh>
  <source id="g-pos"><float_array id="g-pos-array" count="{count}">{positions_text}</float_array>
    <technique_common><accessor source="#g-pos-array" count="{}" stride="3"/></technique_common></source>
  <vertices id="g-vtx"><input semantic="POSITION" source="#g-pos"/></vertices>{prim}</mesh></geometry>"##,
        count / 3
    );
    doc("Y_UP", &g, &node("n", "", "g", ""))
}

#[test]
fn bad_malformed_xml() {
    rejects("<COLLADA><asset></COLLADA>", "malformed XML");
    rejects("", "malformed XML");
    let good = doc("Y_UP", &mesh("g", &TRI, "", "", ONE_TRI), &node("n", "", "g", ""));
    rejects(&good[..good.len() / 2], "malformed XML");
}

#[test]
fn bad_not_collada() {
    rejects("<svg/>", "not a COLLADA file");
}

#[test]
fn bad_dtd_and_entities() {
    let lol = r##"<?xml version="1.0"?><!DOCTYPE COLLADA [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;">]><COLLADA>&b;</COLLADA>"##;
    rejects(lol, "DTD");
}

#[test]
fn bad_missing_references() {
    rejects(&doc("Y_UP", "", &node("n", "", "nope", "")), "\"#nope\" refers to an id that does not exist");
    let g = mesh("g", &TRI, "", "", ONE_TRI);
    let bad_mat = doc("Y_UP", &g, &node("n", "", "g", "")).replace(r##"target="#red""##, r##"target="#missing""##);
    rejects(&bad_mat, "does not exist");
    let bad_src = one_mesh("0 0 0 1 0 0 0 1 0", 9, ONE_TRI).replace(r##"source="#g-pos""##, r##"source="#g-gone""##);
    rejects(&bad_src, "does not exist");
    let wrong_kind = doc("Y_UP", &g, &node("n", "", "red", ""));
    rejects(&wrong_kind, "refers to a <material>, expected <geometry>");
    rejects(&doc("Y_UP", &g, "").replace("#Scene", "#Elsewhere"), "does not exist");
}

#[test]
fn bad_numbers() {
    rejects(&one_mesh("0 0 0 1 zero 0 0 1 0", 9, ONE_TRI), "'zero' is not a number");
    rejects(&one_mesh("0 0 0 1 NaN 0 0 1 0", 9, ONE_TRI), "'NaN' is not a finite number");
    rejects(&one_mesh("0 0 0 1 inf 0 0 1 0", 9, ONE_TRI), "'inf' is not a finite number");
    rejects(&one_mesh("0 0 0 1 1e39 0 0 1 0", 9, ONE_TRI), "not a finite number");
    let neg = ONE_TRI.replace("0 1 2", "0 -1 2");
    rejects(&one_mesh("0 0 0 1 0 0 0 1 0", 9, &neg), "'-1' is not a non-negative integer");
    let g = mesh("g", &TRI, "", "", ONE_TRI);
    rejects(&doc("Y_UP", &g, &node("n", "<translate>1 x 3</translate>", "g", "")), "'x' is not a number");
    rejects(&doc("Y_UP", &g, &node("n", "<translate>1 2</translate>", "g", "")), "expected 3 numbers");
    rejects(&doc("Y_UP", &g, &node("n", "<matrix>1 2 3</matrix>", "g", "")), "expected 16 numbers");
    let huge = doc(
        "Y_UP",
        &g,
        &node("n", "<scale>1e30 1e30 1e30</scale>", "g", &node("c", "<scale>1e30 1 1</scale>", "g", "")),
    );
    rejects(&huge, "non-finite");
}

#[test]
fn bad_indices_out_of_range() {
    let p = ONE_TRI.replace("0 1 2", "0 1 3");
    rejects(&one_mesh("0 0 0 1 0 0 0 1 0", 9, &p), "vertex index 3 is out of range (3 vertices)");
    let big = ONE_TRI.replace("0 1 2", "0 1 4294967295");
    rejects(&one_mesh("0 0 0 1 0 0 0 1 0", 9, &big), "out of range");
    let too_big = ONE_TRI.replace("0 1 2", "0 1 4294967296");
    rejects(&one_mesh("0 0 0 1 0 0 0 1 0", 9, &too_big), "not a non-negative integer");
    let normals = r##"<polylist count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/>
        <input semantic="NORMAL" source="#g-pos" offset="1"/><vcount>3</vcount><p>0 0 1 5 2 0</p></polylist>"##;
    rejects(&one_mesh("0 0 0 1 0 0 0 1 0", 9, normals), "NORMAL index 5 is out of range");
}

#[test]
fn bad_counts_promising_more_than_the_data() {
    // Declared counts far beyond the data must fail before anything is sized from them.
    rejects(&one_mesh("0 0 0 1 0 0 0 1 0", 3_000_000_000, ONE_TRI), "count=3000000000 but the array holds 9");
    let g = one_mesh("0 0 0 1 0 0 0 1 0", 9, ONE_TRI)
        .replace(r##"count="3" stride="3""##, r##"count="1000000000" stride="3""##);
    rejects(&g, "needs 3000000000 numbers but the array holds 9");
    let tri = ONE_TRI.replace(r##"count="1""##, r##"count="4000000000""##);
    rejects(&one_mesh("0 0 0 1 0 0 0 1 0", 9, &tri), "<p> holds 3");
    let poly = r##"<polylist count="2"><input semantic="VERTEX" source="#g-vtx" offset="0"/><vcount>3 4000000000</vcount><p>0 1 2</p></polylist>"##;
    rejects(&one_mesh("0 0 0 1 0 0 0 1 0", 9, poly), "<vcount> needs 4000000003 indices but <p> holds 3");
    let short_vcount = r##"<polylist count="5"><input semantic="VERTEX" source="#g-vtx" offset="0"/><vcount>3</vcount><p>0 1 2</p></polylist>"##;
    rejects(&one_mesh("0 0 0 1 0 0 0 1 0", 9, short_vcount), "count=5 but <vcount> lists 1");
    let stride = one_mesh("0 0 0 1 0 0 0 1 0", 9, ONE_TRI).replace(r##"stride="3""##, r##"stride="2""##);
    rejects(&stride, "stride 2 is less than the 3 components");
}

#[test]
fn bad_deep_nesting_and_cycles() {
    let g = mesh("g", &TRI, "", "", ONE_TRI);
    let depth = 300;
    let nested = format!("{}{}", "<node>".repeat(depth), "</node>".repeat(depth));
    rejects(&doc("Y_UP", &g, &nested), "nest deeper than 256");
    // Very deep XML (beyond any recursion the loader could survive) is refused the same way.
    let deep = format!("{}{}", "<node>".repeat(100_000), "</node>".repeat(100_000));
    rejects(&doc("Y_UP", &g, &deep), "nest deeper");
    let cycle = r##"<node id="loop"><instance_node url="#loop"/></node>"##;
    rejects(&doc("Y_UP", &g, cycle), "nest deeper");
}

#[test]
fn bad_empty_meshes() {
    let empty = r##"<geometry id="g"><mesh></mesh></geometry>"##;
    rejects(&doc("Y_UP", empty, &node("n", "", "g", "")), "no triangles and no spheres");
    rejects(&one_mesh("", 0, ""), "no triangles and no spheres");
    rejects(&doc("Y_UP", "", ""), "no triangles and no spheres");
    let no_vertices = r##"<geometry id="g"><mesh><triangles count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>0 1 2</p></triangles></mesh></geometry>"##;
    rejects(&doc("Y_UP", no_vertices, &node("n", "", "g", "")), "does not exist");
    rejects(&doc("Y_UP", r##"<geometry id="g"/>"##, &node("n", "", "g", "")), "neither a <mesh> nor a CGL <sphere>");
}

#[test]
fn bad_lights_cameras_and_materials() {
    let g = mesh("g", &TRI, "", "", ONE_TRI);
    let with = |lib: &str, inst: &str| {
        doc("Y_UP", &g, &node("n", "", "g", ""))
            .replace("<library_geometries>", &format!("{lib}<library_geometries>"))
            .replace("</visual_scene>", &format!(r##"<node id="x">{inst}</node></visual_scene>"##))
    };
    let cam = |p: &str| {
        with(
            &format!(
                r##"<library_cameras><camera id="c"><optics><technique_common>{p}</technique_common></optics></camera></library_cameras>"##
            ),
            r##"<instance_camera url="#c"/>"##,
        )
    };
    rejects(&cam("<perspective><xfov>200</xfov></perspective>"), "outside (0, 180)");
    rejects(&cam("<perspective><xfov>40</xfov><znear>10</znear><zfar>1</zfar></perspective>"), "clip range");
    rejects(&cam("<orthographic><xmag>-1</xmag></orthographic>"), "view size -1 x -0.75 is not positive");
    rejects(&cam("<frustum/>"), "<perspective> or <orthographic>");
    let light = |l: &str| {
        with(
            &format!(r##"<library_lights><light id="l">{l}</light></library_lights>"##),
            r##"<instance_light url="#l"/>"##,
        )
    };
    rejects(
        &light("<technique_common><point><color>1 1</color></point></technique_common>"),
        "a colour needs 3 numbers",
    );
    rejects(&light("<technique_common><laser><color>1 1 1</color></laser></technique_common>"), "unknown light type");
    let fx = doc("Y_UP", &g, &node("n", "", "g", "")).replace(
        "</profile_COMMON></effect>",
        r##"</profile_COMMON><extra><technique profile="CGL"><microfacet><alpha>0.1</alpha></microfacet></technique></extra></effect>"##,
    );
    rejects(&fx, "missing <eta>");
}

/// Truncations and byte damage of a real scene: always Ok or a one-line error, never a panic.
#[test]
fn damaged_real_file_never_panics() {
    let Some(path) = common::scene("cs184/sky/CBspheres_lambertian.dae") else { return };
    let text = std::fs::read_to_string(&path).unwrap();
    let bytes = text.as_bytes();
    let mut rng = common::Xorshift(0x2545_f491_4f6c_dd1d);
    for k in 0..400 {
        let mut b = bytes.to_vec();
        if k % 2 == 0 {
            b.truncate(rng.below(b.len()));
        } else {
            for _ in 0..4 {
                let i = rng.below(b.len());
                b[i] = b"0123456789 -.<>/\"#e"[rng.below(19)];
            }
        }
        let Ok(t) = String::from_utf8(b) else { continue };
        for opts in [
            LoadOptions::default(),
            LoadOptions { camera: CameraMode::File, smooth_normals: false, ..LoadOptions::default() },
        ] {
            if let Err(e) = parse_str(&t, "damaged.dae", &opts) {
                let msg = e.to_string();
                assert!(msg.starts_with("damaged.dae: ") && !msg.contains('\n'), "{msg}");
            }
        }
    }
}
