//! Split renders: parts merged by `wavepath merge` must give the single-process image
//! (bit for bit for tiles, up to summation order for sample ranges), and every way of
//! handing merge the wrong parts must be refused with one line naming the part.

use crate::common::{self, run_wavepath, temp_dir};
use std::path::{Path, PathBuf};
use std::process::Command;
use wavepath::Settings;
use wavepath::default_scene;
use wavepath_apps::parts::{PartSpec, Split, merge_files, render_part};

fn ok(args: &[&str]) {
    let o = run_wavepath(args);
    assert!(o.status.success(), "wavepath {args:?} failed: {}", String::from_utf8_lossy(&o.stderr));
}

/// Runs a merge that must fail; returns its one-line message.
fn refused(args: &[&str]) -> String {
    let o = run_wavepath(args);
    assert!(!o.status.success(), "wavepath {args:?} should have failed");
    let err = String::from_utf8_lossy(&o.stderr).trim().to_string();
    assert_eq!(err.lines().count(), 1, "not one line: {err}");
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Linear pixels of an EXR as f32 bits (independent of wavepath's own reader).
fn exr_bits(p: &Path) -> Vec<u32> {
    let img = image::open(p).unwrap().into_rgb32f();
    img.into_raw().into_iter().map(f32::to_bits).collect()
}

/// Renders `base` split `n` ways and merges; returns (single, merged) image paths.
fn split_and_merge(dir: &Path, base: &[&str], n: u32, split: &str) -> (PathBuf, PathBuf) {
    let single = dir.join("single.exr");
    let mut a = base.to_vec();
    a.extend(["-f", s(&single)]);
    ok(&a);
    let mut parts = Vec::new();
    for i in 0..n {
        let p = dir.join(format!("part-{i}.exr"));
        let label = format!("{i}/{n}");
        let mut a = base.to_vec();
        a.extend(["--split", split, "--part", &label, "-f", s(&p)]);
        ok(&a);
        parts.push(p);
    }
    let merged = dir.join("merged.exr");
    let mut a = vec!["merge"];
    // Reverse order: the merge must not depend on the order parts are given.
    a.extend(parts.iter().rev().map(|p| s(p)));
    a.extend(["-f", s(&merged)]);
    ok(&a);
    (single, merged)
}

#[test]
fn tile_parts_merge_bit_identical_to_one_process() {
    let dir = temp_dir("parts-tiles");
    let base = ["-s", "4", "-m", "3", "-r", "64", "48", "--seed", "7"];
    for n in [1, 2, 3, 4, 7] {
        let (single, merged) = split_and_merge(&dir, &base, n, "tiles");
        assert_eq!(exr_bits(&single), exr_bits(&merged), "{n} parts");
    }
    // Adaptive sampling decides per pixel, so it splits by tiles exactly too.
    let adaptive = ["-s", "64", "-a", "8", "0.1", "-m", "2", "-r", "40", "30"];
    let (single, merged) = split_and_merge(&dir, &adaptive, 3, "tiles");
    assert_eq!(exr_bits(&single), exr_bits(&merged), "adaptive");
    assert_eq!(
        std::fs::read(dir.join("single_rate.png")).unwrap(),
        std::fs::read(dir.join("merged_rate.png")).unwrap()
    );
    // And the recursive reference.
    let rec = ["-s", "2", "-m", "3", "-r", "32", "24", "--integrator", "recursive"];
    let (single, merged) = split_and_merge(&dir, &rec, 2, "tiles");
    assert_eq!(exr_bits(&single), exr_bits(&merged), "recursive");
}

/// For sample ranges the merge adds each pixel's per-part f64 sums, the single process adds
/// the samples one by one. Radiance is non-negative, so both are within (n-1) u T of the
/// exact sum T (u = 2^-53, n samples): they differ by at most 2 (n-1) u T, far below half an
/// f32 ulp, so a merged f32 mean equals the single one or is its neighbour (1 ulp).
#[test]
fn sample_parts_merge_within_the_summation_order_bound() {
    let dir = temp_dir("parts-samples");
    let scene = default_scene();
    let mut st = Settings::default();
    st.image.width = 48;
    st.image.height = 36;
    st.sampling.spp = 24;
    st.paths.max_depth = 4;
    st.paths.shading = wavepath::Shading::Global;
    let (bvh, _) = wavepath::build_accel(&scene, &Settings::default());
    let (single, _) = wavepath::render_sums(&scene, bvh.as_ref(), &st, &|_| {}).unwrap();
    let n = 5;
    let mut files = Vec::new();
    for i in 0..n {
        let spec = PartSpec::new(i, n, Split::Samples).unwrap();
        let (acc, stats) = render_part(&scene, bvh.as_ref(), &st, &spec, &|_| {}).unwrap();
        let meta = wavepath_apps::parts::PartMeta {
            format: wavepath_apps::parts::file::FORMAT,
            part: spec,
            scene: scene.name.clone(),
            scene_hash: wavepath_apps::parts::identity::scene_hash(&scene),
            settings: wavepath_apps::parts::identity::settings_key(&st),
            width: st.image.width,
            height: st.image.height,
            spp: st.sampling.spp,
            adaptive: st.sampling.adaptive.is_some(),
            stats,
            pixels: String::new(),
        };
        let p = dir.join(format!("s{i}.exr"));
        wavepath_apps::parts::file::write(&p, &meta, &acc).unwrap();
        files.push(p);
    }
    let merged = merge_files(&files).unwrap();
    let bound = 2.0 * (st.sampling.spp as f64 - 1.0) * f64::EPSILON / 2.0;
    let (mut same, mut neighbours) = (0, 0);
    let (fa, fb) = (single.to_film(), merged.acc.to_film());
    for (i, (a, b)) in single.pixels.iter().zip(&merged.acc.pixels).enumerate() {
        assert_eq!((a.taken, a.valid), (b.taken, b.valid), "pixel {i}: sample counts");
        let pairs = [(a.sum.x, b.sum.x), (a.sum.y, b.sum.y), (a.sum.z, b.sum.z), (a.s1, b.s1), (a.s2, b.s2)];
        for (x, y) in pairs {
            assert!((x - y).abs() <= bound * x.abs().max(y.abs()), "pixel {i}: {x} vs {y}");
        }
        for (x, y) in fa.pixels[i].to_array().into_iter().zip(fb.pixels[i].to_array()) {
            let d = (x.to_bits() as i64 - y.to_bits() as i64).abs();
            assert!(d <= 1, "pixel {i}: {x} vs {y} differ by {d} ulp");
            if d == 0 { same += 1 } else { neighbours += 1 }
        }
    }
    // Most pixels round to the very same f32; the rest by one step.
    assert!(same > 10 * neighbours, "{same} identical channels, {neighbours} one ulp apart");
    // Every sample index was taken exactly once across the parts.
    assert!(merged.acc.pixels.iter().all(|p| p.taken == st.sampling.spp));
}

#[test]
fn wrong_parts_are_refused_naming_the_part() {
    let dir = temp_dir("parts-refuse");
    let d = |n: &str| dir.join(n);
    let base = ["-s", "3", "-m", "2", "-r", "32", "24"];
    let part = |extra: &[&str], label: &str, out: &Path| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        a.extend(["--part", label, "-f", s(out)]);
        ok(&a);
    };
    for i in 0..3 {
        part(&[], &format!("{i}/3"), &d(&format!("p{i}.exr")));
    }
    let (p0, p1, p2) = (d("p0.exr"), d("p1.exr"), d("p2.exr"));
    ok(&["merge", s(&p0), s(&p1), s(&p2), "-f", s(&d("ok.png"))]);

    let e = refused(&["merge", s(&p0), s(&p2), "-f", s(&d("x.png"))]);
    assert!(e.contains("part 1/3 is missing"), "{e}");
    let e = refused(&["merge", s(&p0), s(&p1), s(&p1), s(&p2), "-f", s(&d("x.png"))]);
    assert!(e.contains("p1.exr") && e.contains("twice"), "{e}");

    // A copy of a part under another name is still the same part.
    std::fs::copy(&p1, d("copy.exr")).unwrap();
    let e = refused(&["merge", s(&p0), s(&p1), s(&d("copy.exr")), s(&p2), "-f", s(&d("x.png"))]);
    assert!(e.contains("copy.exr") && e.contains("twice"), "{e}");

    // Different settings, different N, different split, different scene.
    part(&["--seed", "3"], "1/3", &d("seed.exr"));
    let e = refused(&["merge", s(&p0), s(&d("seed.exr")), s(&p2), "-f", s(&d("x.png"))]);
    assert!(e.contains("seed.exr") && e.contains("settings"), "{e}");
    part(&[], "1/4", &d("n4.exr"));
    let e = refused(&["merge", s(&p0), s(&d("n4.exr")), s(&p2), "-f", s(&d("x.png"))]);
    assert!(e.contains("n4.exr") && e.contains("number of parts"), "{e}");
    part(&["--split", "samples"], "1/3", &d("samples.exr"));
    let e = refused(&["merge", s(&p0), s(&d("samples.exr")), s(&p2), "-f", s(&d("x.png"))]);
    assert!(e.contains("samples.exr") && e.contains("split"), "{e}");
    if let Some(cb) = common::scene("cs184/sky/CBspheres_lambertian.dae") {
        let other = d("other.exr");
        let mut a = vec![s(&cb)];
        a.extend(base);
        a.extend(["--part", "1/3", "-f", s(&other)]);
        ok(&a);
        let e = refused(&["merge", s(&p0), s(&d("other.exr")), s(&p2), "-f", s(&d("x.png"))]);
        assert!(e.contains("other.exr") && e.contains("scene"), "{e}");
    }
    // The same scene with another camera (a lens) is a different scene.
    part(&["-b", "0.05"], "1/3", &d("lens.exr"));
    let e = refused(&["merge", s(&p0), s(&d("lens.exr")), s(&p2), "-f", s(&d("x.png"))]);
    assert!(e.contains("lens.exr") && e.contains("scene"), "{e}");

    // Truncated, garbage, empty, and an ordinary EXR that is not a part.
    let bytes = std::fs::read(&p1).unwrap();
    for (name, content) in [
        ("truncated.exr", bytes[..bytes.len() / 2].to_vec()),
        ("garbage.exr", b"this is not an image".repeat(50)),
        ("empty.exr", Vec::new()),
    ] {
        std::fs::write(d(name), content).unwrap();
        let e = refused(&["merge", s(&p0), s(&d(name)), s(&p2), "-f", s(&d("x.png"))]);
        assert!(e.contains(name), "{e}");
    }
    let plain = d("plain.exr");
    let mut a = base.to_vec();
    a.extend(["-f", s(&plain)]);
    ok(&a);
    let e = refused(&["merge", s(&p0), s(&d("plain.exr")), s(&p2), "-f", s(&d("x.png"))]);
    assert!(e.contains("plain.exr") && e.contains("not a wavepath part"), "{e}");
    let e = refused(&["merge", s(&p0), s(&d("nonexistent.exr")), s(&p2), "-f", s(&d("x.png"))]);
    assert!(e.contains("nonexistent.exr"), "{e}");
    assert!(!d("x.png").exists(), "a refused merge wrote an image");
}

#[test]
fn part_flags_are_checked() {
    let dir = temp_dir("parts-flags");
    let out = dir.join("p.exr");
    let o = s(&out);
    for (args, says) in [
        (vec!["-s", "8", "-a", "4", "0.1", "--split", "samples", "--part", "0/2", "-f", o], "adaptive"),
        (vec!["-s", "2", "--split", "samples", "--part", "0/4", "-f", o], "at least 4 samples"),
        (vec!["--part", "2/2", "-f", o], "below the number of parts"),
        (vec!["--part", "1-2", "-f", o], "I/N"),
        (vec!["--part", "0/2", "-f", s(&dir.join("p.png"))], "OpenEXR"),
        (vec!["--part", "0/2", "-p", "0", "0", "4", "4", "-f", o], "-p"),
    ] {
        let e = refused(&args);
        assert!(e.contains(says), "{args:?}: {e}");
    }
    // `auto` outside a scheduler has nothing to go on; inside one it reads the environment.
    let o2 = run_wavepath(["--part", "auto", "-f", o]);
    assert!(!o2.status.success());
    let env_run = |vars: &[(&str, &str)], out: &Path| {
        let mut c = Command::new(common::wavepath_bin());
        c.args(["-s", "2", "-r", "16", "12", "--part", "auto", "-f", s(out)]);
        for k in [
            "SLURM_ARRAY_TASK_ID",
            "SLURM_ARRAY_TASK_MIN",
            "SLURM_ARRAY_TASK_COUNT",
            "JOB_COMPLETION_INDEX",
            "WAVEPATH_PARTS",
        ] {
            c.env_remove(k);
        }
        c.envs(vars.iter().copied());
        let r = c.output().unwrap();
        assert!(r.status.success(), "{vars:?}: {}", String::from_utf8_lossy(&r.stderr));
    };
    env_run(&[("SLURM_ARRAY_TASK_ID", "0"), ("SLURM_ARRAY_TASK_COUNT", "2")], &dir.join("a.exr"));
    env_run(&[("JOB_COMPLETION_INDEX", "1"), ("WAVEPATH_PARTS", "2")], &dir.join("b.exr"));
    ok(&["merge", s(&dir.join("b.exr")), s(&dir.join("a.exr")), "-f", s(&dir.join("ab.exr"))]);
    ok(&["-s", "2", "-r", "16", "12", "-f", s(&dir.join("one.exr"))]);
    assert_eq!(exr_bits(&dir.join("one.exr")), exr_bits(&dir.join("ab.exr")));
}

/// A writer that fails after `left` bytes, as a full disk does part-way through a file.
struct FailsAfter {
    inner: std::fs::File,
    left: usize,
}

impl std::io::Write for FailsAfter {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.left == 0 {
            return Err(std::io::Error::other("no space left on device (injected)"));
        }
        let n = buf.len().min(self.left);
        self.left -= n;
        self.inner.write(&buf[..n])
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// A part whose write fails part-way leaves nothing under its name, keeps the previous
/// part there intact, and leaves no temporary file; a re-run replaces a part in one step.
#[test]
fn failed_part_writes_leave_nothing_and_reruns_replace_atomically() {
    use wavepath_apps::parts::file::{read, write_via};
    let dir = temp_dir("parts-kill");
    let out = dir.join("p0.exr");
    ok(&["-s", "2", "-r", "16", "12", "--part", "0/2", "-f", s(&out)]);
    let before = std::fs::read(&out).unwrap();
    let part = read(&out).unwrap();
    for (target, cut) in [(dir.join("fresh.exr"), 100), (out.clone(), before.len() / 2)] {
        let e = write_via(&target, &part.meta, &part.acc, |f| Box::new(FailsAfter { inner: f, left: cut }))
            .expect_err("the injected failure is reported");
        assert!(format!("{e:#}").contains("injected"), "{e:#}");
    }
    assert!(!dir.join("fresh.exr").exists(), "a failed write left a part under its final name");
    assert_eq!(std::fs::read(&out).unwrap(), before, "a failed rewrite touched the previous part");

    let base = ["-s", "2", "-r", "16", "12"];
    let part = |extra: &[&str], label: &str, out: &Path| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        a.extend(["--part", label, "-f", s(out)]);
        ok(&a);
    };
    part(&["--seed", "9"], "0/2", &out);
    part(&[], "1/2", &dir.join("p1.exr"));
    let e = refused(&["merge", s(&out), s(&dir.join("p1.exr")), "-f", s(&dir.join("x.exr"))]);
    assert!(e.contains("settings"), "{e}");
    // Re-running the stale part with the right settings replaces it.
    part(&[], "0/2", &out);
    ok(&["merge", s(&out), s(&dir.join("p1.exr")), "-f", s(&dir.join("m.exr"))]);
    let mut names: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    assert!(names.iter().all(|n| !n.starts_with('.') && !n.contains("partial")), "left behind: {names:?}");
    // The same write without the injected failure is a valid part again.
    write_via(&dir.join("again.exr"), &read(&out).unwrap().meta, &read(&out).unwrap().acc, |f| Box::new(f)).unwrap();
    assert!(read(&dir.join("again.exr")).is_ok());
}

/// The merged stats list exactly the stages the single process lists: with direct light
/// only (`-m 1`) there is no bounce stage, and merging must not invent one.
#[test]
fn merged_stats_keep_absent_stages_absent() {
    let dir = temp_dir("parts-stages");
    let stage_keys = |p: &Path| -> Vec<String> {
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap();
        let mut k: Vec<String> = v["stages"].as_object().unwrap().keys().cloned().collect();
        k.sort();
        k
    };
    for m in ["1", "3"] {
        let single_stats = dir.join(format!("single-{m}.json"));
        let base = ["-s", "2", "-m", m, "-r", "32", "24"];
        let single_img = dir.join("single.exr");
        let mut a = base.to_vec();
        a.extend(["-f", s(&single_img), "--stats", s(&single_stats)]);
        ok(&a);
        let mut parts = Vec::new();
        for i in 0..2 {
            let p = dir.join(format!("p{m}-{i}.exr"));
            let label = format!("{i}/2");
            let mut a = base.to_vec();
            a.extend(["--part", &label, "-f", s(&p)]);
            ok(&a);
            parts.push(p);
        }
        let merged_stats = dir.join(format!("merged-{m}.json"));
        ok(&["merge", s(&parts[0]), s(&parts[1]), "-f", s(&dir.join("m.exr")), "--stats", s(&merged_stats)]);
        let (single, merged) = (stage_keys(&single_stats), stage_keys(&merged_stats));
        assert_eq!(single, merged, "-m {m}");
        assert_eq!(single.iter().any(|k| k == "compact"), m != "1", "-m {m}: {single:?}");
    }
}

/// Parts rendered with different thread counts (one with 1, one with 2) merge into the image
/// a single process renders with 2: the thread count is not part of the result.
#[test]
fn parts_rendered_with_different_thread_counts_merge_bit_for_bit() {
    let dir = temp_dir("parts-threads");
    let base = ["-s", "4", "-m", "3", "-r", "64", "48"];
    let run = |extra: &[&str]| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        ok(&a);
    };
    run(&["-t", "1", "--part", "0/2", "-f", s(&dir.join("a.exr"))]);
    run(&["-t", "2", "--part", "1/2", "-f", s(&dir.join("b.exr"))]);
    ok(&["merge", s(&dir.join("a.exr")), s(&dir.join("b.exr")), "-f", s(&dir.join("m.exr"))]);
    run(&["-t", "2", "-f", s(&dir.join("one.exr"))]);
    assert_eq!(exr_bits(&dir.join("one.exr")), exr_bits(&dir.join("m.exr")));
}

