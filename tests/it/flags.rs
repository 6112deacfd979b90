//! Render flags through the binary, each against what a user sees: the stats JSON
//! (`--stats`), the log, and the image (PFM, bit for bit where the flag must not change it).
//! Every test fails if the command line ignores its flag: a flag whose effect is speed only
//! (`--isa`, `--bvh-leaves`, `--bvh-build`) is checked through what the log or the stats
//! report about the choice, and an unchanged image.

use crate::common::pfm::{Pfm, read_pfm};
use crate::common::{repo_root, run_wavepath, temp_dir};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// What one render left: its image, its stats and its log (stderr).
struct Run {
    image: Pfm,
    stats: Value,
    log: String,
}

impl Run {
    /// The image's bits, for comparisons that must be exact.
    fn bits(&self) -> Vec<[u32; 3]> {
        self.image.pixels.iter().map(|p| p.map(f32::to_bits)).collect()
    }

    /// The reason the stats give for effect `name`, if it is on.
    fn effect(&self, name: &str) -> Option<String> {
        self.stats["effect_reasons"]
            .as_array()
            .expect("effect_reasons")
            .iter()
            .find(|e| e["name"] == name)
            .map(|e| e["reason"].as_str().unwrap_or_default().to_string())
    }

    fn sum(&self) -> f64 {
        self.image.pixels.iter().flatten().map(|&c| c as f64).sum()
    }
}

/// Renders with `args` into `dir/name.pfm` and `dir/name.json`, which must succeed.
fn render(dir: &Path, name: &str, args: &[&str]) -> Run {
    let (pfm, json) = (dir.join(format!("{name}.pfm")), dir.join(format!("{name}.json")));
    let mut all: Vec<&str> = args.to_vec();
    all.extend(["-f", pfm.to_str().unwrap(), "--stats", json.to_str().unwrap()]);
    let o = run_wavepath(&all);
    let log = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{args:?}: {log}");
    let stats = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    Run { image: read_pfm(&pfm), stats, log }
}

fn scene(name: &str) -> String {
    repo_root().join("scenes").join(name).to_str().unwrap().to_string()
}

fn with<'a>(base: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
    base.iter().chain(extra).copied().collect()
}

/// The repository's Cornell box as a binary PLY (the mesh only: the loader adds a sky), for
/// a fourth format.
fn cornell_ply(dir: &Path) -> PathBuf {
    let path = dir.join("cornell.ply");
    let sub = run_wavepath(["subdivide", &scene("cornell_mesh.obj"), path.to_str().unwrap(), "-n", "0"]);
    assert!(sub.status.success(), "{}", String::from_utf8_lossy(&sub.stderr));
    path
}

/// `--sampler` picks the pattern the stats name, and each pattern gives another image (the
/// pixels' samples sit elsewhere); without the flag the pattern follows the file: independent
/// numbers for `.dae` files (the extension in any case) and the embedded scene (the CS184
/// pictures), Sobol for OBJ, PLY and glTF. Naming the default explicitly gives the flagless
/// image bit for bit.
#[test]
fn the_sampler_flag_and_its_default_per_format() {
    let dir = temp_dir("flags-sampler");
    let base = ["-r", "24", "18", "-s", "4", "-m", "2", "-l", "2"];
    let ply = cornell_ply(&dir);
    let upper = dir.join("cornell.DAE");
    std::fs::copy(scene("cornell_mesh.dae"), &upper).unwrap();
    let scenes: [(&str, Option<String>, &str); 6] = [
        ("embedded", None, "independent"),
        ("dae", Some(scene("cornell_mesh.dae")), "independent"),
        ("DAE", Some(upper.to_str().unwrap().to_string()), "independent"),
        ("obj", Some(scene("cornell_mesh.obj")), "sobol"),
        ("gltf", Some(scene("cornell_mesh.gltf")), "sobol"),
        ("ply", Some(ply.to_str().unwrap().to_string()), "sobol"),
    ];
    for (what, file, default) in &scenes {
        let args: Vec<&str> = file.iter().map(String::as_str).chain(base).collect();
        let none = render(&dir, &format!("{what}-none"), &args);
        assert_eq!(none.stats["sampler"], *default, "{what}: the default sampler");
        assert!(none.sum() > 0.0, "{what}: a black image");
        let mut images = vec![];
        for kind in ["independent", "stratified", "sobol"] {
            let r = render(&dir, &format!("{what}-{kind}"), &with(&args, &["--sampler", kind]));
            assert_eq!(r.stats["sampler"], kind, "{what}: --sampler {kind}");
            if kind == *default {
                assert!(r.bits() == none.bits(), "{what}: --sampler {kind} (the default) changed the image");
            } else {
                assert!(r.bits() != none.bits(), "{what}: --sampler {kind} gave the default's image");
            }
            images.push(r.bits());
        }
        let distinct = images[0] != images[1] && images[1] != images[2] && images[0] != images[2];
        assert!(distinct, "{what}: two samplers gave one image");
    }
}

