//! The defaults that depend on the kind of file come from the library, once: for every
//! format, the settings the command line renders with (its `--stats`) and those `wavepath
//! info` reports equal `Settings::for_scene` of the loaded scene, and both are the dialect's
//! rule written out here: CS184 scenes (.dae, the embedded one) fixed roulette from depth 1
//! and independent numbers, every other file throughput roulette from depth 5 and Sobol.

use crate::common;
use serde_json::Value;
use std::path::PathBuf;
use wavepath::{LoadOptions, Settings, default_scene, load};

fn json(path: &std::path::Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// (sampler, roulette kind, roulette start depth) as the JSON reports them.
fn policy(sampler: &Value, roulette: &Value) -> (String, String, u64) {
    (
        sampler.as_str().unwrap().to_string(),
        roulette["kind"].as_str().unwrap().to_string(),
        roulette["start_depth"].as_u64().unwrap(),
    )
}

fn of_settings(s: &Settings) -> (String, String, u64) {
    let r = &s.paths.roulette;
    (s.sampling.sampler.name().to_string(), r.kind.name().to_string(), r.start_depth as u64)
}

#[test]
fn command_line_and_info_use_the_librarys_defaults_for_every_format() {
    let dir = common::temp_dir("dialect-defaults");
    let scenes = common::repo_root().join("scenes");
    // A binary PLY of the same box, written here (the repository keeps none).
    let ply = dir.join("cornell.ply");
    let cornell = load(&scenes.join("cornell_mesh.obj"), &LoadOptions::default()).unwrap();
    wavepath::write_ply(&ply, &cornell.mesh.positions, &cornell.mesh.triangles).unwrap();
    let mut cases: Vec<(Option<PathBuf>, &str, bool)> = vec![
        (Some(scenes.join("cornell_mesh.dae")), "collada", true),
        (Some(scenes.join("cornell_mesh.obj")), "tobj", false),
        (Some(ply), "ply-bulk", false),
        (Some(scenes.join("cornell_mesh.gltf")), "gltf", false),
        (None, "embedded", true),
    ];
    if let Some(glb) = common::scene("gltf/BoxTextured.glb") {
        cases.push((Some(glb), "gltf", false));
    }
    let cs184 = ("independent".to_string(), "fixed".to_string(), 1);
    let standard = ("sobol".to_string(), "throughput".to_string(), 5);
    for (file, reader, is_cs184) in cases {
        let what = file.as_ref().map_or("the embedded scene".to_string(), |p| p.display().to_string());
        let scene = match &file {
            Some(p) => load(p, &LoadOptions::default()).unwrap(),
            None => default_scene(),
        };
        let library = of_settings(&Settings::for_scene(&scene));
        assert_eq!(library, if is_cs184 { cs184.clone() } else { standard.clone() }, "{what}: the dialect's rule");

        let stats = dir.join("s.json");
        let mut args: Vec<String> = file.iter().map(|p| p.display().to_string()).collect();
        args.extend(
            ["-r", "8", "6", "--stats", stats.to_str().unwrap(), "-f", dir.join("o.pfm").to_str().unwrap()]
                .map(String::from),
        );
        let o = common::run_wavepath(&args);
        assert!(o.status.success(), "{what}: {}", String::from_utf8_lossy(&o.stderr));
        let st = json(&stats);
        assert_eq!(policy(&st["sampler"], &st["roulette"]), library, "{what}: the render's settings");
        assert_eq!(st["reader"], reader, "{what}: reader in the stats");
        assert!(String::from_utf8_lossy(&o.stderr).contains(&format!("({reader} reader,")), "{what}: load line");

        if let Some(p) = &file {
            let o = common::run_wavepath(["info", "--json", p.to_str().unwrap()]);
            assert!(o.status.success(), "{what}: {}", String::from_utf8_lossy(&o.stderr));
            let info: Value = serde_json::from_slice(&o.stdout).unwrap();
            assert_eq!(policy(&info["defaults"]["sampler"], &info["defaults"]["roulette"]), library, "{what}: info");
            assert_eq!(info["reader"], reader, "{what}: reader in info");
        }
    }
}

/// Flags given on the command line override the dialect's defaults, each on its own.
#[test]
fn explicit_flags_override_the_dialects_defaults() {
    let dir = common::temp_dir("dialect-flags");
    let dae = common::repo_root().join("scenes/cornell_mesh.dae");
    let stats = dir.join("s.json");
    let run = |extra: &[&str]| {
        let mut args = vec![dae.to_str().unwrap(), "-r", "8", "6", "--stats", stats.to_str().unwrap()];
        let out = dir.join("o.pfm");
        args.extend(["-f", out.to_str().unwrap()]);
        args.extend(extra);
        let o = common::run_wavepath(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let st = json(&stats);
        policy(&st["sampler"], &st["roulette"])
    };
    let p = |s: &str, k: &str, d| (s.to_string(), k.to_string(), d);
    assert_eq!(run(&[]), p("independent", "fixed", 1));
    assert_eq!(run(&["--sampler", "sobol"]), p("sobol", "fixed", 1));
    assert_eq!(run(&["--roulette", "throughput"]), p("independent", "throughput", 5));
    assert_eq!(run(&["--rr-depth", "3"]), p("independent", "fixed", 3));
}