/// Pixel data changed after the part was written, in a way the EXR decoder cannot see (a
/// file whose header is another render's): the checksum refuses it, naming the part.
#[test]
fn parts_with_damaged_pixels_are_refused() {
    use wavepath_apps::parts::file::{read, write};
    let dir = temp_dir("parts-damaged");
    let out = dir.join("p0.exr");
    ok(&["-s", "2", "-r", "16", "12", "--part", "0/2", "-f", s(&out)]);
    ok(&["-s", "2", "-r", "16", "12", "--part", "1/2", "-f", s(&dir.join("p1.exr"))]);
    let part = read(&out).unwrap();
    let mut other = part.acc.clone();
    other.pixels[7].sum.x += 0.25;
    let changed = dir.join("changed.exr");
    write(&changed, &part.meta, &other).unwrap();
    let hash = |acc| wavepath_apps::parts::identity::pixels_hash(acc);
    let (good, bad) = (hash(&part.acc), hash(&other));
    assert_ne!(good, bad);
    // The changed pixels under the original header's checksum.
    let bytes = std::fs::read(&changed).unwrap();
    let at = bytes.windows(bad.len()).position(|w| w == bad.as_bytes()).expect("checksum in the header");
    let mut forged = bytes.clone();
    forged[at..at + good.len()].copy_from_slice(good.as_bytes());
    std::fs::write(&changed, &forged).unwrap();
    let e = format!("{:#}", read(&changed).err().expect("a damaged part is refused"));
    assert!(e.contains("changed.exr") && e.contains("checksum"), "{e}");
    let e = refused(&["merge", s(&changed), s(&dir.join("p1.exr")), "-f", s(&dir.join("x.exr"))]);
    assert!(e.contains("changed.exr"), "{e}");
}
