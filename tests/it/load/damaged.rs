//! Damaged files of every format through the binary: truncations, random bytes, huge counts
//! and NaN numbers in OBJ (and its MTL), PLY ascii and binary, glTF (its JSON and its
//! buffer), GLB, COLLADA, HDR and EXR environment maps and part files. Every run ends with
//! success or a non-zero exit and exactly one stderr line that names the damaged file (or the
//! scene that refers to it) — never a panic, a signal or a multi-line dump.
//!
//! The mutations come from a fixed-seed generator, so a failure reproduces; the case number
//! and its kind are in the message.
//!
//! Every damaged scene file that loads (`info` succeeds: about 100 of the 512 cases) is also
//! rendered, tiny (8x6, 1 spp, depth 2, PFM; about 0.2 s in all): the render succeeds and
//! writes an 8x6 image with finite pixels, or fails with one line naming the file.

use crate::common::{self, Xorshift, temp_dir};
use std::path::Path;

/// Cases per source file, cycling through the four kinds of damage.
const CASES: usize = 64;

#[derive(Clone, Copy, Debug)]
enum Damage {
    Truncate,
    RandomBytes,
    HugeCount,
    NotANumber,
}

const KINDS: [Damage; 4] = [Damage::Truncate, Damage::RandomBytes, Damage::HugeCount, Damage::NotANumber];

/// Byte ranges of the decimal numbers in `b` (text formats).
fn numbers(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() {
            let start = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.' || b[i] == b'e') {
                i += 1;
            }
            out.push((start, i));
        }
        i += 1;
    }
    out
}

fn damage(src: &[u8], kind: Damage, text: bool, rng: &mut Xorshift) -> Vec<u8> {
    let mut b = src.to_vec();
    let splice = |b: &mut Vec<u8>, (s, e): (usize, usize), with: &[u8]| {
        b.splice(s..e, with.iter().copied());
    };
    match kind {
        Damage::Truncate => b.truncate(rng.below(b.len())),
        Damage::RandomBytes => {
            for _ in 0..1 + rng.below(8) {
                let i = rng.below(b.len());
                b[i] = rng.next() as u8;
            }
        }
        Damage::HugeCount if text => {
            let nums = numbers(&b);
            let with: &[&[u8]] = &[b"4294967296", b"99999999999999999999", b"2147483647", b"-1"];
            let at = nums[rng.below(nums.len())];
            splice(&mut b, at, with[rng.below(with.len())]);
        }
        Damage::NotANumber if text => {
            let nums = numbers(&b);
            let with: &[&[u8]] = &[b"nan", b"inf", b"-1e999", b"NaN", b"1e40"];
            let at = nums[rng.below(nums.len())];
            splice(&mut b, at, with[rng.below(with.len())]);
        }
        Damage::HugeCount | Damage::NotANumber => {
            // Binary: an aligned 32-bit word set to a huge count or a NaN / Inf float.
            let words: [u32; 4] = match kind {
                Damage::HugeCount => [u32::MAX, 0x7fff_ffff, 0x8000_0000, 0x1000_0000],
                _ => [f32::NAN.to_bits(), f32::INFINITY.to_bits(), f32::NEG_INFINITY.to_bits(), 0x7f80_0001],
            };
            for _ in 0..1 + rng.below(4) {
                let i = rng.below(b.len() / 4) * 4;
                let w = words[rng.below(4)].to_le_bytes();
                let n = (b.len() - i).min(4);
                b[i..i + n].copy_from_slice(&w[..n]);
            }
        }
    }
    b
}

