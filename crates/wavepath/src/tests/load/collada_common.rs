//! COLLADA's common profile in files that are not the CS184 course's: each shader and
//! parameter mapped as the README's table "What materials become" says, textures through
//! the newparam chain, and the course's files kept as the course reads them.

use super::collada::{TRI, mesh};
use crate::load::LoadOptions;
use crate::load::collada::parse_str;
use crate::scene::{Bsdf, Scene};
use crate::tests::common::temp_dir;
use glam::{Vec3, vec3};

/// A document whose one mesh has a triangle per (id, effect body) pair, each bound to its
/// own material; `images` goes into `<library_images>`, `asset` into `<asset>`.
fn document(asset: &str, images: &str, effects: &[(&str, &str)]) -> String {
    let mut fx = String::new();
    let mut mats = String::new();
    let mut prims = String::new();
    let mut binds = String::new();
    for (id, body) in effects {
        fx.push_str(&format!(r##"<effect id="{id}-fx"><profile_COMMON>{body}</profile_COMMON></effect>"##));
        mats.push_str(&format!(r##"<material id="{id}" name="{id}"><instance_effect url="#{id}-fx"/></material>"##));
        prims.push_str(&format!(
            r##"<triangles material="{id}-sym" count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>0 1 2</p></triangles>"##
        ));
        binds.push_str(&format!(r##"<instance_material symbol="{id}-sym" target="#{id}"/>"##));
    }
    let g = mesh("g", &TRI, "", "", &prims);
    format!(
        r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset>{asset}<up_axis>Y_UP</up_axis></asset>
  <library_images>{images}</library_images>
  <library_effects>{fx}</library_effects>
  <library_materials>{mats}</library_materials>
  <library_geometries>{g}</library_geometries>
  <library_visual_scenes><visual_scene id="Scene"><node id="n"><instance_geometry url="#g"><bind_material>
    <technique_common>{binds}</technique_common></bind_material></instance_geometry></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#Scene"/></scene>
</COLLADA>"##
    )
}

fn technique(shader: &str, params: &str) -> String {
    format!(r##"<technique sid="common"><{shader}>{params}</{shader}></technique>"##)
}

fn colour(tag: &str, c: &str) -> String {
    format!("<{tag}><color>{c}</color></{tag}>")
}

fn float(tag: &str, v: f32) -> String {
    format!("<{tag}><float>{v}</float></{tag}>")
}

fn bsdf(s: &Scene, name: &str) -> Bsdf {
    s.materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material {name}")).bsdf.clone()
}

const KD: Vec3 = Vec3::new(0.6, 0.3, 0.2);

#[test]
fn each_common_shader_becomes_its_model() {
    let d = colour("diffuse", "0.6 0.3 0.2 1");
    let spec = colour("specular", "0.25 0.25 0.25 1");
    let shin = float("shininess", 48.0);
    let effects = [
        ("lambert", technique("lambert", &d)),
        ("phong", technique("phong", &format!("{d}{spec}{shin}"))),
        ("blinn", technique("blinn", &format!("{d}{spec}{}", float("shininess", 200.0)))),
        ("phong_black", technique("phong", &format!("{d}{}{shin}", colour("specular", "0 0 0 1")))),
        ("constant", technique("constant", &colour("emission", "4 3 2 1"))),
        ("glowing", technique("lambert", &format!("{}{d}", colour("emission", "1 2 3 1")))),
        (
            "glass",
            technique(
                "phong",
                &format!(
                    "{d}{spec}{}{}{}",
                    r#"<transparent opaque="A_ONE"><color>1 1 1 1</color></transparent>"#,
                    float("transparency", 0.2),
                    float("index_of_refraction", 1.45)
                ),
            ),
        ),
        (
            "filter",
            technique(
                "lambert",
                &format!("{d}{}", r#"<transparent opaque="RGB_ZERO"><color>0.5 0.8 1 1</color></transparent>"#),
            ),
        ),
        (
            "mirror",
            technique(
                "phong",
                &format!(
                    "{}{}{}",
                    colour("diffuse", "0 0 0 1"),
                    colour("reflective", "0.9 0.8 0.7 1"),
                    float("reflectivity", 1.0)
                ),
            ),
        ),
        ("opaque", technique("lambert", &format!("{d}{}", float("transparency", 1.0)))),
    ];
    let effects: Vec<(&str, &str)> = effects.iter().map(|(a, b)| (*a, b.as_str())).collect();
    let s = parse_str(&document("", "", &effects), "other.dae", &LoadOptions::default()).unwrap();
    assert_eq!(bsdf(&s, "lambert"), Bsdf::Diffuse { albedo: KD });
    assert_eq!(bsdf(&s, "phong"), Bsdf::Phong { diffuse: KD, specular: Vec3::splat(0.25), shininess: 48.0 });
    assert_eq!(bsdf(&s, "blinn"), Bsdf::Phong { diffuse: KD, specular: Vec3::splat(0.25), shininess: 200.0 });
    assert_eq!(bsdf(&s, "phong_black"), Bsdf::Diffuse { albedo: KD });
    let constant = s.materials.iter().find(|m| m.name == "constant").unwrap();
    assert_eq!((constant.bsdf.clone(), constant.emission), (Bsdf::Diffuse { albedo: Vec3::ZERO }, vec3(4.0, 3.0, 2.0)));
    let glowing = s.materials.iter().find(|m| m.name == "glowing").unwrap();
    assert_eq!((glowing.bsdf.clone(), glowing.emission), (Bsdf::Diffuse { albedo: KD }, vec3(1.0, 2.0, 3.0)));
    // A_ONE: opacity = alpha x transparency = 0.2, so 0.8 of the light goes through.
    let Bsdf::Glass { reflectance, transmittance, ior, .. } = bsdf(&s, "glass") else { panic!("not glass") };
    assert_eq!((reflectance, ior), (Vec3::ONE, 1.45));
    assert!((transmittance - Vec3::splat(0.8)).abs().max_element() < 1e-6, "{transmittance}");
    // RGB_ZERO: the colour is what goes through; no index: light is filtered, not bent.
    assert_eq!(
        bsdf(&s, "filter"),
        Bsdf::Glass { reflectance: Vec3::ONE, transmittance: vec3(0.5, 0.8, 1.0), roughness: 0.0, ior: 1.0 }
    );
    assert_eq!(bsdf(&s, "mirror"), Bsdf::Mirror { reflectance: vec3(0.9, 0.8, 0.7) });
    assert_eq!(bsdf(&s, "opaque"), Bsdf::Diffuse { albedo: KD });
}

/// `<texture texture="sampler">` -> newparam sampler2D -> newparam surface -> init_from ->
/// `<image>` -> file, read as the albedo (and COLLADA 1.5's instance_image, and an image
/// named directly); a chain that leads nowhere loses the texture with a warning.
#[test]
fn diffuse_textures_follow_the_newparam_chain() {
    let d = temp_dir("collada-texture");
    let img =
        image::RgbImage::from_fn(2, 2, |x, _| if x == 0 { image::Rgb([255, 0, 0]) } else { image::Rgb([0, 0, 255]) });
    std::fs::create_dir_all(d.join("tex")).unwrap();
    img.save(d.join("tex/my image.png")).unwrap();
    let images = r##"<image id="img1"><init_from>tex/my%20image.png</init_from></image>
                    <image id="img2"><init_from><ref>./tex/my image.png</ref></init_from></image>"##;
    let tex = |sampler: &str| format!(r##"<diffuse><texture texture="{sampler}" texcoord="UVMap"/></diffuse>"##);
    let chain = format!(
        r##"<newparam sid="surf"><surface type="2D"><init_from>img1</init_from></surface></newparam>
            <newparam sid="samp"><sampler2D><source>surf</source></sampler2D></newparam>{}"##,
        technique(
            "phong",
            &format!("{}{}{}", tex("samp"), colour("specular", "0.2 0.2 0.2 1"), float("shininess", 50.0))
        )
    );
    let v15 = format!(
        r##"<newparam sid="s15"><sampler2D><instance_image url="#img2"/></sampler2D></newparam>{}"##,
        technique("lambert", &tex("s15"))
    );
    let direct = technique("lambert", &tex("img1"));
    let broken = technique("lambert", &tex("nowhere"));
    let effects =
        [("chain", chain.as_str()), ("v15", v15.as_str()), ("direct", direct.as_str()), ("broken", broken.as_str())];
    let file = d.join("scene.dae");
    std::fs::write(&file, document("", images, &effects)).unwrap();
    let s = crate::load::load(&file, &LoadOptions::default()).unwrap();
    for name in ["chain", "v15", "direct"] {
        let m = s.materials.iter().find(|m| m.name == name).unwrap();
        let t = m.albedo_texture.as_ref().unwrap_or_else(|| panic!("{name}: no texture; notes {:?}", s.notes));
        let image = t.image.as_ref().expect("decoded");
        assert_eq!((image.width, image.height), (2, 2));
        assert_eq!((image.texels[0], image.texels[1]), (vec3(1.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0)), "{name}");
        assert!(t.flip_v, "COLLADA's v points up, as OBJ's");
    }
    assert!(matches!(bsdf(&s, "chain"), Bsdf::Phong { shininess: 50.0, .. }));
    let broken = s.materials.iter().find(|m| m.name == "broken").unwrap();
    assert!(broken.albedo_texture.is_none());
    assert!(s.notes.iter().any(|n| n.contains("scene.dae") && n.contains("\"nowhere\"")), "{:?}", s.notes);
}

/// The course's files keep the course's reading: a Phong effect with a specular colour is
/// diffuse when the file has CGL extras or was exported by the course's Blender versions.
#[test]
fn course_files_keep_diffuse_phong() {
    let phong = technique(
        "phong",
        &format!(
            "{}{}{}",
            colour("diffuse", "0.6 0.3 0.2 1"),
            colour("specular", "0.5 0.5 0.5 1"),
            float("shininess", 50.0)
        ),
    );
    let effects = [("p", phong.as_str())];
    let tool = "<contributor><authoring_tool>Blender 2.74.0 commit date:2015-03-31</authoring_tool></contributor>";
    let course = parse_str(&document(tool, "", &effects), "course.dae", &LoadOptions::default()).unwrap();
    assert_eq!(bsdf(&course, "p"), Bsdf::Diffuse { albedo: KD });
    let newer = "<contributor><authoring_tool>Blender 4.1.0</authoring_tool></contributor>";
    let other = parse_str(&document(newer, "", &effects), "other.dae", &LoadOptions::default()).unwrap();
    assert!(matches!(bsdf(&other, "p"), Bsdf::Phong { .. }));
    // Every shared CS184 file is recognised as the course's.
    let Some(dir) = crate::tests::common::scenes_dir() else { return };
    for f in crate::tests::common::files_with_ext(&dir.join("cs184"), &["dae"]) {
        let s = crate::load::load(&f, &LoadOptions::default()).unwrap();
        assert!(s.materials.iter().all(|m| !matches!(m.bsdf, Bsdf::Phong { .. })), "{}", f.display());
    }
}