/// An OBJ scene of one emissive square (`Ke 2 3 4`, black otherwise) in the plane z = 0,
/// wound to face +z (`front`) or -z. The framing camera of a mesh-only file looks at a flat
/// square from its +z side, so the front winding faces the camera and the other shows it
/// its back.
fn emitter_square(dir: &Path, front: bool) -> PathBuf {
    let name = if front { "front" } else { "back" };
    std::fs::write(dir.join("e.mtl"), "newmtl glow\nKd 0 0 0\nKe 2 3 4\n").unwrap();
    let faces = if front { "f 1 2 3 4" } else { "f 1 4 3 2" };
    let obj = format!("mtllib e.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nusemtl glow\n{faces}\n");
    let path = dir.join(format!("{name}.obj"));
    std::fs::write(&path, obj).unwrap();
    path
}

/// OBJ `Ke` emits from the front face only (the side its winding points to); with
/// `--two-sided-emission` from both. Seen from the front the centre pixel is exactly `Ke`
/// either way; seen from the back it is black without the flag and exactly `Ke` with it.
/// Direct light only (`-m 1`), one sample: the camera sees the emission, nothing else lights.
#[test]
fn two_sided_emission_lights_an_emitter_seen_from_its_back() {
    let dir = temp_dir("flags-two-sided");
    let base = ["-r", "16", "12", "-s", "1", "-m", "1"];
    let centre = |r: &Run| r.image.top_down(8, 6);
    for front in [true, false] {
        let path = emitter_square(&dir, front);
        let file = path.to_str().unwrap();
        let side = if front { "front" } else { "back" };
        let one = render(&dir, &format!("{side}-one"), &with(&[file], &base));
        let two = render(&dir, &format!("{side}-two"), &with(&with(&[file], &base), &["--two-sided-emission"]));
        let lit = [2.0, 3.0, 4.0];
        assert_eq!(centre(&two), lit, "{side}, two-sided");
        if front {
            assert_eq!(centre(&one), lit, "the front, one-sided");
            assert!(one.bits() == two.bits(), "the front face's image changed with --two-sided-emission");
        } else {
            assert_eq!(centre(&one), [0.0; 3], "the back of a one-sided emitter is lit");
            assert!(one.image.pixels.iter().all(|p| *p == [0.0; 3]), "the back of a one-sided emitter is lit");
        }
    }
}

/// MIS of light and BSDF samples runs at diffuse surfaces where emissive triangles are the
/// lights (the repository's OBJ Cornell box); `--no-mis` turns it off: the stats drop the
/// `mis` effect and the image changes (another estimator, other numbers). In the embedded
/// scene the light is an area light, where MIS is never used, so the flag changes nothing
/// there, bit for bit.
#[test]
fn no_mis_turns_off_mis_where_emissive_triangles_light_the_scene() {
    let dir = temp_dir("flags-no-mis");
    let obj = scene("cornell_mesh.obj");
    let base = ["-r", "24", "18", "-s", "4", "-m", "3"];
    let mis = render(&dir, "obj-mis", &with(&[&obj], &base));
    let no_mis = render(&dir, "obj-no-mis", &with(&with(&[&obj], &base), &["--no-mis"]));
    let reason = mis.effect("mis").expect("MIS is on for the OBJ Cornell box");
    assert!(reason.contains("emissive triangle"), "{reason}");
    assert_eq!(no_mis.effect("mis"), None, "--no-mis left MIS on");
    assert!(mis.bits() != no_mis.bits(), "--no-mis gave the same image");
    let mis = render(&dir, "default-mis", &base);
    let no_mis = render(&dir, "default-no-mis", &with(&base, &["--no-mis"]));
    assert_eq!(mis.effect("mis"), None, "MIS is on for an area light");
    assert!(mis.bits() == no_mis.bits(), "--no-mis changed an area light's image");
}

