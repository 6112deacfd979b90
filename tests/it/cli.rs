//! The command line end to end: the default render, output formats, and bad flags.

use crate::common::{self, run_wavepath, temp_dir};
use std::path::Path;
use std::process::Output;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A PFM the binary wrote, by the shared reader: (width, height, rgb rows bottom-up).
fn read_pfm(path: &Path) -> (usize, usize, Vec<[f32; 3]>) {
    let p = crate::common::pfm::read_pfm(path);
    (p.width, p.height, p.pixels)
}

#[test]
fn default_scene_normals_show_the_floor_and_walls() {
    let dir = temp_dir("cli-normals");
    let out = dir.join("n.pfm");
    // The whole 800x600 picture, small (the CS184 rule would show its centre 80x60 only).
    let o = run_wavepath(["--shading", "normals", "--fov", "frame", "-r", "80", "60", "-f", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (w, h, px) = read_pfm(&out);
    assert_eq!((w, h), (80, 60));
    // Every pixel against a reference computed here: the pixel centre's ray (one sample is
    // the centre) against every triangle and sphere of the embedded scene in f64, brute force,
    // coloured n * 0.5 + 0.5 with the triangle's normal as wound (the walls face into the box)
    // or the sphere's outward normal; black where nothing is hit. Pixels whose answer changes
    // within 1e-3 of a pixel (silhouettes) are skipped.
    let mut scene = wavepath::default_scene();
    scene.camera.whole_frame();
    scene.camera.fit_to(w as f32, h as f32);
    let reference = |fx: f64, fy: f64| -> [f32; 3] {
        let r = scene.camera.generate_ray((fx / w as f64) as f32, (fy / h as f64) as f32);
        let (o, d) = (r.origin.as_dvec3(), r.dir.as_dvec3());
        let mut best = (f64::INFINITY, glam::DVec3::ZERO);
        for i in 0..scene.mesh.triangles.len() {
            let [a, b, c] = scene.mesh.corners(i).map(|p| p.as_dvec3());
            let Some((t, u, v)) = common::triangle_f64(o, d, [a, b, c]) else { continue };
            if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > r.tmin as f64 && t < best.0 {
                best = (t, (b - a).cross(c - a).normalize());
            }
        }
        for sp in &scene.spheres {
            let oc = o - sp.center.as_dvec3();
            let (b, c) = (oc.dot(d), oc.length_squared() - (sp.radius as f64).powi(2));
            let disc = b * b - c;
            if disc > 0.0 {
                let t = -b - disc.sqrt();
                if t > r.tmin as f64 && t < best.0 {
                    best = (t, (oc + t * d).normalize());
                }
            }
        }
        if best.0.is_finite() { (best.1 * 0.5 + 0.5).as_vec3().to_array() } else { [0.0; 3] }
    };
    let (mut compared, mut background, mut floor) = (0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
            let want = reference(cx, cy);
            let near = [(1e-3, 0.0), (-1e-3, 0.0), (0.0, 1e-3), (0.0, -1e-3)];
            if near.iter().any(|(dx, dy)| reference(cx + dx, cy + dy) != want) {
                continue;
            }
            let got = px[y * w + x];
            assert!(
                got.iter().zip(want).all(|(g, e)| (g - e).abs() < 1e-3),
                "pixel ({x},{y}): {got:?}, expected {want:?}"
            );
            compared += 1;
            background += usize::from(want == [0.0; 3]);
            floor += usize::from(want == [0.5, 1.0, 0.5]);
        }
    }
    assert!(compared > w * h * 9 / 10 && background > 100 && floor > 100, "{compared} {background} {floor}");
    // The seed's log lines are there.
    let log = stderr(&o);
    assert!(log.contains("million rays per second") && log.contains("intersection tests per ray"), "{log}");
}

#[test]
fn png_exr_and_stats_are_written() {
    let dir = temp_dir("cli-formats");
    let png = dir.join("a.png");
    let exr = dir.join("a.exr");
    let stats = dir.join("s.json");
    for f in [&png, &exr] {
        let o = run_wavepath([
            "-s",
            "4",
            "-m",
            "1",
            "--tonemap",
            "cs184",
            "--fov",
            "frame",
            "-r",
            "32",
            "24",
            "-t",
            "1",
            "-f",
            f.to_str().unwrap(),
            "--stats",
            stats.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (32, 24));
    let exr_img = image::open(&exr).unwrap().into_rgb32f();
    assert_eq!((exr_img.width(), exr_img.height()), (32, 24));
    // The PNG is the EXR's radiance through the transfer curve, byte for byte (values within
    // 1e-3 of a byte boundary, where f32 and f64 may round apart, are skipped); both files
    // have row 0 at the top.
    let curve = |l: f32| (2f64.sqrt() * l as f64).powf(1.0 / 2.2).clamp(0.0, 1.0) * 255.0;
    let mut checked = 0;
    for (p, e) in img.pixels().zip(exr_img.pixels()) {
        for c in 0..3 {
            let v = curve(e[c]);
            if (v - v.round()).abs() > 1e-3 || v == 0.0 || v == 255.0 {
                assert_eq!(p[c] as f64, v.floor(), "PNG byte {} for radiance {}", p[c], e[c]);
                checked += 1;
            }
        }
    }
    assert!(checked > 32 * 24 * 3 * 9 / 10, "{checked}");
    assert!(exr_img.pixels().any(|e| e[0] != e[1]), "a coloured picture");
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    for key in
        ["scene", "triangles", "spheres", "effects", "bvh", "rays", "stages", "samples_per_pixel", "invalid_samples"]
    {
        assert!(v.get(key).is_some(), "stats lack {key}: {v}");
    }
    assert_eq!(v["rays"]["camera"], 32 * 24 * 4);
    assert_eq!(v["threads"], 1);
}

/// A cell (`-p`) renders exactly the full render's pixels inside it, bit for bit (each
/// pixel's samples are its own), and nothing outside.
#[test]
fn cell_renders_only_that_rectangle() {
    let dir = temp_dir("cli-cell");
    let (cell, full) = (dir.join("c.pfm"), dir.join("f.pfm"));
    let base = ["-s", "4", "-m", "3", "-r", "40", "30"];
    for (out, extra) in [(&cell, &["-p", "10", "5", "20", "10"][..]), (&full, &[][..])] {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        args.extend(["-f", out.to_str().unwrap()]);
        let o = run_wavepath(&args);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let (w, _, px) = read_pfm(&cell);
    let (_, _, all) = read_pfm(&full);
    for (i, (p, q)) in px.iter().zip(&all).enumerate() {
        let (x, y) = (i % w, i / w);
        if (10..30).contains(&x) && (5..15).contains(&y) {
            assert_eq!(p.map(f32::to_bits), q.map(f32::to_bits), "pixel ({x},{y}) differs from the full render");
        } else {
            assert_eq!(*p, [0.0; 3], "pixel ({x},{y}) outside the cell was rendered");
        }
    }
    assert!(px.iter().filter(|p| **p != [0.0; 3]).count() > 150);
}

/// Each bad flag gets exactly one line on stderr, naming the problem, and a non-zero exit.
#[test]
fn bad_flags_fail_with_one_line() {
    let dir = temp_dir("cli-badflags");
    let cam = dir.join("cam.txt");
    std::fs::write(&cam, "1 2 three").unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["-r", "0", "10"], "-r (image width)"),
        (vec!["-r", "100000", "100000"], "-r (image width)"),
        (vec!["-r", "20000", "20000"], "pixels"),
        (vec!["-s", "-4"], "-s"),
        (vec!["-l", "0"], "-l"),
        (vec!["-m", "-1"], "-m"),
        (vec!["-o", "2"], "-o"),
        (vec!["-t", "-1"], "-t"),
        (vec!["-t", "5000"], "-t"),
        (vec!["--rr", "0"], "--rr"),
        (vec!["--rr", "1.5"], "--rr"),
        (vec!["-a", "0", "0.05"], "-a"),
        (vec!["-a", "64", "-1"], "-a"),
        (vec!["-p", "500", "0", "10", "10", "-r", "100", "100"], "-p"),
        (vec!["-b", "-1"], "-b"),
        (vec!["-d", "0"], "-d"),
        (vec!["-f", "out.bmp"], "out.bmp"),
        (vec!["-s", "many"], "many"),
        (vec!["--shading", "fancy"], "fancy"),
        (vec!["--bvh-build", "best"], "best"),
        (vec!["--aov", "albedo,nromal"], "nromal"),
        (vec!["--aov", "depth", "--integrator", "recursive"], "depth"),
        (vec!["--aov", "albedo", "--shading", "normals"], "normals"),
        (vec!["--denoise", "--oidn", "/nonexistent/oidn"], "/nonexistent/oidn"),
        (vec!["--aov", "depth", "--part", "0/2"], "--aov"),
        (vec!["-c", cam.to_str().unwrap()], "cam.txt"),
        (vec!["-c", "/nonexistent/cam.txt"], "cam.txt"),
        (vec!["/nonexistent/scene.dae"], "/nonexistent/scene.dae"),
        (vec![dir.join("scene.xyz").to_str().unwrap()], "scene.xyz"),
    ]
    .into_iter()
    .map(|(a, m)| (a.into_iter().map(String::from).collect(), m))
    .collect();
    std::fs::write(dir.join("scene.xyz"), "hello").unwrap();
    for (args, needle) in cases {
        let mut full = args.clone();
        full.extend(["-f".into(), dir.join("x.png").to_str().unwrap().into()]);
        if args.iter().any(|a| a == "-f") {
            full = args.clone();
        }
        let refs: Vec<&str> = full.iter().map(|s| s.as_str()).collect();
        let o = run_wavepath(&refs);
        let err = stderr(&o);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?} printed more than one line:\n{err}");
        assert!(err.contains(needle), "{args:?}: error does not mention {needle}: {err}");
        assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    }
}

/// The same bad value gets the same message from the command line and the viewer's
/// controls, each under its own name for the option: both show the engine's message (the
/// Python package's tests compare theirs with this binary's too).
#[test]
fn a_bad_value_gets_the_same_message_from_the_command_line_and_the_viewer() {
    let dir = temp_dir("cli-same-message");
    let out = dir.join("x.png");
    // (flags, the viewer's control and value, the command line's name for the option)
    let cases = [
        (vec!["-r", "0", "10"], "res", "0x10", "-r"),
        (vec!["-r", "100000", "10"], "res", "100000x10", "-r"),
        (vec!["-r", "20000", "20000"], "res", "20000x20000", "-r"),
        (vec!["--rr", "1.5"], "rr", "1.5", "--rr"),
        (vec!["-s", "0"], "spp", "0", "-s"),
        (vec!["-m", "-1"], "m", "-1", "-m"),
        (vec!["-b", "-1"], "lens", "-1", "-b"),
        (vec!["--shading", "wireframe"], "shading", "wireframe", "--shading"),
    ];
    for (flags, key, value, flag) in cases {
        let o = run_wavepath(flags.iter().copied().chain(["-f", out.to_str().unwrap()]));
        assert!(!o.status.success(), "{flags:?} succeeded");
        let line = stderr(&o).trim_end().to_string();
        let message = line.strip_prefix("error: ").unwrap_or(&line);
        let message = message.strip_suffix(" (see wavepath --help)").unwrap_or(message);
        let view = wavepath_apps::view::controls::parse(key, value).unwrap_err();
        assert_eq!(view.replacen(key, flag, 1), message, "{flags:?} against {key}={value}");
    }
    // The engine's own message, under the command line's name.
    let o = run_wavepath(["-s", "0", "-f", out.to_str().unwrap()]);
    let engine = wavepath::Field::Spp.whole("-s", 0).unwrap_err();
    assert_eq!(stderr(&o).trim_end(), format!("error: {engine}"));
}

#[test]
fn the_fast_bvh_build_renders_the_same_image() {
    // Global illumination through both spheres and every wall: the trees differ (Morton
    // order against binned SAH), the closest hits and so every sample do not.
    let dir = temp_dir("cli-bvh-build");
    let render = |build: &str| {
        let (out, stats) = (dir.join(format!("{build}.pfm")), dir.join(format!("{build}.json")));
        let args = ["-s", "4", "-l", "2", "-m", "4", "-r", "64", "48", "-t", "2", "--bvh-build", build];
        let o = run_wavepath(args.into_iter().chain(["-f", out.to_str().unwrap(), "--stats", stats.to_str().unwrap()]));
        assert!(o.status.success(), "{}", stderr(&o));
        // The log and the stats say which build it was.
        assert!(stderr(&o).contains(&format!("{build} build")), "{}", stderr(&o));
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        assert_eq!(json["bvh"]["method"], build);
        read_pfm(&out).2
    };
    let (sah, fast) = (render("sah"), render("fast"));
    assert!(sah.iter().flatten().any(|&c| c > 0.0), "a lit image");
    assert!(sah == fast, "the images differ");
}

#[test]
fn help_lists_every_cs184_flag() {
    let o = run_wavepath(["--help"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    for flag in [
        "-s",
        "-l",
        "-m",
        "-o",
        "-a",
        "-t",
        "-r",
        "-f",
        "-p",
        "-c",
        "-e",
        "-b",
        "-d",
        "-H",
        "--shading",
        "--rr",
        "--no-bvh",
        "--seed",
        "--tonemap",
        "--integrator",
        "--camera",
        "--stats",
    ] {
        let listed = text.lines().any(|l| {
            let l = l.trim_start();
            l.starts_with(&format!("{flag} ")) || l.starts_with(&format!("{flag},")) || l == flag
        });
        assert!(listed, "--help lacks {flag}");
    }
}

/// A scene whose mesh or BVH would not fit is refused before the allocations, with one line
/// naming the file: `--max-memory` below the file's size stops the load, a limit between the
/// file's size and the BVH's estimate (72 bytes a triangle with corner leaves) stops the build.
#[test]
fn scenes_that_would_not_fit_in_memory_are_refused_before_the_work() {
    let d = common::temp_dir("max-memory");
    let obj = d.join("quad.obj");
    let text = "v 0 0 0\nv 2 0 0\nv 2 0 1\nv 0 0 1\nf 1 2 3\nf 1 3 4\n";
    std::fs::write(&obj, text).unwrap();
    let img = d.join("q.png");
    let run_with = |limit: &str, extra: &[&str]| {
        let mut args = vec![obj.to_str().unwrap(), "-r", "8", "6", "-f", img.to_str().unwrap(), "--max-memory", limit];
        args.extend(extra);
        common::run_wavepath(args)
    };
    let run = |limit: &str| run_with(limit, &[]);
    let refused = |limit: &str, doing: &str| {
        let o = run(limit);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "--max-memory {limit} should refuse");
        let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
        assert!(errors.len() == 1 && errors[0].contains("quad.obj") && errors[0].contains(doing), "{err}");
    };
    // The file is 48 bytes; subdivided twice its mesh needs 16 times that.
    assert_eq!(text.len(), 48);
    refused("47", "loading it");
    // 2 triangles: a BVH estimate of 144 bytes; 4^2 x 2 = 32 triangles: 2304.
    refused("100", "building its BVH");
    let o = run("144");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run_with("2303", &["--subdivide", "2"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("building its BVH"), "{err}");
    for bad in ["0", "5Q", "G", "1e30"] {
        let o = run(bad);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.trim().lines().count() == 1 && err.contains(bad), "{bad}: {err}");
    }
    assert!(run("1K").status.success());
}

/// The sample-rate image is written only for adaptive renders (`-a`): a fixed-rate render's
/// would be flat, a file nobody asked for. The same for a merge of parts.
#[test]
fn the_rate_image_only_for_adaptive_renders() {
    let dir = temp_dir("cli-rate-image");
    let render = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec!["-r", "16", "12", "-s", "4", "-f", out.to_str().unwrap()];
        args.extend(extra);
        let o = run_wavepath(&args);
        assert!(o.status.success(), "{}", stderr(&o));
    };
    render("fixed.png", &[]);
    assert!(dir.join("fixed.png").exists());
    assert!(!dir.join("fixed_rate.png").exists(), "a rate image without -a");
    render("adaptive.png", &["-a", "2", "0.1"]);
    assert!(dir.join("adaptive_rate.png").exists(), "no rate image with -a");
    // Split and merged: the merge follows the parts.
    for (stem, extra) in [("tiles", &[][..]), ("tiles_a", &["-a", "2", "0.1"][..])] {
        let mut parts = Vec::new();
        for i in 0..2 {
            let p = dir.join(format!("{stem}{i}.exr"));
            let part = format!("{i}/2");
            let mut args = vec!["-r", "16", "12", "-s", "4", "--part", &part, "-f", p.to_str().unwrap()];
            args.extend(extra);
            let o = run_wavepath(&args);
            assert!(o.status.success(), "{}", stderr(&o));
            parts.push(p.to_str().unwrap().to_string());
        }
        let merged = dir.join(format!("{stem}.png"));
        let mut args = vec!["merge".to_string()];
        args.extend(parts);
        args.extend(["-f".to_string(), merged.to_str().unwrap().to_string()]);
        let o = run_wavepath(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(dir.join(format!("{stem}_rate.png")).exists(), !extra.is_empty(), "{stem}: merged rate image");
    }
}

/// A map given by `-e` lights a file that has no light of its own: the default sky is not
/// added beside it (one light, the map's), and without `-e` the sky is there.
#[test]
fn an_environment_map_replaces_the_default_sky() {
    let dir = temp_dir("cli-envmap-sky");
    let obj = dir.join("plane.obj");
    std::fs::write(&obj, "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 3 2\nf 1 4 3\n").unwrap();
    let map = dir.join("grey.hdr");
    let film = wavepath::Film { width: 8, height: 4, pixels: vec![glam::Vec3::splat(0.5); 32] };
    wavepath::write_image(&film, &map, wavepath::Tonemap::Cs184).unwrap();
    let lights = |extra: &[&str]| {
        let mut args = vec!["info", "--json", obj.to_str().unwrap()];
        args.extend(extra);
        let o = run_wavepath(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let kinds: Vec<String> = v["lights"].as_array().unwrap().iter().map(|l| l["kind"].to_string()).collect();
        (kinds, v["environment"].as_str().unwrap().to_string())
    };
    let (bare, env) = lights(&[]);
    assert_eq!((bare, env.as_str()), (vec!["\"hemisphere\"".to_string()], "none"), "the default sky");
    let (with_map, env) = lights(&["-e", map.to_str().unwrap()]);
    assert!(with_map.is_empty() && env.starts_with("map "), "lights {with_map:?}, environment {env}");
}
