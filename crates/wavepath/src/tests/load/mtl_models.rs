//! MTL illumination models and keys, each on a small library written by the test, mapped
//! as the README's table "What materials become" says; and the warnings for keys not read.

use crate::bsdf::{Glossy, Model};
use crate::load::{LoadOptions, load};
use crate::scene::{Bsdf, Material, Scene};
use crate::tests::common::temp_dir;
use glam::{Vec2, Vec3, vec3};
use std::path::Path;

const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";

/// Loads an OBJ of one quad per material of `mtl` (in the library's order).
fn load_library(tag: &str, mtl: &str) -> Scene {
    let d = temp_dir(&format!("mtl-{tag}"));
    std::fs::write(d.join("m.mtl"), mtl).unwrap();
    let names: Vec<&str> = mtl.lines().filter_map(|l| l.trim().strip_prefix("newmtl ")).collect();
    let mut obj = format!("mtllib m.mtl\n{QUAD}");
    for n in &names {
        obj.push_str(&format!("usemtl {n}\nf 1/1 2/2 3/3 4/4\n"));
    }
    std::fs::write(d.join("a.obj"), obj).unwrap();
    load(&d.join("a.obj"), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e:#}"))
}

fn material<'a>(s: &'a Scene, name: &str) -> &'a Material {
    s.materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material {name}"))
}

fn bsdf(s: &Scene, name: &str) -> Bsdf {
    material(s, name).bsdf.clone()
}

const KD: Vec3 = Vec3::new(0.6, 0.3, 0.2);

/// A block of `illum n` with every key the models read.
fn block(name: &str, illum: i32) -> String {
    format!(
        "newmtl {name}\nKa 0.1 0.1 0.1\nKd 0.6 0.3 0.2\nKs 0.3 0.3 0.25\nNs 98\nNi 1.7\nTf 0.9 0.8 0.7\nillum {illum}\n"
    )
}

#[test]
fn every_illumination_model_becomes_its_scattering_model() {
    let mtl: String = (0..=11).map(|i| block(&format!("m{i}"), i)).collect();
    let s = load_library("illum", &mtl);
    let ks = vec3(0.3, 0.3, 0.25);
    let glass = Bsdf::Glass { reflectance: Vec3::ONE, transmittance: vec3(0.9, 0.8, 0.7), roughness: 0.0, ior: 1.7 };
    let expect = [
        (0, Bsdf::Diffuse { albedo: KD }),
        (1, Bsdf::Diffuse { albedo: KD }),
        (2, Bsdf::Phong { diffuse: KD, specular: ks, shininess: 98.0 }),
        (3, Bsdf::Mirror { reflectance: ks }),
        (4, glass.clone()),
        (5, Bsdf::Mirror { reflectance: ks }),
        (6, glass.clone()),
        (7, glass.clone()),
        (8, Bsdf::Mirror { reflectance: ks }),
        (9, glass.clone()),
        (10, Bsdf::Diffuse { albedo: KD }),
        (11, Bsdf::Diffuse { albedo: KD }),
    ];
    for (i, want) in expect {
        assert_eq!(bsdf(&s, &format!("m{i}")), want, "illum {i}");
    }
    // One warning for the shadow matte, one for the model that does not exist; none for Ka.
    let notes = s.notes.join("\n");
    assert!(notes.contains("'m10': illum 10 (shadow matte)"), "{notes}");
    assert!(notes.contains("'m11': illum 11 is not a model"), "{notes}");
    assert!(!notes.contains("Ka"), "{notes}");
}