/// The instruction set the BVH runs for a request, from the CPU's own feature flags: AVX2
/// (with FMA, BMI1, POPCNT) for avx2 and avx512 (its kernels stop at AVX2), SSE4.1 for sse,
/// and the best of those below a request the CPU lacks.
#[cfg(target_arch = "x86_64")]
fn effective_isa(request: &str) -> &'static str {
    let avx2 = std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma")
        && std::arch::is_x86_feature_detected!("bmi1")
        && std::arch::is_x86_feature_detected!("popcnt");
    let sse = std::arch::is_x86_feature_detected!("sse4.1");
    match request {
        "avx2" | "avx512" if avx2 => "avx2",
        "avx2" | "avx512" | "sse" if sse => "sse",
        _ => "scalar",
    }
}

/// `--isa` caps every SIMD kernel: every choice gives the same image bit for bit (global
/// illumination through both spheres, so box tests, leaf tests, camera rays, shading lanes
/// and random numbers all run), and the log names the instruction set the BVH traverses
/// with. An unknown name is a one-line error naming it.
#[cfg(target_arch = "x86_64")]
#[test]
fn every_isa_renders_the_same_image_and_the_log_names_it() {
    let dir = temp_dir("flags-isa");
    let base = ["-r", "32", "24", "-s", "2", "-m", "3", "-l", "2"];
    let scalar = render(&dir, "scalar", &with(&base, &["--isa", "scalar"]));
    assert!(scalar.sum() > 0.0, "a black image");
    for isa in ["scalar", "portable", "sse", "avx2", "avx512"] {
        let r = render(&dir, isa, &with(&base, &["--isa", isa]));
        let want = format!("Built bvh8 {}, sah build", effective_isa(isa));
        assert!(r.log.contains(&want), "--isa {isa}: the log lacks '{want}':\n{}", r.log);
        assert!(r.bits() == scalar.bits(), "--isa {isa} changed the image");
    }
    // Without the flag: the best this CPU has.
    let r = render(&dir, "none", &base);
    assert!(r.log.contains(&format!("Built bvh8 {}, ", effective_isa("avx2"))), "{}", r.log);
    let o = run_wavepath(with(&base, &["--isa", "neon", "-f", dir.join("x.png").to_str().unwrap()]));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "--isa neon succeeded");
    assert!(err.trim_end().lines().count() == 1 && err.contains("neon"), "{err}");
}

