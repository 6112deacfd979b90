//! Albedo textures in real renders: under a uniform white environment a convex diffuse
//! object reflects exactly its albedo (cosine-sampled constant light: f cos / pdf x L =
//! albedo), so every pixel on it must equal the texture's colour at that point. The
//! expected colours come from the image decoded here on its own and a local bilinear filter.

use crate::accel::{BruteForce, Intersector, TraceCounters};
use crate::load::{LoadOptions, load};
use crate::scene::texture::{Filter, Wrap};
use crate::scene::{Bsdf, Environment, Scene};
use crate::settings::{Settings, Shading};
use crate::tests::common;
use glam::{Vec2, Vec3};

const W: usize = 64;
const H: usize = 48;

/// An image as linear RGB rows (top first), decoded independently of the renderer.
struct Img {
    w: usize,
    h: usize,
    px: Vec<Vec3>,
}

fn srgb(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

impl Img {
    fn from_rgba(w: usize, h: usize, bytes: &[u8], channels: usize) -> Img {
        let px = bytes.chunks_exact(channels).map(|p| Vec3::new(srgb(p[0]), srgb(p[1]), srgb(p[2]))).collect();
        Img { w, h, px }
    }

    /// Bilinear between texel centres, repeat wrap; (s, t) with t down from the top row.
    fn bilinear(&self, s: f32, t: f32) -> Vec3 {
        let (x, y) = (s * self.w as f32 - 0.5, t * self.h as f32 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let at = |i: i64, j: i64| {
            self.px[j.rem_euclid(self.h as i64) as usize * self.w + i.rem_euclid(self.w as i64) as usize]
        };
        let (i, j) = (x0 as i64, y0 as i64);
        let top = at(i, j) * (1.0 - fx) + at(i + 1, j) * fx;
        let bot = at(i, j + 1) * (1.0 - fx) + at(i + 1, j + 1) * fx;
        top * (1.0 - fy) + bot * fy
    }
}

/// Renders `scene` lit only by a white constant environment, direct light, one sample at
/// each pixel centre. Materials become Lambertian with their base colour: what is tested
/// here is where the texture is looked up (glTF's specular layer has tests of its own).
fn render_white_furnace(scene: &mut Scene) -> crate::film::Film {
    for m in &mut scene.materials {
        m.bsdf = Bsdf::Diffuse { albedo: m.bsdf.diffuse_albedo() };
    }
    scene.lights.clear();
    scene.env = Environment::Constant(Vec3::ONE);
    scene.camera.fit_aspect(W as f32 / H as f32);
    let mut s = Settings::default();
    s.image.width = W;
    s.image.height = H;
    s.paths.max_depth = 1;
    s.paths.shading = Shading::Direct;
    let (film, _) = crate::render::render(scene, &BruteForce::new(scene), &s).unwrap();
    film
}

fn pixel_ray(scene: &Scene, x: usize, y: usize) -> crate::geometry::Ray {
    scene.camera.generate_ray((x as f32 + 0.5) / W as f32, (y as f32 + 0.5) / H as f32)
}

/// tex_cube.obj (no usemtl: its one material applies) under white light: on the face
/// z = +10, the file's uvs are u = (10 - x) / 20, v = (y + 10) / 20, and OBJ's v points up.
#[test]
fn tex_cube_shows_its_texture() {
    let path = common::scene("obj/tex_cube/tex_cube.obj").expect("WAVEPATH_SCENES must point at the scenes");
    let mut scene = load(&path, &LoadOptions::default()).unwrap();
    assert!(crate::effects::Effects::of(&scene, &Settings::default()).textures);
    assert!(!crate::effects::Effects::of(&crate::load::default_scene(), &Settings::default()).textures);
    let t = scene.materials[0].albedo_texture.as_ref().expect("map_Kd is loaded");
    assert_eq!((t.wrap, t.filter), ([Wrap::Repeat; 2], Filter::Linear));
    let png = image::open(path.with_file_name("tatsy_logo.png")).unwrap().into_rgb8();
    let img = Img::from_rgba(png.width() as usize, png.height() as usize, png.as_raw(), 3);
    let film = render_white_furnace(&mut scene);
    let (mut checked, mut light, mut dark) = (0, 0, 0);
    for y in 0..H {
        for x in 0..W {
            let r = pixel_ray(&scene, x, y);
            let t = (10.0 - r.origin.z) / r.dir.z;
            let p = r.origin + t * r.dir;
            // The front face, away from its edges (the camera is above it: nothing is in front).
            if t <= 0.0 || p.x.abs() > 9.5 || p.y.abs() > 9.5 {
                continue;
            }
            let (u, v) = ((10.0 - p.x) / 20.0, (p.y + 10.0) / 20.0);
            let want = img.bilinear(u, 1.0 - v);
            let got = film.get(x, y);
            assert!((got - want).abs().max_element() < 2e-3, "pixel ({x},{y}) uv ({u},{v}): {got} vs texture {want}");
            checked += 1;
            if want.min_element() > 0.8 {
                light += 1;
            } else if want.z > 2.0 * want.x {
                dark += 1;
            }
        }
    }
    // Enough of the face, with both the white letters and the blue ground.
    assert!(checked > 500 && light > 30 && dark > 300, "checked {checked}, white {light}, blue {dark}");
}

/// BoxTextured.glb (embedded PNG, sampler LINEAR / REPEAT): every pixel on the box equals the
/// image at the hit's interpolated uv (glTF: v down from the top row).
#[test]
fn box_textured_shows_its_embedded_texture() {
    let path = common::scene("gltf/BoxTextured.glb").expect("WAVEPATH_SCENES must point at the scenes");
    let mut scene = load(&path, &LoadOptions::default()).unwrap();
    let tex = scene.materials.iter().find_map(|m| m.albedo_texture.clone()).expect("a textured material");
    assert!(tex.image.is_some(), "embedded image decoded");
    assert_eq!((tex.wrap, tex.filter, tex.flip_v), ([Wrap::Repeat; 2], Filter::Linear, false));
    let (_, _, images) = gltf::import(&path).unwrap();
    let d = &images[0];
    let channels = d.pixels.len() / (d.width * d.height) as usize;
    let img = Img::from_rgba(d.width as usize, d.height as usize, &d.pixels, channels);
    let film = render_white_furnace(&mut scene);
    let accel = BruteForce::new(&scene);
    let mut checked = 0;
    let mut colours = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let r = pixel_ray(&scene, x, y);
            let Some(hit) = accel.closest_hit(&r, &mut TraceCounters::default()) else { continue };
            // Away from triangle edges, where a pixel centre could fall on either side.
            if hit.u < 0.02 || hit.v < 0.02 || hit.u + hit.v > 0.98 {
                continue;
            }
            let uv: Vec2 = scene.surface_point(&r, &hit).uv;
            let want = tex.factor * img.bilinear(uv.x, uv.y);
            let got = film.get(x, y);
            assert!((got - want).abs().max_element() < 2e-3, "pixel ({x},{y}) uv {uv}: {got} vs texture {want}");
            checked += 1;
            colours.push(want);
        }
    }
    let spread = colours.iter().fold(Vec3::ZERO, |a, c| a.max(*c)) - colours.iter().fold(Vec3::ONE, |a, c| a.min(*c));
    assert!(checked > 300 && spread.max_element() > 0.5, "checked {checked}, colour spread {spread}");
}

