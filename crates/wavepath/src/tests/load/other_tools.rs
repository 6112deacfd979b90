//! Scenes as other tools write them: orthographic cameras (COLLADA and glTF) render as
//! parallel projections, and COLLADA skinned or morphed geometry loads in its bind pose.

use super::collada::{ONE_TRI, TRI, doc, mesh, node, parse, rejects};
use crate::accel::BruteForce;
use crate::load::collada::parse_str;
use crate::load::{CameraMode, LoadOptions, load};
use crate::scene::{Environment, Scene};
use crate::settings::{Settings, Shading};
use crate::tests::common::temp_dir;
use glam::{Vec3, vec3};

const W: usize = 40;
const H: usize = 30;

/// A unit square (two triangles) in the z = 0 plane, centred on the origin.
const SQUARE: [f32; 18] =
    [-0.5, -0.5, 0.0, 0.5, -0.5, 0.0, 0.5, 0.5, 0.0, -0.5, -0.5, 0.0, 0.5, 0.5, 0.0, -0.5, 0.5, 0.0];
const TWO_TRIS: &str = r##"<triangles material="mat" count="2"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>0 1 2 3 4 5</p></triangles>"##;

/// Pixels that see geometry in a W x H render (one sample at each pixel centre), counted
/// in the normal view and in a direct-light render under a white sky (the ground is
/// darker than the sky); both must agree.
fn covered(scene: &mut Scene) -> usize {
    scene.camera.fit_to(W as f32, H as f32);
    scene.lights.clear();
    scene.env = Environment::Constant(Vec3::ONE);
    let count = |shading: Shading, seen: fn(Vec3) -> bool| {
        let mut s = Settings::default();
        s.image.width = W;
        s.image.height = H;
        s.paths.shading = shading;
        s.paths.max_depth = 1;
        let (film, _) = crate::render::render(scene, &BruteForce::new(scene), &s).unwrap();
        (0..H).flat_map(|y| (0..W).map(move |x| (x, y))).filter(|&(x, y)| seen(film.get(x, y))).count()
    };
    let normals = count(Shading::Normals, |c| c != Vec3::ZERO);
    let direct = count(Shading::Direct, |c| c.max_element() < 0.99);
    assert_eq!(normals, direct, "normal view and light transport see different pixels");
    direct
}

/// A COLLADA orthographic camera 4 x 3 units wide (xmag 2, ymag 1.5) looking at the unit
/// square from distance `dist`: the square covers exactly a quarter of the width and a third
/// of the height, 10 x 10 pixel centres at 40 x 30, from any distance.
#[test]
fn orthographic_cameras_are_parallel_projections() {
    let cam = r##"<library_cameras><camera id="c"><optics><technique_common><orthographic>
        <xmag>2</xmag><ymag>1.5</ymag><znear>0.1</znear><zfar>1000</zfar></orthographic></technique_common></optics></camera></library_cameras>"##;
    for dist in [2.0f32, 50.0] {
        let text = doc("Y_UP", &mesh("g", &SQUARE, "", "", TWO_TRIS), &node("n", "", "g", ""))
            .replace("<library_geometries>", &format!("{cam}<library_geometries>"))
            .replace(
                "</visual_scene>",
                &format!(r##"<node id="cn"><translate>0 0 {dist}</translate><instance_camera url="#c"/></node></visual_scene>"##),
            );
        // The CS184 placement has no parallel projection to imitate: both modes use the file's.
        for mode in [CameraMode::Cs184, CameraMode::File] {
            let mut s = parse_str(&text, "ortho.dae", &LoadOptions { camera: mode, ..LoadOptions::default() }).unwrap();
            assert!(s.camera.orthographic);
            let (a, b) = (s.camera.generate_ray(0.1, 0.2), s.camera.generate_ray(0.9, 0.7));
            assert!(a.dir.distance(b.dir) < 1e-6 && a.dir.distance(-Vec3::Z) < 1e-6, "{} {}", a.dir, b.dir);
            assert!((b.origin - a.origin - vec3(0.8 * 4.0, 0.5 * 3.0, 0.0)).length() < 1e-5);
            assert_eq!(covered(&mut s), 100, "distance {dist}, {mode:?}");
        }
    }
}

#[test]
fn gltf_orthographic_cameras_load_and_render() {
    let d = temp_dir("gltf-ortho");
    let square: Vec<u8> = SQUARE.iter().flat_map(|c| c.to_le_bytes()).collect();
    use base64::Engine;
    let doc = format!(
        r#"{{"asset":{{"version":"2.0"}},"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
          "cameras":[{{"type":"orthographic","orthographic":{{"xmag":2,"ymag":1.5,"znear":0.1,"zfar":100}}}}],
          "nodes":[{{"mesh":0}},{{"camera":0,"translation":[0,0,7]}}],"scenes":[{{"nodes":[0,1]}}],
          "buffers":[{{"byteLength":72,"uri":"data:application/octet-stream;base64,{}"}}],
          "bufferViews":[{{"buffer":0,"byteLength":72}}],
          "accessors":[{{"bufferView":0,"componentType":5126,"count":6,"type":"VEC3","min":[-0.5,-0.5,0],"max":[0.5,0.5,0]}}]}}"#,
        base64::engine::general_purpose::STANDARD.encode(&square)
    );
    std::fs::write(d.join("o.gltf"), doc).unwrap();
    let mut s = load(&d.join("o.gltf"), &LoadOptions::default()).unwrap();
    assert!(s.camera.orthographic);
    assert_eq!(covered(&mut s), 100);
}

/// A skin's geometry under its bind-shape matrix (translate 0 0 -3) inside a node
/// translated by 1 0 0; a morph's base geometry as it is; a skin of a morph composes.
#[test]
fn skinned_and_morphed_geometry_loads_in_its_bind_pose() {
    let controllers = r##"<library_controllers>
        <controller id="skin"><skin source="#g"><bind_shape_matrix>1 0 0 0 0 1 0 0 0 0 1 -3 0 0 0 1</bind_shape_matrix></skin></controller>
        <controller id="morph"><morph source="#g" method="NORMALIZED"/></controller>
        <controller id="skinned-morph"><skin source="#morph"><bind_shape_matrix>2 0 0 0 0 2 0 0 0 0 2 0 0 0 0 1</bind_shape_matrix></skin></controller>
        <controller id="empty"/>
        <controller id="loop"><skin source="#loop"/></controller>
      </library_controllers>"##;
    let with = |ctrl: &str| {
        let node = format!(
            r##"<node id="n"><translate>1 0 0</translate><instance_controller url="#{ctrl}"><bind_material><technique_common>
              <instance_material symbol="mat" target="#red"/></technique_common></bind_material></instance_controller></node>"##
        );
        doc("Y_UP", &mesh("g", &TRI, "", "", ONE_TRI), &node)
            .replace("<library_geometries>", &format!("{controllers}<library_geometries>"))
    };
    let corners = |s: &Scene| s.mesh.corners(0).to_vec();
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let skin = parse(&with("skin"));
    assert_eq!(corners(&skin), tri.map(|p| p + vec3(1.0, 0.0, -3.0)));
    // The bound material is kept.
    assert_eq!(skin.materials[skin.mesh.material_ids[0] as usize].name, "red");
    assert_eq!(corners(&parse(&with("morph"))), tri.map(|p| p + Vec3::X));
    assert_eq!(corners(&parse(&with("skinned-morph"))), tri.map(|p| 2.0 * p + Vec3::X));
    rejects(&with("empty"), "without <skin> or <morph>");
    rejects(&with("loop"), "in a loop");
}