/// `--bvh-leaves` and `--bvh-build` change the tree, never the hits: every layout under each
/// build gives the same image bit for bit (the OBJ box subdivided three times: 2,816
/// triangles, so leaves are many and full). The stats report the layout through the leaves'
/// resident bytes: a corner leaf holds three corners of four triangles as f32 (4 x 3 x 3 x 4
/// = 144 bytes), the lane mask and four ids (20), padded to three cache lines: 192 bytes;
/// packed leaves keep each distinct vertex once (less); auto is corners below 16 million
/// primitives.
#[test]
fn bvh_leaf_layouts_and_builds_render_the_same_image() {
    let dir = temp_dir("flags-bvh-leaves");
    let obj = scene("cornell_mesh.obj");
    let base = ["-r", "24", "18", "-s", "2", "-m", "3", "-l", "2", "--subdivide", "3", &obj];
    let reference = render(&dir, "sah-default", &base);
    for build in ["sah", "fast"] {
        let mut bytes = vec![];
        for leaves in ["corners", "packed", "auto"] {
            let r = render(
                &dir,
                &format!("{build}-{leaves}"),
                &with(&base, &["--bvh-build", build, "--bvh-leaves", leaves]),
            );
            assert_eq!(r.stats["bvh"]["method"], build);
            assert!(r.log.contains(&format!("{build} build")), "{}", r.log);
            assert!(r.bits() == reference.bits(), "--bvh-build {build} --bvh-leaves {leaves} changed the image");
            let (count, leaf_bytes) =
                (r.stats["bvh"]["leaves"].as_u64().unwrap(), r.stats["bvh"]["leaf_bytes"].as_u64().unwrap());
            assert!(count > 100, "{count} leaves");
            bytes.push((count, leaf_bytes));
        }
        let [(n, corners), (n_packed, packed), auto] = bytes[..] else { unreachable!() };
        assert_eq!(n, n_packed, "{build}: the layout changed the tree");
        assert_eq!(corners, 192 * n, "{build}: corner leaves are 192 bytes each");
        assert!(packed < corners * 9 / 10, "{build}: packed leaves {packed} bytes, corners {corners}");
        assert_eq!(auto, (n, corners), "{build}: auto is corners for a small mesh");
    }
}

/// `--roulette`: the embedded scene's default is the seed's fixed probability from the
/// second bounce (`--roulette fixed` gives that image bit for bit); `throughput` continues by
/// the path's throughput from depth 5 (the stats say so), which stops other paths: other
/// extension rays and another image. `--rr 1` with fixed roulette stops none (the effect is
/// off and more extension rays are traced); `--rr-depth` moves where it starts. A bad value
/// is a one-line error.
#[test]
fn the_roulette_flags_change_which_paths_go_on() {
    let dir = temp_dir("flags-roulette");
    let base = ["-r", "24", "18", "-s", "4", "-m", "8"];
    let extension = |r: &Run| r.stats["rays"]["extension"].as_u64().unwrap();
    let none = render(&dir, "none", &base);
    let reason = none.effect("russian-roulette").expect("roulette runs at -m 8");
    assert!(reason.contains("--rr 0.65 < 1 from depth 1"), "{reason}");
    let fixed = render(&dir, "fixed", &with(&base, &["--roulette", "fixed"]));
    assert!(fixed.bits() == none.bits() && fixed.stats["rays"] == none.stats["rays"], "--roulette fixed");
    let throughput = render(&dir, "throughput", &with(&base, &["--roulette", "throughput"]));
    let reason = throughput.effect("russian-roulette").expect("throughput roulette runs at -m 8");
    assert!(reason.contains("throughput from depth 5"), "{reason}");
    assert!(extension(&throughput) != extension(&none), "--roulette throughput stopped the same paths");
    assert!(throughput.bits() != none.bits(), "--roulette throughput gave the fixed image");
    let from3 = render(&dir, "throughput3", &with(&base, &["--roulette", "throughput", "--rr-depth", "3"]));
    let reason = from3.effect("russian-roulette").unwrap();
    assert!(reason.contains("throughput from depth 3"), "{reason}");
    assert!(extension(&from3) < extension(&throughput), "starting earlier stopped no more paths");
    let half = render(&dir, "half", &with(&base, &["--rr", "0.5"]));
    assert!(half.effect("russian-roulette").unwrap().contains("--rr 0.5 < 1"));
    assert!(extension(&half) < extension(&none), "--rr 0.5 stopped no more paths than 0.65");
    let never = render(&dir, "never", &with(&base, &["--rr", "1"]));
    assert_eq!(never.effect("russian-roulette"), None, "--rr 1 left roulette on");
    assert!(extension(&never) > extension(&none), "--rr 1 traced no more extension rays");
    // An OBJ file defaults to throughput: naming it changes nothing, fixed changes the image.
    let obj = scene("cornell_mesh.obj");
    let obj_base = with(&[&obj], &base);
    let obj_none = render(&dir, "obj-none", &obj_base);
    let obj_throughput = render(&dir, "obj-throughput", &with(&obj_base, &["--roulette", "throughput"]));
    assert!(obj_throughput.bits() == obj_none.bits(), "--roulette throughput (an OBJ's default) changed the image");
    let obj_fixed = render(&dir, "obj-fixed", &with(&obj_base, &["--roulette", "fixed"]));
    assert!(obj_fixed.effect("russian-roulette").unwrap().contains("--rr 0.65"));
    assert!(obj_fixed.bits() != obj_none.bits(), "--roulette fixed gave an OBJ's default image");
    let o = run_wavepath(with(&base, &["--roulette", "sometimes", "-f", dir.join("x.png").to_str().unwrap()]));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.trim_end().lines().count() == 1 && err.contains("sometimes"), "{err}");
}