#[test]
fn illum_2_without_specular_is_lambertian_and_defaults_follow_the_table() {
    let s = load_library(
        "defaults",
        "newmtl black_ks\nKd 0.6 0.3 0.2\nKs 0 0 0\nNs 500\nillum 2\n\
         newmtl no_ks\nKd 0.6 0.3 0.2\nillum 2\n\
         newmtl no_illum\nKd 0.6 0.3 0.2\nKs 0.2\n\
         newmtl mirror_no_ks\nillum 5\n\
         newmtl glass_no_ni\nillum 7\n\
         newmtl glass_bad_ni\nNi 0\nillum 4\n",
    );
    assert_eq!(bsdf(&s, "black_ks"), Bsdf::Diffuse { albedo: KD });
    assert_eq!(bsdf(&s, "no_ks"), Bsdf::Diffuse { albedo: KD });
    // No illum: the model with both Kd and Ks.
    assert_eq!(bsdf(&s, "no_illum"), Bsdf::Phong { diffuse: KD, specular: Vec3::splat(0.2), shininess: 0.0 });
    assert_eq!(bsdf(&s, "mirror_no_ks"), Bsdf::Mirror { reflectance: Vec3::ONE });
    let clear = Bsdf::Glass { reflectance: Vec3::ONE, transmittance: Vec3::ONE, roughness: 0.0, ior: 1.5 };
    assert_eq!(bsdf(&s, "glass_no_ni"), clear);
    assert_eq!(bsdf(&s, "glass_bad_ni"), clear);
    assert!(s.notes.iter().any(|n| n.contains("'glass_bad_ni': glass with Ni 0")), "{:?}", s.notes);
}

/// The glossy model's parameters: alpha = sqrt(2 / (Ns + 2)) and Kd scaled down (keeping
/// its hue) where Kd + Ks exceeds 1.
#[test]
fn glossy_roughness_and_energy_rule() {
    let s = load_library("glossy", "newmtl g\nKd 0.9 0.45 0.3\nKs 0.4 0.2 0.2\nNs 48\nillum 2\n");
    let Model::Glossy(g) = Model::new(&bsdf(&s, "g")) else { panic!("not glossy") };
    assert!((g.alpha - 0.2).abs() < 1e-6, "Ns 48: alpha sqrt(2/50) = 0.2, got {}", g.alpha);
    assert_eq!(g.specular, vec3(0.4, 0.2, 0.2));
    // Red overflows: 0.9 + 0.4 > 1, so Kd is scaled by 0.6 / 0.9.
    assert!((g.diffuse - vec3(0.6, 0.3, 0.2)).abs().max_element() < 1e-6, "{}", g.diffuse);
    // Within the budget nothing changes; Ks above 1 is clamped.
    assert_eq!(Glossy::phong(KD, Vec3::splat(0.3), 0.0).diffuse, KD);
    assert_eq!(Glossy::phong(Vec3::ZERO, Vec3::splat(2.0), 0.0).specular, Vec3::ONE);
    assert!((Glossy::phong(KD, Vec3::ONE, 1000.0).alpha - (2.0f32 / 1002.0).sqrt()).abs() < 1e-7);
}

/// Blender's PBR extension: Pr and Pm make glTF's metallic-roughness model (base Kd) whatever
/// the reflective illumination model; glass models stay glass.
#[test]
fn pbr_keys_make_metallic_roughness() {
    let s = load_library(
        "pbr",
        "newmtl metal\nKd 0.8 0.7 0.2\nKs 0.5\nNs 250\nPr 0.3\nPm 0.9\nillum 3\n\
         newmtl rough_only\nKd 0.5\nPr 0.7\nillum 2\n\
         newmtl metal_only\nKd 0.5\nNs 48\nPm 1\nillum 2\n\
         newmtl pbr_glass\nKd 0.5\nPr 0.2\nPm 0\nNi 1.45\nillum 7\n",
    );
    assert_eq!(bsdf(&s, "metal"), Bsdf::MetallicRoughness { base: vec3(0.8, 0.7, 0.2), metallic: 0.9, roughness: 0.3 });
    assert_eq!(
        bsdf(&s, "rough_only"),
        Bsdf::MetallicRoughness { base: Vec3::splat(0.5), metallic: 0.0, roughness: 0.7 }
    );
    // Without Pr the roughness is the one Ns gives: alpha 0.2 from Ns 48, roughness sqrt(0.2).
    let Bsdf::MetallicRoughness { metallic, roughness, .. } = bsdf(&s, "metal_only") else { panic!() };
    assert_eq!(metallic, 1.0);
    assert!((roughness - 0.2f32.sqrt()).abs() < 1e-6, "{roughness}");
    assert!(matches!(bsdf(&s, "pbr_glass"), Bsdf::Glass { ior: 1.45, .. }));
}

