//! Alpha as the files state it: glTF `alphaMode` (`OPAQUE` ignores alpha, `MASK` with
//! `alphaCutoff` or its default 0.5, `BLEND`) over the base colour's alpha (factor x the
//! texture's alpha channel), and MTL `d`, `Tr` and `map_d` as `load/obj/dissolve.rs`
//! documents them, on small files written here.

use crate::accel::cutout::Cutouts;
use crate::load::{LoadOptions, load};
use crate::scene::texture::Filter;
use crate::scene::{Alpha, AlphaMode, Material, Scene};
use crate::tests::common::cutout::{png_uri, square_doc, textured};
use crate::tests::common::temp_dir;
use glam::vec2;
use std::path::Path;

fn load_ok(path: &Path) -> Scene {
    load(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e:#}"))
}

fn by_name<'a>(s: &'a Scene, name: &str) -> &'a Material {
    s.materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material {name}"))
}

/// 2 x 2 texels of alpha 0, 64, 128, 255 (rows top first).
const ALPHAS: [u8; 4] = [0, 64, 128, 255];

/// An OBJ reading `m.mtl` with one textured triangle per material of `names`, in order.
fn triangle_per_material(names: &[&str]) -> String {
    let mut obj = String::from("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n");
    for n in names {
        obj.push_str(&format!("usemtl {n}\nf 1/1 2/2 3/3\n"));
    }
    obj
}

/// The centre of texel (x, y) of a 2 x 2 image in glTF's frame (v down).
fn centre(x: usize, y: usize) -> glam::Vec2 {
    vec2(0.25 + 0.5 * x as f32, 0.25 + 0.5 * y as f32)
}