/// The 8-bit value of linear radiance `l` by `curve`, in f64: (the value before rounding, the
/// byte, the value's distance to the nearest rounding boundary). `srgb`: the sRGB encoding of
/// clamp(l, 0, 1), rounded; `cs184`: clamp((sqrt 2 l)^(1/2.2), 0, 1), truncated.
fn expected_byte(curve: &str, l: f64) -> (f64, f64, f64) {
    let l = l.max(0.0);
    let (v, byte, boundary) = if curve == "srgb" {
        let l = l.min(1.0);
        let v = 255.0 * if l <= 0.003_130_8 { 12.92 * l } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 };
        (v, v.round(), 0.5)
    } else {
        let v = 255.0 * (2f64.sqrt() * l).powf(1.0 / 2.2).min(1.0);
        (v, v.floor(), 0.0)
    };
    let f = (v - boundary).rem_euclid(1.0);
    (v, byte, f.min(1.0 - f))
}

/// `--tonemap srgb` writes the standard sRGB curve of clamp(L, 0, 1), rounded, and the
/// default writes the CS184 reference's clamp((sqrt 2 L)^(1/2.2)), truncated. Both PNGs of
/// one render are checked byte by byte against those formulas, evaluated here in f64 on the
/// render's linear radiance (the PFM of the same render: same seed, same pixels), skipping
/// values within 1e-3 of a rounding boundary where f32 and f64 may land apart.
#[test]
fn tonemap_srgb_writes_the_srgb_curve() {
    let dir = temp_dir("flags-tonemap");
    let base = ["-r", "32", "24", "-s", "4", "-m", "3"];
    let linear = render(&dir, "linear", &base);
    let png = |name: &str, extra: &[&str]| {
        let out = dir.join(format!("{name}.png"));
        let o = run_wavepath(with(&with(&base, extra), &["-f", out.to_str().unwrap()]));
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        image::open(&out).unwrap().to_rgb8()
    };
    let cases: [(&str, &[&str], &str); 3] = [
        ("srgb", &["--tonemap", "srgb"], "srgb"),
        ("cs184", &["--tonemap", "cs184"], "cs184"),
        ("default", &[], "cs184"),
    ];
    let mut pngs = vec![];
    for (name, extra, curve) in cases {
        let img = png(name, extra);
        assert_eq!((img.width(), img.height()), (32, 24));
        let mut checked = 0;
        for (x, y, p) in img.enumerate_pixels() {
            let l = linear.image.top_down(x as usize, y as usize);
            for c in 0..3 {
                let (v, byte, margin) = expected_byte(curve, l[c] as f64);
                if margin >= 1e-3 || v == 0.0 || v == 255.0 {
                    assert_eq!(p[c] as f64, byte, "{name}: pixel ({x},{y}) channel {c}, radiance {}", l[c]);
                    checked += 1;
                }
            }
        }
        assert!(checked > 32 * 24 * 3 * 9 / 10, "{name}: {checked} values checked");
        pngs.push(img);
    }
    assert!(pngs[1] == pngs[2], "--tonemap cs184 is not the default");
    let differ = pngs[0].as_raw().iter().zip(pngs[1].as_raw()).filter(|(a, b)| a != b).count();
    assert!(differ > 32 * 24 * 3 / 2, "only {differ} bytes differ between srgb and cs184");
}