/// One damaged input: the file written at `target` (its siblings copied intact), and the
/// command that reads it.
struct Format {
    what: &'static str,
    /// The file to damage and its name in the case folder.
    source: Vec<u8>,
    name: &'static str,
    /// Other files the case needs, intact (name, bytes).
    siblings: Vec<(&'static str, Vec<u8>)>,
    text: bool,
    /// The arguments, with `{}` standing for the case folder.
    args: Vec<String>,
    /// File names an error may name (the damaged file, or the scene that refers to it).
    names: Vec<&'static str>,
    /// Where a run succeeds, the file it writes (in the case folder) and the bytes it must
    /// have: damage that goes through may not change the result.
    output: Option<(&'static str, Vec<u8>)>,
}

/// The render of a loading scene case: `info`'s scene, tiny, into `{}/render.pfm`.
fn render_args(f: &Format) -> Option<Vec<String>> {
    (f.args.first().map(String::as_str) == Some("info")).then(|| {
        let mut a = f.args[1..].to_vec();
        a.extend(args(&["-r", "8", "6", "-s", "1", "-m", "2", "-f", "{}/render.pfm"]));
        a
    })
}

/// Renders a case that loaded (see the module comment): success with a finite 8x6 image, or
/// one line naming the file. Returns whether it rendered.
fn render_case(f: &Format, dir: &Path, what: &str) -> bool {
    let Some(list) = render_args(f) else { return false };
    let args: Vec<String> = list.iter().map(|a| a.replace("{}", dir.to_str().unwrap())).collect();
    let out = common::run_wavepath(&args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.code().is_some(), "{what}, rendered: killed by a signal; stderr: {err}");
    assert!(!err.contains("panicked"), "{what}, rendered: {err}");
    if out.status.success() {
        let image = common::pfm::read_pfm(&dir.join("render.pfm"));
        assert_eq!((image.width, image.height), (8, 6), "{what}, rendered");
        assert!(image.pixels.iter().flatten().all(|c| c.is_finite()), "{what}, rendered: a NaN or Inf pixel");
        true
    } else {
        let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error") || !l.starts_with("[wavepath]")).collect();
        assert!(
            lines.len() == 1 && f.names.iter().any(|n| lines[0].contains(n)),
            "{what}, rendered: expected one error line naming one of {:?}, got:\n{err}",
            f.names
        );
        false
    }
}

/// What a format's cases did: refused, loaded, and of the loaded ones how many rendered (the
/// others failed with one line naming the file).
#[derive(Default)]
struct Outcome {
    refused: usize,
    loaded: usize,
    rendered: usize,
}

fn run_cases(f: &Format, root: &Path, seed: u64) -> Outcome {
    let mut rng = Xorshift(seed);
    let mut n = Outcome::default();
    for case in 0..CASES {
        let kind = KINDS[case % KINDS.len()];
        let dir = root.join(format!("{}-{case}", f.what.replace(' ', "_")));
        std::fs::create_dir_all(&dir).unwrap();
        for (n, b) in &f.siblings {
            std::fs::write(dir.join(n), b).unwrap();
        }
        std::fs::write(dir.join(f.name), damage(&f.source, kind, f.text, &mut rng)).unwrap();
        let args: Vec<String> = f.args.iter().map(|a| a.replace("{}", dir.to_str().unwrap())).collect();
        let out = common::run_wavepath(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        let what = format!("{} case {case} ({kind:?})", f.what);
        assert!(out.status.code().is_some(), "{what}: killed by a signal; stderr: {err}");
        assert!(!err.contains("panicked"), "{what}: {err}");
        if out.status.success() {
            n.loaded += 1;
            if let Some((file, want)) = &f.output {
                assert!(std::fs::read(dir.join(file)).unwrap() == *want, "{what}: loaded, but {file} differs");
            }
            n.rendered += usize::from(render_case(f, &dir, &what));
        } else {
            n.refused += 1;
            let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
            assert_eq!(lines.len(), 1, "{what}: expected one line, got:\n{err}");
            assert!(
                f.names.iter().any(|n| lines[0].contains(n)),
                "{what}: the error names none of {:?}: {err}",
                f.names
            );
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    n
}

fn authored(name: &str) -> Vec<u8> {
    std::fs::read(crate::common::repo_root().join("scenes").join(name)).unwrap()
}

fn args(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// The authored Cornell box's triangles as PLY, ascii or binary little endian.
fn ply(binary: bool) -> Vec<u8> {
    let scene =
        wavepath::load(&crate::common::repo_root().join("scenes/cornell_mesh.obj"), &wavepath::LoadOptions::default())
            .unwrap();
    let m = &scene.mesh;
    let format = if binary { "binary_little_endian" } else { "ascii" };
    let mut out = format!(
        "ply\nformat {format} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        m.positions.len(),
        m.triangles.len()
    )
    .into_bytes();
    for p in &m.positions {
        if binary {
            for c in p.to_array() {
                out.extend(c.to_le_bytes());
            }
        } else {
            out.extend(format!("{} {} {}\n", p.x, p.y, p.z).bytes());
        }
    }
    for t in &m.triangles {
        if binary {
            out.push(3);
            for i in t {
                out.extend((*i as i32).to_le_bytes());
            }
        } else {
            out.extend(format!("3 {} {} {}\n", t[0], t[1], t[2]).bytes());
        }
    }
    out
}

/// An 8x4 environment map in `ext` (hdr or exr), a gradient.
fn envmap(dir: &Path, ext: &str) -> Vec<u8> {
    let img = image::Rgb32FImage::from_fn(8, 4, |x, y| image::Rgb([x as f32 * 0.5, y as f32, 1.0]));
    let p = dir.join(format!("map.{ext}"));
    image::DynamicImage::ImageRgb32F(img).save(&p).unwrap();
    std::fs::read(p).unwrap()
}

#[test]
fn damaged_scene_files_fail_with_one_line_through_the_binary() {
    let root = temp_dir("damaged-scenes");
    let obj = authored("cornell_mesh.obj");
    let mtl = authored("cornell_mesh.mtl");
    let gltf = authored("cornell_mesh.gltf");
    let bin = authored("cornell_mesh.bin");
    let info = |name: &str| args(&["info", &format!("{{}}/{name}")]);
    let mut formats = vec![
        Format {
            what: "obj",
            source: obj.clone(),
            name: "cornell_mesh.obj",
            siblings: vec![("cornell_mesh.mtl", mtl.clone())],
            text: true,
            args: info("cornell_mesh.obj"),
            names: vec!["cornell_mesh.obj"],
            output: None,
        },
        Format {
            what: "mtl",
            source: mtl,
            name: "cornell_mesh.mtl",
            siblings: vec![("cornell_mesh.obj", obj)],
            text: true,
            args: info("cornell_mesh.obj"),
            names: vec!["cornell_mesh.mtl", "cornell_mesh.obj"],
            output: None,
        },
        Format {
            what: "ply ascii",
            source: ply(false),
            name: "m.ply",
            siblings: vec![],
            text: true,
            args: info("m.ply"),
            names: vec!["m.ply"],
            output: None,
        },
        Format {
            what: "ply binary",
            source: ply(true),
            name: "m.ply",
            siblings: vec![],
            text: false,
            args: info("m.ply"),
            names: vec!["m.ply"],
            output: None,
        },
        Format {
            what: "gltf json",
            source: gltf.clone(),
            name: "cornell_mesh.gltf",
            siblings: vec![("cornell_mesh.bin", bin.clone())],
            text: true,
            args: info("cornell_mesh.gltf"),
            names: vec!["cornell_mesh.gltf"],
            output: None,
        },
        Format {
            what: "gltf buffer",
            source: bin,
            name: "cornell_mesh.bin",
            siblings: vec![("cornell_mesh.gltf", gltf)],
            text: false,
            args: info("cornell_mesh.gltf"),
            names: vec!["cornell_mesh.gltf", "cornell_mesh.bin"],
            output: None,
        },
        Format {
            what: "dae",
            source: authored("cornell_mesh.dae"),
            name: "cornell_mesh.dae",
            siblings: vec![],
            text: true,
            args: info("cornell_mesh.dae"),
            names: vec!["cornell_mesh.dae"],
            output: None,
        },
    ];
    if let Some(glb) = common::scene("gltf/BoxTextured.glb") {
        formats.push(Format {
            what: "glb",
            source: std::fs::read(glb).unwrap(),
            name: "box.glb",
            siblings: vec![],
            text: false,
            args: info("box.glb"),
            names: vec!["box.glb"],
            output: None,
        });
    }
    check_all(&formats, &root);
}

#[test]
fn damaged_environment_maps_and_part_files_fail_with_one_line_through_the_binary() {
    let root = temp_dir("damaged-maps");
    let (hdr, exr) = (envmap(&root, "hdr"), envmap(&root, "exr"));
    // Two parts of a tiny render, the second damaged in each case.
    let part = |i: u32| {
        let p = root.join(format!("part{i}.exr"));
        let out = common::run_wavepath(["-r", "8", "6", "--part", &format!("{i}/2"), "-f", p.to_str().unwrap()]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        std::fs::read(p).unwrap()
    };
    let (p0, p1) = (part(0), part(1));
    let intact = root.join("intact.exr");
    let merged = common::run_wavepath([
        "merge",
        root.join("part0.exr").to_str().unwrap(),
        root.join("part1.exr").to_str().unwrap(),
        "-f",
        intact.to_str().unwrap(),
    ]);
    assert!(merged.status.success());
    let formats = vec![
        Format {
            what: "hdr",
            source: hdr,
            name: "map.hdr",
            siblings: vec![],
            text: false,
            args: args(&["-r", "4", "3", "-e", "{}/map.hdr", "-f", "{}/out.png"]),
            names: vec!["map.hdr"],
            output: None,
        },
        Format {
            what: "exr",
            source: exr,
            name: "map.exr",
            siblings: vec![],
            text: false,
            args: args(&["-r", "4", "3", "-e", "{}/map.exr", "-f", "{}/out.png"]),
            names: vec!["map.exr"],
            output: None,
        },
        Format {
            what: "part",
            source: p1,
            name: "part1.exr",
            siblings: vec![("part0.exr", p0)],
            text: false,
            args: args(&["merge", "{}/part0.exr", "{}/part1.exr", "-f", "{}/out.exr"]),
            names: vec!["part1.exr"],
            output: Some(("out.exr", std::fs::read(&intact).unwrap())),
        },
    ];
    check_all(&formats, &root);
}

/// Runs every format's cases, the formats side by side; each format must have refused some
/// of its damaged files (else the damage missed what the reader checks).
fn check_all(formats: &[Format], root: &Path) {
    let results: Vec<Outcome> = std::thread::scope(|s| {
        let handles: Vec<_> = formats
            .iter()
            .enumerate()
            .map(|(i, f)| s.spawn(move || run_cases(f, root, 0x2545_f491_4f6c_dd1d ^ ((i as u64 + 1) * 0x9e37_79b9))))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let mut rendered_total = 0;
    for (f, n) in formats.iter().zip(results) {
        let Outcome { refused, loaded, rendered } = n;
        eprintln!("{}: {refused} refused, {loaded} loaded, {rendered} of those rendered", f.what);
        assert!(refused >= CASES / 4, "{}: only {refused} of {CASES} damaged files refused", f.what);
        rendered_total += rendered;
    }
    // The scene formats load some damaged files (a changed number, a cut comment) and
    // render most of them: if none rendered, the renders would test nothing.
    if formats.iter().any(|f| render_args(f).is_some()) {
        assert!(rendered_total >= 50, "only {rendered_total} damaged scenes rendered");
    }
}