fn write_grey_png(path: &Path, w: u32, h: u32, value: impl Fn(u32, u32) -> u8) {
    let img = image::GrayImage::from_fn(w, h, |x, y| image::Luma([value(x, y)]));
    img.save(path).unwrap();
}

/// map_Pr and map_Pm become one metallic-roughness texture (green roughness, blue
/// metalness, linear values), looked up where the mesh's uv points; a channel without a map
/// keeps its constant.
#[test]
fn pbr_maps_become_the_metallic_roughness_texture() {
    let d = temp_dir("mtl-pbr-maps");
    // Roughness: left half 51 (0.2), right half 204 (0.8); metalness 2x1: 0 and 255.
    write_grey_png(&d.join("r.png"), 4, 2, |x, _| if x < 2 { 51 } else { 204 });
    write_grey_png(&d.join("m.png"), 2, 1, |x, _| if x == 0 { 0 } else { 255 });
    let mtl = "newmtl both\nKd 0.5\nPr 0.5\nPm 0.5\nmap_Pr r.png\nmap_Pm -bm 1 m.png\n\
               newmtl rough_map\nKd 0.5\nPm 0.25\nmap_Pr r.png\n";
    std::fs::write(d.join("m.mtl"), mtl).unwrap();
    std::fs::write(
        d.join("a.obj"),
        format!("mtllib m.mtl\n{QUAD}usemtl both\nf 1/1 2/2 3/3\nusemtl rough_map\nf 1/1 3/3 4/4\n"),
    )
    .unwrap();
    let s = load(&d.join("a.obj"), &LoadOptions::default()).unwrap();
    let t = crate::scene::Textures::new(&s);
    let both = s.materials.iter().position(|m| m.name == "both").unwrap();
    let rough = s.materials.iter().position(|m| m.name == "rough_map").unwrap();
    let near = |a: Vec2, b: Vec2| (a - b).abs().max_element() < 1e-6;
    // (metalness, roughness) at texel centres; OBJ's v is up, the image's rows go down.
    let at = |m: usize, u: f32| t.metal_rough(m, Vec2::new(u, 0.25)).expect("a metallic-roughness texture");
    assert!(near(at(both, 0.125), Vec2::new(0.0, 0.2)), "{}", at(both, 0.125));
    assert!(near(at(both, 0.875), Vec2::new(1.0, 0.8)), "{}", at(both, 0.875));
    assert!(near(at(rough, 0.125), Vec2::new(0.25, 0.2)), "{}", at(rough, 0.125));
    assert!(near(at(rough, 0.875), Vec2::new(0.25, 0.8)), "{}", at(rough, 0.875));
}

/// Keys not read are named once per file in one warning; map_Ks and map_Ns are read but not
/// applied, with one warning naming them.
#[test]
fn keys_not_read_are_named_once() {
    let s = load_library(
        "ignored",
        "newmtl a\nKd 0.5\nPs 0.1\nPc 0.2\nPcr 0.3\naniso 0.4\nmap_Ks s.png\nsharpness 60\n\
         newmtl b\nKd 0.5\nPs 0.5\naniso 0.1\nmap_Ns n.png\nmap_Ks s.png\n",
    );
    let lines: Vec<&String> = s.notes.iter().filter(|n| n.contains("keys not read")).collect();
    assert_eq!(lines.len(), 1, "{:?}", s.notes);
    assert!(lines[0].ends_with("keys not read: aniso, sharpness"), "{}", lines[0]);
    assert!(lines[0].contains("m.mtl"), "{}", lines[0]);
    let maps: Vec<&String> = s.notes.iter().filter(|n| n.contains("map_Ks, map_Ns not applied")).collect();
    assert_eq!(maps.len(), 1, "{:?}", s.notes);
    assert!(maps[0].contains("map_Ks, map_Ns not applied"), "{}", maps[0]);
    // A file that uses only keys this reader knows gets no warning.
    let clean = load_library("clean", &block("x", 2));
    assert!(clean.notes.is_empty(), "{:?}", clean.notes);
}