/// The uvs are freed only when no material has a decoded map of any kind: each map alone,
/// decoded, keeps them; the same map not decoded (a file that could not be read) does not.
#[test]
fn every_kind_of_map_keeps_the_uvs_it_is_read_through() {
    use crate::scene::alpha::AlphaMap;
    use crate::scene::texture::TextureImage;
    use crate::scene::{Layers, Material, Mesh, Relief, ReliefMap, SpecularGlossinessMap};
    use std::sync::Arc;
    let image = Arc::new(TextureImage { width: 1, height: 1, texels: vec![Vec3::ONE] });
    let texture = |decoded: bool| {
        let mut t = crate::scene::Texture::obj("t.png".into());
        t.image = decoded.then(|| image.clone());
        t
    };
    type Give = fn(&mut Material, crate::scene::Texture);
    let kinds: [(&str, Give); 8] = [
        ("albedo", |m, t| m.albedo_texture = Some(t)),
        ("emission", |m, t| m.emission_texture = Some(t)),
        ("metallic-roughness", |m, t| m.metallic_roughness_texture = Some(t)),
        ("normal", |m, t| m.relief = Some(ReliefMap { texture: t, relief: Relief::Normal { scale: 1.0 } })),
        ("height", |m, t| m.relief = Some(ReliefMap { texture: t, relief: Relief::Height { bm: 1.0 } })),
        ("specular-glossiness", |m, t| {
            m.specular_glossiness_texture = Some(Box::new(SpecularGlossinessMap { specular: t.clone(), glossiness: t }))
        }),
        ("transmission", |m, t| {
            m.layers = Some(Box::new(Layers { transmission: 1.0, transmission_texture: Some(t), ..Layers::default() }))
        }),
        ("alpha", |m, t| {
            let mut a = AlphaMap::obj("a.png".into());
            if t.image.is_some() {
                a.image = Some(Arc::new(crate::scene::alpha::AlphaImage { width: 1, height: 1, texels: vec![1.0] }));
            }
            m.alpha.map = Some(a);
        }),
    ];
    let mesh = Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        uvs: Some(vec![Vec2::ZERO, Vec2::X, Vec2::Y]),
        triangles: vec![[0, 1, 2]],
        material_ids: crate::scene::MaterialIds::uniform(1, 1),
        ..Mesh::default()
    };
    for (kind, give) in kinds {
        for decoded in [true, false] {
            let mut m = Material::diffuse("m", Vec3::splat(0.5));
            give(&mut m, texture(decoded));
            assert_eq!(m.maps().len(), if kind == "specular-glossiness" { 2 } else { 1 }, "{kind}");
            let mut s = Scene { mesh: mesh.clone(), materials: vec![Material::default(), m], ..Scene::default() };
            s.drop_unused_uvs();
            assert_eq!(s.mesh.uvs.is_some(), decoded, "a {kind} map, decoded: {decoded}");
        }
    }
}