#[test]
fn gltf_alpha_modes_read_the_base_colours_alpha() {
    let d = temp_dir("cutouts-gltf");
    let tex = r#""baseColorTexture":{"index":0}"#;
    let materials = [
        format!(
            r#"{{"name":"mask","alphaMode":"MASK","alphaCutoff":0.3,"pbrMetallicRoughness":{{{tex},"baseColorFactor":[1,1,1,0.8]}}}}"#
        ),
        format!(r#"{{"name":"mask-default","alphaMode":"MASK","pbrMetallicRoughness":{{{tex}}}}}"#),
        format!(
            r#"{{"name":"blend","alphaMode":"BLEND","pbrMetallicRoughness":{{{tex},"baseColorFactor":[1,1,1,0.5]}}}}"#
        ),
        format!(r#"{{"name":"opaque","pbrMetallicRoughness":{{{tex},"baseColorFactor":[1,1,1,0.1]}}}}"#),
        r#"{"name":"factor-only","alphaMode":"BLEND","pbrMetallicRoughness":{"baseColorFactor":[1,1,1,0.25]}}"#.into(),
        format!(r#"{{"name":"glowing","alphaMode":"MASK","emissiveFactor":[1,1,1],"pbrMetallicRoughness":{{{tex}}}}}"#),
    ];
    let doc = square_doc(1.0, 3.0, 0.5, &textured(&materials.join(","), &png_uri(2, 2, Some(&ALPHAS), [255; 3])));
    std::fs::write(d.join("a.gltf"), doc).unwrap();
    let s = load_ok(&d.join("a.gltf"));
    let texel = |k: usize| ALPHAS[k] as f32 / 255.0;

    let m = by_name(&s, "mask");
    assert_eq!((m.alpha.mode, m.alpha.factor), (AlphaMode::Mask { cutoff: 0.3 }, 0.8));
    let map = m.alpha.map.as_ref().expect("the base colour texture's alpha");
    assert_eq!(map.filter, Filter::Nearest, "the texture's sampler");
    let img = map.image.as_ref().expect("decoded");
    assert_eq!((img.width, img.height), (2, 2));
    for (k, &a) in img.texels.iter().enumerate() {
        assert_eq!(a, texel(k), "texel {k}");
        let cov = m.alpha.coverage(centre(k % 2, k / 2));
        assert_eq!(cov, 0.8 * texel(k), "coverage over texel {k}");
        // Cut where 0.8 x alpha < 0.3: the texels of alpha 0 and 64.
        assert_eq!(m.alpha.keeps(cov, 0.0), k >= 2, "texel {k}");
    }
    assert_eq!(by_name(&s, "mask-default").alpha.mode, AlphaMode::Mask { cutoff: 0.5 });
    let b = &by_name(&s, "blend").alpha;
    assert_eq!((b.mode, b.factor), (AlphaMode::Blend, 0.5));
    assert_eq!(b.coverage(centre(0, 1)), 0.5 * texel(2));
    // OPAQUE: alpha ignored, whatever the factor and texture say.
    assert_eq!(by_name(&s, "opaque").alpha, Alpha::OPAQUE);
    let f = &by_name(&s, "factor-only").alpha;
    assert_eq!((f.mode, f.factor, f.map.is_none()), (AlphaMode::Blend, 0.25, true));
    assert!(!f.is_opaque());
    // An emitter keeps its alpha as read, is not cut, and says so.
    assert!(!by_name(&s, "glowing").alpha.is_opaque());
    let mut only_emitter = s.clone();
    for m in &mut only_emitter.materials {
        if m.name != "glowing" {
            m.alpha = Alpha::OPAQUE;
        }
    }
    assert!(Cutouts::of(&only_emitter).is_none());
    assert!(s.notes.iter().any(|n| n.contains("glowing") && n.contains("not cut")), "{:?}", s.notes);

    // A base colour image without an alpha channel: nothing to cut but the factor.
    let doc = square_doc(1.0, 3.0, 0.5, &textured(&materials[0], &png_uri(2, 2, None, [200; 3])));
    std::fs::write(d.join("rgb.gltf"), doc).unwrap();
    let s = load_ok(&d.join("rgb.gltf"));
    let a = &s.materials[0].alpha;
    assert_eq!((a.mode, a.factor, a.map.is_none()), (AlphaMode::Mask { cutoff: 0.3 }, 0.8, true));
    assert!(a.is_opaque(), "0.8 passes the cutoff everywhere");
}

fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) {
    if let Some(parent) = dir.join(name).parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(dir.join(name), contents).unwrap();
}

fn png_file(dir: &Path, name: &str, uri: &str) {
    use base64::Engine;
    let b64 = uri.split_once(',').unwrap().1;
    write(dir, name, base64::engine::general_purpose::STANDARD.decode(b64).unwrap());
}

#[test]
fn mtl_d_tr_and_map_d_become_blend_and_mask() {
    let d = temp_dir("cutouts-mtl");
    png_file(&d, "tex/cut.png", &png_uri(2, 2, Some(&ALPHAS), [255; 3]));
    png_file(&d, "grey.png", &png_uri(2, 2, None, [51; 3]));
    let mtl = "newmtl d\nd 0.4\n\
               newmtl tr\nTr 0.25\n\
               newmtl both\nd 0.6\nTr 0.9\n\
               newmtl halo\nd -halo 0.7\n\
               newmtl cut\nKd 1 1 1\nmap_d -bm 1 -imfchan m .\\tex\\cut.png\n\
               newmtl grey\nd 0.5\nmap_d grey.png\n\
               newmtl glass\nillum 7\nd 0.5\nNi 1.5\n\
               newmtl solid\nd 1\nTr 0\n\
               newmtl gone\nd 0\n";
    write(&d, "m.mtl", mtl);
    let names = ["d", "tr", "both", "halo", "cut", "grey", "glass", "solid", "gone"];
    write(&d, "a.obj", triangle_per_material(&names));
    let s = load_ok(&d.join("a.obj"));
    let alpha = |n: &str| by_name(&s, n).alpha.clone();
    let blend = |f: f32| Alpha { mode: AlphaMode::Blend, factor: f, map: None };
    assert_eq!(alpha("d"), blend(0.4));
    assert_eq!(alpha("tr"), blend(0.75));
    assert_eq!(alpha("both"), blend(0.6), "d wins over Tr");
    assert_eq!(alpha("halo"), blend(0.7));
    assert_eq!(alpha("glass"), Alpha::OPAQUE, "a dielectric's d is its own transparency");
    assert_eq!(alpha("solid"), Alpha::OPAQUE);
    // Wholly dissolved: drawn, with a warning (`mtl_keys_that_would_draw_nothing_are_read_as_meant`).
    assert_eq!(alpha("gone"), Alpha::OPAQUE);
    assert!(s.notes.iter().any(|n| n.contains("'gone'") && n.contains("d 0")), "{:?}", s.notes);
    // map_d after options, on a Windows path: a mask at 0.5 of the image's alpha channel,
    // v up (OBJ): uv (0.25, 0.75) is the top-left texel.
    let cut = alpha("cut");
    assert_eq!((cut.mode, cut.factor), (AlphaMode::Mask { cutoff: 0.5 }, 1.0));
    let img = cut.map.as_ref().and_then(|m| m.image.clone()).expect("tex/cut.png decoded");
    assert_eq!(img.texels, ALPHAS.map(|a| a as f32 / 255.0).to_vec());
    assert_eq!(cut.coverage(vec2(0.25, 0.75)), 0.0);
    assert_eq!(cut.coverage(vec2(0.75, 0.25)), 1.0);
    // Without an alpha channel, the luminance; times d.
    let grey = alpha("grey");
    assert_eq!(grey.mode, AlphaMode::Mask { cutoff: 0.5 });
    assert!((grey.coverage(vec2(0.5, 0.5)) - 0.5 * 0.2).abs() < 1e-6, "{grey:?}");
    // The uvs the maps read are kept.
    let mut s2 = s.clone();
    s2.drop_unused_uvs();
    assert!(s2.mesh.uvs.is_some());
}

/// MTL keys that would leave a material wholly invisible (opacity 0) are read as their authors
/// meant, as `load/obj/dissolve.rs` says: MeshLab's `Tr 1` on an opaque material (trimesh's
/// `fuze.obj`, `capsule.obj`) is an opacity of 1, and `d 0` is drawn opaque too, each with a
/// warning naming the library, the material and the key; a map keeps cutting. Values that
/// draw something keep their meaning, and a dielectric's `Tr` stays unread.
#[test]
fn mtl_keys_that_would_draw_nothing_are_read_as_meant() {
    use crate::accel::BruteForce;
    use crate::render::render_normals;
    use crate::scene::Camera;
    use glam::{Vec3, vec3};
    let d = temp_dir("cutouts-mtl-invisible");
    png_file(&d, "cut.png", &png_uri(2, 2, Some(&ALPHAS), [255; 3]));
    let mtl = "# Converted by Meshlab Group\n\
               newmtl\tmeshlab\t\t\nKa 0.2 0.2 0.2\nKd 1 1 1\nKs 1 1 1\nTr 1.000000\nillum 2\nNs 0\n\
               newmtl dissolved\nKd 0.5 0.5 0.5\nd 0\n\
               newmtl both\nd 0.000000\nTr 1.000000\n\
               newmtl tr-cut\nTr 1\nmap_d cut.png\n\
               newmtl d-cut\nd 0\nmap_d cut.png\n\
               newmtl d-wins\nd 1\nTr 1\n\
               newmtl mostly\nTr 0.9\n\
               newmtl glass\nillum 7\nTr 1\nNi 1.5\n";
    write(&d, "m.mtl", mtl);
    let names = ["meshlab", "dissolved", "both", "tr-cut", "d-cut", "d-wins", "mostly", "glass"];
    write(&d, "a.obj", triangle_per_material(&names));
    let s = load_ok(&d.join("a.obj"));
    let alpha = |n: &str| by_name(&s, n).alpha.clone();
    let warned = |name: &str, key: &str| {
        s.notes.iter().any(|n| {
            n.starts_with("warning: ") && n.contains("m.mtl") && n.contains(&format!("'{name}'")) && n.contains(key)
        })
    };
    assert_eq!(alpha("meshlab"), Alpha::OPAQUE, "MeshLab's Tr 1 is an opacity");
    assert!(warned("meshlab", "Tr 1"), "{:?}", s.notes);
    assert_eq!(alpha("dissolved"), Alpha::OPAQUE);
    assert!(warned("dissolved", "d 0"), "{:?}", s.notes);
    assert_eq!(alpha("both"), Alpha::OPAQUE);
    assert!(warned("both", "d 0"), "d is the key read when both are given: {:?}", s.notes);
    for name in ["tr-cut", "d-cut"] {
        let a = alpha(name);
        assert_eq!((a.mode, a.factor), (AlphaMode::Mask { cutoff: 0.5 }, 1.0), "{name}: the map alone cuts");
        assert_eq!(a.coverage(vec2(0.75, 0.25)), 1.0, "{name}");
        assert_eq!(a.coverage(vec2(0.25, 0.75)), 0.0, "{name}");
    }
    assert!(warned("tr-cut", "Tr 1") && warned("d-cut", "d 0"), "{:?}", s.notes);
    assert_eq!(alpha("d-wins"), Alpha::OPAQUE);
    assert_eq!(alpha("mostly"), Alpha { mode: AlphaMode::Blend, factor: 1.0 - 0.9, map: None });
    assert_eq!(alpha("glass"), Alpha::OPAQUE);
    for quiet in ["d-wins", "mostly", "glass"] {
        assert!(!s.notes.iter().any(|n| n.contains(&format!("'{quiet}'"))), "{quiet}: {:?}", s.notes);
    }

    // The file as MeshLab writes it renders its object: every pixel on the square sees it.
    write(&d, "q.mtl", "newmtl\tm\t\t\nKd 1 1 1\nTr 1.000000\nillum 2\n");
    write(&d, "q.obj", "mtllib q.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl m\nf 1 2 3 4\n");
    let mut q = load_ok(&d.join("q.obj"));
    q.camera = Camera::look_at(vec3(0.5, 0.5, 2.0), vec3(0.5, 0.5, 0.0), Vec3::Y, 10.0, 1.0);
    let (film, _) =
        render_normals(&q, &q.camera, &BruteForce::new(&q), &crate::tests::common::render::settings(8, 8, 1, 1));
    assert!(film.pixels.iter().all(|p| (*p - vec3(0.5, 0.5, 1.0)).abs().max_element() < 1e-5), "{:?}", film.pixels);
}
