//! What a CS184 user compares against: the reference renderer's framing at every `-r`, its
//! normal view and 8-bit bytes, its biased area-light pdf on request; and the cameras that
//! files without the reference's conventions get (automatic framing, widened clips).

use crate::common::meshgen::icosphere;
use crate::common::{self, render, run_wavepath, temp_dir};
use glam::{DVec3, Vec3, vec3};
use std::path::Path;
use wavepath::BruteForce;
use wavepath::{Camera, FovFit, Light, Material, Mesh, Scene};
use wavepath::{Film, Tonemap, write_image};
use wavepath::{LoadOptions, load};
use wavepath::{Settings, Shading};

// ---------------------------------------------------------------------------------------
// The reference's camera, computed here from the file's own numbers
// ---------------------------------------------------------------------------------------

/// The camera numbers of a CS184 file, read with a plain XML parser: the last camera node's
/// row-major matrix, its optics and the up axis.
struct FileCamera {
    matrix: [f64; 16],
    xfov: f64,
    aspect: f64,
    z_up: bool,
}

fn file_camera(path: &Path) -> FileCamera {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let named = |n: &roxmltree::Node, tag: &str| n.tag_name().name() == tag;
    let z_up =
        doc.descendants().find(|n| named(n, "up_axis")).and_then(|n| n.text()).is_some_and(|t| t.trim() == "Z_UP");
    let node = doc
        .descendants()
        .rfind(|n| named(n, "node") && n.children().any(|c| named(&c, "instance_camera")))
        .expect("a camera node");
    let numbers =
        |n: roxmltree::Node| -> Vec<f64> { n.text().unwrap().split_whitespace().map(|t| t.parse().unwrap()).collect() };
    let m = numbers(node.children().find(|c| named(c, "matrix")).unwrap());
    let url = node.children().find(|c| named(c, "instance_camera")).unwrap().attribute("url").unwrap();
    let cam = doc.descendants().find(|n| named(n, "camera") && n.attribute("id") == Some(&url[1..])).unwrap();
    let value = |tag: &str| numbers(cam.descendants().find(|n| named(n, tag)).unwrap())[0];
    FileCamera { matrix: m.try_into().unwrap(), xfov: value("xfov"), aspect: value("aspect_ratio"), z_up }
}