/// The PBR extension's clearcoat and sheen (`Pc`, `Pcr`, `Ps`) become the layers of the
/// metallic-roughness model, as glTF's clearcoat and sheen extensions; on a model without a
/// metallic-roughness base they are named in a warning and not applied.
#[test]
fn pbr_clearcoat_and_sheen_become_layers() {
    let s = load_library(
        "layers",
        "newmtl coat\nKd 0.5\nPr 0.4\nPm 0.1\nPc 0.8\nPcr 0.2\nnewmtl sheen\nKd 0.5\nPr 0.6\nPs 0.3\n\
         newmtl plain\nKd 0.5\nPr 0.6\nnewmtl lambert\nKd 0.5\nPc 0.5\n",
    );
    let coat = material(&s, "coat").layers.as_deref().expect("clearcoat layer");
    assert_eq!((coat.clearcoat, coat.clearcoat_roughness), (0.8, 0.2));
    assert_eq!(coat.sheen_color, Vec3::ZERO);
    let sheen = material(&s, "sheen").layers.as_deref().expect("sheen layer");
    assert_eq!((sheen.sheen_color, sheen.clearcoat), (Vec3::splat(0.3), 0.0));
    assert!(sheen.sheen_roughness > 0.0);
    assert!(material(&s, "plain").layers.is_none());
    assert!(material(&s, "lambert").layers.is_none());
    assert!(s.notes.iter().any(|n| n.contains("'lambert'") && n.contains("not applied")), "{:?}", s.notes);
}

#[test]
fn malformed_values_are_errors_naming_the_file_and_line() {
    let d = temp_dir("mtl-bad");
    std::fs::write(d.join("m.mtl"), "newmtl a\nKd 0.5\nNs lots\n").unwrap();
    std::fs::write(d.join("a.obj"), format!("mtllib m.mtl\n{QUAD}usemtl a\nf 1 2 3\n")).unwrap();
    let e = format!("{:#}", load(&d.join("a.obj"), &LoadOptions::default()).unwrap_err());
    assert!(e.contains("m.mtl") && e.contains("line 3") && e.contains("Ns 'lots'") && !e.contains('\n'), "{e}");
}

/// The Cornell boxes of the shared scenes: CornellBox-Sphere's mirror (illum 5, Ks 0.95) and
/// glass (illum 7, Ni 2.5, Tf 0.1) spheres; CornellBox-Glossy's glossy sphere and floor.
#[test]
fn cornell_boxes_get_their_mirror_glass_and_glossy_materials() {
    let Some(s) = crate::tests::common::load_scene("obj/CornellBox/CornellBox-Sphere.obj") else { return };
    assert_eq!(bsdf(&s, "leftSphere"), Bsdf::Mirror { reflectance: Vec3::splat(0.95) });
    assert_eq!(
        bsdf(&s, "rightSphere"),
        Bsdf::Glass { reflectance: Vec3::ONE, transmittance: Vec3::splat(0.1), roughness: 0.0, ior: 2.5 }
    );
    assert_eq!(bsdf(&s, "floor"), Bsdf::Diffuse { albedo: vec3(0.725, 0.71, 0.68) });
    let Some(g) = crate::tests::common::load_scene("obj/CornellBox/CornellBox-Glossy.obj") else { return };
    assert_eq!(
        bsdf(&g, "sphere"),
        Bsdf::Phong { diffuse: vec3(0.486, 0.631, 0.663), specular: Vec3::splat(0.7), shininess: 32.0 }
    );
    assert_eq!(
        bsdf(&g, "floor"),
        Bsdf::Phong { diffuse: vec3(0.725, 0.71, 0.68), specular: Vec3::splat(0.3), shininess: 80.0 }
    );
}