/// The pixel rectangle `[x0, x1] x [y0, y1]` (bottom-left origin) whose pixel centres the
/// reference's camera sees inside the projection of `points`, for a `w x h` picture:
/// COLLADA-CS184.md "Camera", steps 1 to 4, in f64.
fn predicted_bounds(fc: &FileCamera, points: &[DVec3], w: usize, h: usize) -> [i64; 4] {
    let swap = |p: DVec3| if fc.z_up { DVec3::new(-p.x, p.z, p.y) } else { p };
    let m = &fc.matrix;
    // The node matrix applied to the point (0, 0, -1), as a point.
    let ahead = DVec3::new(m[3] - m[2], m[7] - m[6], m[11] - m[10]);
    let d = swap(ahead).normalize();
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for &p in points {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let eye = 0.5 * (lo + hi) + 1.5 * (hi - lo).length() * d;
    let right = DVec3::Y.cross(d).normalize();
    let up = d.cross(right);
    let half_tan = |deg: f64| (deg.to_radians() / 2.0).tan();
    let vfov = 2.0 * (half_tan(fc.xfov) / fc.aspect).atan().to_degrees();
    let t = half_tan(vfov).max(0.75 * half_tan(fc.xfov));
    let (tan_h, tan_v) = (w as f64 * t / 600.0, h as f64 * t / 600.0);
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &p in points {
        let q = p - eye;
        let z = -q.dot(d);
        assert!(z > 0.0, "the whole scene is in front of the reference's camera");
        let sx = (q.dot(right) / z / tan_h + 1.0) / 2.0 * w as f64;
        let sy = (q.dot(up) / z / tan_v + 1.0) / 2.0 * h as f64;
        (x0, x1, y0, y1) = (x0.min(sx), x1.max(sx), y0.min(sy), y1.max(sy));
    }
    // Pixel i's centre is at i + 0.5.
    let first = |s: f64, n: usize| ((s - 0.5).ceil() as i64).clamp(0, n as i64 - 1);
    let last = |s: f64, n: usize| ((s - 0.5).floor() as i64).clamp(0, n as i64 - 1);
    [first(x0, w), last(x1, w), first(y0, h), last(y1, h)]
}

/// The pixels a normal-shading render hit (misses are black), as `[x0, x1, y0, y1]`.
fn hit_bounds(film: &Film) -> [i64; 4] {
    let mut b = [i64::MAX, i64::MIN, i64::MAX, i64::MIN];
    for y in 0..film.height {
        for x in 0..film.width {
            if film.get(x, y) != Vec3::ZERO {
                let (x, y) = (x as i64, y as i64);
                b = [b[0].min(x), b[1].max(x), b[2].min(y), b[3].max(y)];
            }
        }
    }
    b
}

fn normals_film(scene: &Scene, w: usize, h: usize) -> Film {
    let accel = wavepath::build_accel(scene, &Default::default()).0;
    let mut s = Settings::default();
    s.image.width = w;
    s.image.height = h;
    s.paths.shading = Shading::Normals;
    wavepath::render(scene, accel.as_ref(), &s).unwrap().0
}

fn all_points(scene: &Scene) -> Vec<DVec3> {
    let mut pts: Vec<DVec3> = scene.mesh.positions.iter().map(|p| p.as_dvec3()).collect();
    for s in &scene.spheres {
        pts.extend([DVec3::splat(-1.0), DVec3::splat(1.0)].map(|k| s.center.as_dvec3() + k * s.radius as f64));
    }
    pts
}

mod slow {
    use super::*;

    /// Each scene at 800x600 and 480x360: the silhouette of a normal-shading render lands on
    /// the pixel bounds the reference's rule predicts from the file's numbers (peter.dae has
    /// two cameras: the last one counts). The extreme of a projected mesh is a vertex, and a
    /// pixel centre next to a sharp tip may miss it: 2 pixels of slack.
    #[test]
    fn cs184_framing_follows_the_reference_rule_at_every_resolution() {
        let files = [
            "cs184/meshedit/beetle.dae",
            "cs184/meshedit/maxplanck.dae",
            "cs184/meshedit/peter.dae",
            "cs184/sky/CBbunny.dae",
            "cs184/reconstructed/sky/dragon.dae",
            "cs184/reconstructed/sky/CBlucy.dae",
        ];
        for rel in files {
            let Some(path) = common::scene(rel) else { return };
            let fc = file_camera(&path);
            let loaded = load(&path, &LoadOptions::default()).unwrap();
            let points = all_points(&loaded);
            for (w, h) in [(800, 600), (480, 360)] {
                let mut scene = loaded.clone();
                scene.camera.fit_to(w as f32, h as f32);
                let want = predicted_bounds(&fc, &points, w, h);
                let got = hit_bounds(&normals_film(&scene, w, h));
                let off = want.iter().zip(&got).map(|(a, b)| (a - b).abs()).max().unwrap();
                assert!(off <= 2, "{rel} at {w}x{h}: silhouette {got:?}, the reference's rule predicts {want:?}");
            }
        }
    }

    /// The binary applies the rule to `-r` exactly as the library's `fit_to` does; `--fov
    /// frame` shows the 800x600 picture's vertical field at any size.
    #[test]
    fn the_command_line_frames_as_the_rule() {
        let Some(path) = common::scene("cs184/meshedit/maxplanck.dae") else { return };
        let dir = temp_dir("cs184-fov");
        let out = dir.join("n.pfm");
        let run = |extra: &[&str]| {
            let mut args = vec![path.to_str().unwrap(), "--shading", "normals", "-r", "480", "360"];
            args.extend(extra);
            args.extend(["-f", out.to_str().unwrap()]);
            let o = run_wavepath(&args);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            read_pfm(&out)
        };
        let loaded = load(&path, &LoadOptions::default()).unwrap();
        let mut scene = loaded.clone();
        scene.camera.fit_to(480.0, 360.0);
        assert_eq!(run(&[]), normals_film(&scene, 480, 360).pixels);
        let mut scene = loaded;
        scene.camera.whole_frame();
        scene.camera.fit_to(480.0, 360.0);
        let t = 2.0 * (0.75 * (39.5978f32.to_radians() / 2.0).tan()).atan().to_degrees();
        assert!((scene.camera.vfov_deg - t).abs() < 1e-3, "{} vs {t}", scene.camera.vfov_deg);
        assert_eq!(run(&["--fov", "frame"]), normals_film(&scene, 480, 360).pixels);
    }
}

/// The pixels of a PFM the binary wrote (the shared reader's), as vectors.
fn read_pfm(path: &Path) -> Vec<Vec3> {
    crate::common::pfm::read_pfm(path).pixels.into_iter().map(Vec3::from_array).collect()
}

// ---------------------------------------------------------------------------------------
// Camera files and the fit rules
// ---------------------------------------------------------------------------------------

/// A camera settings file as the reference dumps it (its own numbers, including a lens):
/// the fields of view are used as written at any size, the lens is replaced by the
/// reference's defaults.
#[test]
fn camera_files_keep_their_fields_of_view_and_drop_their_lens() {
    let dump = "30 50 0.6 0.1 100\n0 1 4 0 1 0\n1.5708 0 4 0.3 60\n1 0 0 0 1 0 0 0 1\n480 800 868.6\n2.5 0.25\n";
    let mut cam = wavepath::parse_camera_settings(dump).unwrap();
    for (w, h) in [(800.0, 600.0), (64.0, 48.0), (100.0, 300.0)] {
        cam.fit_to(w, h);
        assert_eq!((cam.hfov_deg, cam.vfov_deg), (30.0, 50.0));
    }
    assert_eq!((cam.lens_radius, cam.focal_distance), (0.0, 4.7));
    assert_eq!(cam.position, vec3(0.0, 1.0, 4.0));
}

/// `double` as C++ `<<` writes it: %g with 6 significant digits (what the reference's
/// settings dump holds).
fn cpp_double(v: f64) -> String {
    if v == 0.0 {
        return if v.is_sign_negative() { "-0".into() } else { "0".into() };
    }
    let exp = v.abs().log10().floor() as i32;
    let trim = |s: String| if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if !(-4..6).contains(&exp) {
        let s = format!("{v:.5e}");
        let (m, e) = s.split_once('e').unwrap();
        let e: i32 = e.parse().unwrap();
        format!("{}e{}{:02}", trim(m.to_string()), if e < 0 { '-' } else { '+' }, e.abs())
    } else {
        trim(format!("{v:.*}", (5 - exp).max(0) as usize))
    }
}

/// A settings file laid out as the reference's dump writes one (fields of view, aspect and
/// clip; position and target; the orbit angles; c2w row by row; screen size and distance;
/// lens), with its 6-digit numbers, for the camera CS184 places for the banana at 800x600
/// (turned 45 degrees and looking down, so that a transposed c2w shows another picture):
/// read with `-c`, it shows the picture `--fov frame` shows (the whole 800x600 view), up to
/// the dump's rounding.
#[test]
fn a_settings_dump_as_the_reference_writes_it_reproduces_its_view() {
    let Some(path) = common::scene("cs184/keenan/banana.dae") else { return };
    let mut cam = load(&path, &LoadOptions::default()).unwrap().camera;
    cam.fit_to(800.0, 600.0);
    let f = |v: f32| cpp_double(v as f64);
    let (p, m) = (cam.position, cam.c2w);
    let target = p - 3.0 * m.z_axis;
    let dump = format!(
        "{} {} {} {} {}\n{} {} {} {} {} {} \n{} {} {} {} {}\n{}\n800 600 {}\n4.7 0\n",
        f(cam.hfov_deg),
        f(cam.vfov_deg),
        f(4.0 / 3.0),
        f(cam.nclip),
        f(cam.fclip),
        f(p.x),
        f(p.y),
        f(p.z),
        f(target.x),
        f(target.y),
        f(target.z),
        f(m.z_axis.y.acos()),
        f(m.z_axis.x.atan2(m.z_axis.z)),
        f(3.0),
        f(0.2),
        f(40.0),
        (0..9).map(|i| f(m.col(i % 3)[i / 3]) + " ").collect::<String>(),
        f(300.0 / (cam.vfov_deg.to_radians() / 2.0).tan()),
    );
    let dir = temp_dir("cs184-dump");
    std::fs::write(dir.join("cam.txt"), &dump).unwrap();
    let render = |extra: &[&str], name: &str| {
        let out = dir.join(name);
        let mut args =
            vec![path.to_str().unwrap(), "--shading", "normals", "-r", "160", "120", "-f", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = run_wavepath(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        read_pfm(&out)
    };
    let from_dump = render(&["-c", dir.join("cam.txt").to_str().unwrap()], "dump.pfm");
    let framed = render(&["--fov", "frame"], "frame.pfm");
    let same = from_dump.iter().zip(&framed).filter(|(a, b)| (**a - **b).abs().max_element() < 1e-2).count();
    assert!(same * 100 >= framed.len() * 99, "{same} of {} pixels agree\n{dump}", framed.len());
    let covered = framed.iter().filter(|p| **p != Vec3::ZERO).count();
    assert!(covered > framed.len() / 20, "{covered} pixels show the banana");
    assert_eq!(cpp_double(1.5e-5), "1.5e-05");
    assert_eq!(cpp_double(-0.000123456789), "-0.000123457");
    assert_eq!(cpp_double(49.13434), "49.1343");
}

/// The fit rules, each against its definition.
#[test]
fn fit_rules_follow_their_definitions() {
    let tan = |deg: f32| (deg.to_radians() / 2.0).tan();
    let mut cam = Camera { fit: FovFit::cs184(49.13434, 28.8415), ..Camera::default() };
    let t = tan(28.8415).max(0.75 * tan(49.13434));
    for (w, h) in [(800.0, 600.0), (480.0, 360.0), (1600.0, 1200.0), (100.0, 700.0)] {
        cam.fit_to(w, h);
        assert!((tan(cam.hfov_deg) - w * t / 600.0).abs() < 1e-5 && (tan(cam.vfov_deg) - h * t / 600.0).abs() < 1e-5);
    }
    // A 16:9 file at 800x600: the 800 pixels span exactly xfov.
    cam.fit_to(800.0, 600.0);
    assert!((cam.hfov_deg - 49.13434).abs() < 1e-3);
    let mut short = Camera { fit: FovFit::ShorterSide, hfov_deg: 40.0, vfov_deg: 40.0, ..Camera::default() };
    for (w, h) in [(640.0, 480.0), (480.0, 640.0), (100.0, 100.0)] {
        short.fit_to(w, h);
        assert!((short.hfov_deg.min(short.vfov_deg) - 40.0).abs() < 1e-4, "{w}x{h}");
        assert!((tan(short.hfov_deg) / tan(short.vfov_deg) - w / h).abs() < 1e-4);
    }
}

// ---------------------------------------------------------------------------------------
// Files without the reference's camera
// ---------------------------------------------------------------------------------------

fn write_obj(path: &Path, mesh: &Mesh) {
    let mut text = String::new();
    for p in &mesh.positions {
        text += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(path, text).unwrap();
}

/// Fraction of a normal-shading render's pixels that hit something, at 64x48 through the
/// camera the file was given.
fn coverage(path: &Path) -> (f64, Scene) {
    let mut scene = load(path, &LoadOptions::default()).unwrap();
    scene.camera.fit_to(64.0, 48.0);
    let film = normals_film(&scene, 64, 48);
    (film.pixels.iter().filter(|p| **p != Vec3::ZERO).count() as f64 / film.pixels.len() as f64, scene)
}

/// A flat model in the YZ plane (the old automatic camera looked down -Z and saw its edge: a
/// black picture), one lying flat, and one 3e5 from the origin: each is seen, from
/// the side of its largest face, and fills a good part of the picture.
#[test]
fn files_without_a_camera_see_their_largest_face() {
    let dir = temp_dir("cs184-framing");
    let grid = |f: &dyn Fn(f32, f32) -> Vec3| {
        let mut m = Mesh::default();
        let n = 8;
        for j in 0..=n {
            for i in 0..=n {
                m.positions.push(f(i as f32 / n as f32 - 0.5, j as f32 / n as f32 - 0.5));
            }
        }
        for j in 0..n {
            for i in 0..n {
                let a = (j * (n + 1) + i) as u32;
                let b = a + n as u32 + 1;
                m.triangles.extend([[a, a + 1, b + 1], [a, b + 1, b]]);
            }
        }
        m.material_ids = wavepath::MaterialIds::uniform(0, m.triangles.len());
        m
    };
    let cases: [(&str, Mesh, Vec3); 3] = [
        ("yz", grid(&|u, v| vec3(0.0, 2.0 * u, 3.0 * v)), Vec3::X),
        ("xz", grid(&|u, v| vec3(3.0 * u, 0.0, 2.0 * v)), Vec3::Y),
        (
            "far",
            {
                let mut m = icosphere(2);
                for p in &mut m.positions {
                    *p = *p * 2.0 + vec3(2e5, -5e4, 3e5);
                }
                m
            },
            Vec3::Z,
        ),
    ];
    for (name, mesh, face) in cases {
        let path = dir.join(format!("{name}.obj"));
        write_obj(&path, &mesh);
        let (covered, scene) = coverage(&path);
        assert!(covered > 0.1, "{name}: only {:.1}% of the picture shows the model", 100.0 * covered);
        // Seen from the side of its largest face, at most 55 degrees off its normal.
        let back = scene.camera.c2w.z_axis;
        assert!(back.dot(face) > 55f32.to_radians().cos(), "{name}: the camera looks along {}", -back);
        let (lo, hi) = scene.bounds().unwrap();
        let (near, far) = [lo, hi].iter().fold((f32::MAX, 0f32), |(n, f), &c| {
            let d = c.distance(scene.camera.position);
            (n.min(d), f.max(d))
        });
        assert!(scene.camera.nclip < near && scene.camera.fclip > far, "{name}: clip range misses the model");
    }
}

/// A COLLADA file from another tool: a 900-unit scene whose camera's far clip (1000) is
/// nearer than the scene once the CS184 placement has moved the camera 1.5 diagonals back.
/// The clip is widened, the log says so on one line naming the file, and the model is seen.
#[test]
fn a_clip_that_no_longer_covers_the_scene_is_widened() {
    let dir = temp_dir("cs184-clip");
    let path = dir.join("maya.dae");
    std::fs::write(&path, maya_like_file()).unwrap();
    let scene = load(&path, &LoadOptions::default()).unwrap();
    let (lo, hi) = scene.bounds().unwrap();
    let farthest = [lo.x, hi.x]
        .iter()
        .flat_map(|&x| [lo.y, hi.y].map(move |y| (x, y)))
        .flat_map(|(x, y)| [lo.z, hi.z].map(move |z| vec3(x, y, z)))
        .map(|c| c.distance(scene.camera.position))
        .fold(0.0, f32::max);
    assert!(farthest > 1000.0, "the test scene must lie beyond the file's far clip ({farthest})");
    assert!(scene.camera.fclip > farthest, "far clip {} < {farthest}", scene.camera.fclip);
    let out = dir.join("n.pfm");
    let o =
        run_wavepath([path.to_str().unwrap(), "--shading", "normals", "-r", "64", "48", "-f", out.to_str().unwrap()]);
    assert!(o.status.success());
    let log = String::from_utf8_lossy(&o.stderr);
    let notes: Vec<&str> = log.lines().filter(|l| l.contains("widened")).collect();
    assert!(notes.len() == 1 && notes[0].contains("maya.dae"), "{log}");
    assert!(read_pfm(&out).iter().filter(|p| **p != Vec3::ZERO).count() > 64 * 48 / 10);
}

fn maya_like_file() -> String {
    // A 900 x 600 quad standing on the ground; camera 1500 units back along +Z, far clip 1000.
    r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><up_axis>Y_UP</up_axis></asset>
  <library_cameras><camera id="cam"><optics><technique_common><perspective>
    <xfov>37.8</xfov><aspect_ratio>1.5</aspect_ratio><znear>0.1</znear><zfar>1000</zfar>
  </perspective></technique_common></optics></camera></library_cameras>
  <library_geometries><geometry id="g"><mesh>
    <source id="g-pos"><float_array id="g-pos-array" count="12">-450 0 0 450 0 0 450 600 0 -450 600 0</float_array>
      <technique_common><accessor source="#g-pos-array" count="4" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
    <vertices id="g-vtx"><input semantic="POSITION" source="#g-pos"/></vertices>
    <triangles count="2"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>0 1 2 0 2 3</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="Scene">
    <node id="Camera"><matrix>1 0 0 0 0 1 0 300 0 0 1 900 0 0 0 1</matrix><instance_camera url="#cam"/></node>
    <node id="Quad"><instance_geometry url="#g"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#Scene"/></scene>
</COLLADA>"##
        .to_string()
}

/// CBbunny's normal view: every wall, the floor and the ceiling show a normal pointing into
/// the box, as in the reference's pictures (the file winds them facing out).
#[test]
fn cornell_walls_show_normals_into_the_box() {
    let Some(mut scene) = common::load_scene("cs184/sky/CBbunny.dae") else { return };
    let (w, h) = (120, 90);
    scene.camera.fit_aspect(w as f32 / h as f32);
    let film = normals_film(&scene, w, h);
    let (lo, hi) = scene.bounds().unwrap();
    let centre = 0.5 * (lo + hi);
    let accel = BruteForce::new(&scene);
    let mut walls = 0;
    for y in 0..h {
        for x in 0..w {
            let ray = scene.camera.generate_ray((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            let Some(hit) = wavepath::Intersector::closest_hit(&accel, &ray, &mut Default::default()) else {
                continue;
            };
            let p = ray.at(hit.t);
            let ng = scene.surface_point(&ray, &hit).geometric_normal;
            // On the box's bounds, facing along the axis: a wall, the floor or the ceiling.
            let inward = (0..3).find_map(|k| {
                let axis = Vec3::AXES[k];
                if ng.dot(axis).abs() < 0.999 {
                    None
                } else if (p[k] - lo[k]).abs() < 1e-4 {
                    Some(axis)
                } else if (p[k] - hi[k]).abs() < 1e-4 {
                    Some(-axis)
                } else {
                    None
                }
            });
            let Some(inward) = inward else { continue };
            let shown = film.get(x, y) * 2.0 - Vec3::ONE;
            assert!(shown.dot(inward) > 0.999, "pixel ({x},{y}) at {p}: normal {shown}, into the box is {inward}");
            assert!((centre - p).dot(inward) > 0.0);
            walls += 1;
        }
    }
    assert!(walls > w * h / 4, "{walls} wall pixels");
}

/// `--tonemap cs184` writes the reference's bytes, truncated; `srgb` rounds. Expected bytes
/// computed here in f64 from the transfer curves, for radiances chosen so that no value lies
/// within 1e-3 of a byte boundary (where f32 and f64 could round apart).
#[test]
fn png_bytes_truncate_for_cs184_and_round_for_srgb() {
    let curve_cs184 = |l: f64| (2f64.sqrt() * l).powf(1.0 / 2.2).clamp(0.0, 1.0) * 255.0;
    let curve_srgb = |l: f64| {
        let l = l.clamp(0.0, 1.0);
        255.0 * if l <= 0.0031308 { 12.92 * l } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 }
    };
    let safe = |v: f64| (v - v.floor()).min(v.ceil() - v) > 1e-3 && ((v - v.floor()) - 0.5).abs() > 1e-3;
    let radiances: Vec<f32> = (1..2000)
        .map(|i| i as f32 * 3.7e-4)
        .filter(|&l| safe(curve_cs184(l as f64)) && safe(curve_srgb(l as f64)))
        .take(300)
        .collect();
    assert!(radiances.len() == 300);
    let film = Film { width: radiances.len(), height: 1, pixels: radiances.iter().map(|&l| Vec3::splat(l)).collect() };
    let dir = temp_dir("cs184-bytes");
    for (tonemap, want) in [(Tonemap::Cs184, &f64::floor as &dyn Fn(f64) -> f64), (Tonemap::Srgb, &f64::round)] {
        let out = dir.join(format!("{tonemap:?}.png"));
        write_image(&film, &out, tonemap).unwrap();
        let img = image::open(&out).unwrap().to_rgb8();
        let curve: &dyn Fn(f64) -> f64 = if tonemap == Tonemap::Cs184 { &curve_cs184 } else { &curve_srgb };
        let mut differs = 0;
        for (i, &l) in radiances.iter().enumerate() {
            let got = img.get_pixel(i as u32, 0)[0];
            assert_eq!(got as f64, want(curve(l as f64)), "{tonemap:?}: L = {l}");
            differs += usize::from(curve(l as f64).fract() >= 0.5);
        }
        // The two rules differ on about half the values: the test would see a swap.
        assert!(differs > 50);
    }
}

// ---------------------------------------------------------------------------------------
// The course renderer's light pdf
// ---------------------------------------------------------------------------------------

/// A diffuse floor lit only by a one-sided 0.6 x 0.8 area light 1.2 above it (as the
/// Cornell boxes'), direct light. With `--cs184-light-pdf` every light-sampled estimate is
/// the correct one times the distance to the light point, so a floor pixel converges to
/// `albedo / pi * integral of L cos_p cos_l / d dA` instead of `/ d^2`; both integrals are
/// computed here by a 200 x 200 midpoint rule in f64. Hemisphere sampling (`-H`) does not use
/// the light's pdf and is unchanged by the switch.
///
/// Regions of 8x8 pixels are compared by the shared z-test of `common::agree` (false
/// failures below 1e-6, fixed seeds).
#[test]
fn cs184_light_pdf_weights_each_light_sample_by_its_distance() {
    let (w, h) = (32, 24);
    let (height, le, albedo) = (1.2f32, 6.0f32, 0.7f32);
    let (dx, dy) = (vec3(0.6, 0.0, 0.0), vec3(0.0, 0.0, 0.8));
    let mut mesh = Mesh::default();
    common::meshgen::quad(
        &mut mesh,
        [vec3(-5.0, 0.0, -5.0), vec3(-5.0, 0.0, 5.0), vec3(5.0, 0.0, 5.0), vec3(5.0, 0.0, -5.0)],
        0,
    );
    let mut camera = Camera::look_at(vec3(0.0, 1.0, 0.6), vec3(0.0, 0.0, 0.0), Vec3::Y, 60.0, w as f32 / h as f32);
    camera.nclip = 0.01;
    let scene = Scene {
        name: "floor under an area light".into(),
        mesh,
        materials: vec![Material::diffuse("grey", Vec3::splat(albedo))],
        lights: vec![Light::Area {
            position: vec3(0.0, height, 0.0),
            direction: -Vec3::Y,
            dim_x: dx,
            dim_y: dy,
            radiance: Vec3::splat(le),
        }],
        camera,
        ..Scene::default()
    };
    // Radiance at floor point p with the light-side distance raised to `power` (2: correct).
    let expected = |p: Vec3, power: i32| -> f64 {
        let n = 200;
        let mut sum = 0.0;
        for j in 0..n {
            for i in 0..n {
                let (s, t) = ((i as f64 + 0.5) / n as f64 - 0.5, (j as f64 + 0.5) / n as f64 - 0.5);
                let q = DVec3::new(0.0, height as f64, 0.0) + s * dx.as_dvec3() + t * dy.as_dvec3();
                let d = q - p.as_dvec3();
                let dist = d.length();
                let (cos_p, cos_l) = (d.y / dist, d.y / dist);
                sum += le as f64 * cos_p * cos_l / dist.powi(power);
            }
        }
        let area = (dx.length() * dy.length()) as f64;
        albedo as f64 / std::f64::consts::PI * sum * area / (n * n) as f64
    };
    let floor_point = |x: usize, y: usize| {
        let r = scene.camera.generate_ray((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
        r.at(-r.origin.y / r.dir.y)
    };
    let mut s = render::settings(w, h, 1, 16);
    s.sampling.light_samples = 4;
    for (biased, power) in [(false, 2), (true, 1)] {
        let acc = render::wavefront(&scene, &s.clone().with(|s| s.cs184.light_pdf = biased)).0;
        let want = |x, y| Some(glam::DVec3::splat(expected(floor_point(x, y), power)));
        crate::common::agree::assert_regions_match(&acc, 8, want, 1e-4, &format!("cs184 pdf {biased}"));
    }
    let mut hemi = s.clone();
    hemi.paths.hemisphere = true;
    let a = render::wavefront(&scene, &hemi).0;
    let b = render::wavefront(&scene, &hemi.with(|s| s.cs184.light_pdf = true)).0;
    assert!(a.pixels.iter().zip(&b.pixels).all(|(p, q)| p.mean() == q.mean()));
}

/// The switch reaches the renderer from the command line and says so in the log: the
/// default Cornell box (lit by an area light 0.1 to 2 units from its surfaces) comes out
/// brighter with it, by no more than the largest distance in the box.
#[test]
fn the_light_pdf_switch_is_plumbed_and_logged() {
    let dir = temp_dir("cs184-switch");
    let mean = |extra: &[&str]| {
        let out = dir.join("m.pfm");
        let mut args = vec!["-r", "32", "24", "-s", "16", "-l", "2", "-m", "1", "--fov", "frame"];
        args.extend(extra);
        args.extend(["-f", out.to_str().unwrap()]);
        let o = run_wavepath(&args);
        assert!(o.status.success());
        let px = read_pfm(&out);
        (px.iter().map(|p| p.x as f64).sum::<f64>(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (plain, log_plain) = mean(&[]);
    let (biased, log) = mean(&["--cs184-light-pdf"]);
    assert!(log.lines().any(|l| l.contains("--cs184-light-pdf") && l.contains("biased")), "{log}");
    assert!(!log_plain.contains("--cs184-light-pdf"));
    assert!(biased > 1.1 * plain && biased < 2.5 * plain, "{biased} vs {plain}");
}
