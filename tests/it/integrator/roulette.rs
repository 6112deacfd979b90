//! Russian roulette changes how many paths go on, never what they converge to: the seed's
//! fixed probability and the throughput rule (from any starting depth) agree with no
//! roulette at all on a scene where deep paths carry most of the light.

use crate::common::{agree, render};
use wavepath::Effects;
use wavepath::RouletteKind;
use wavepath::default_scene;

/// The embedded Cornell box at depth 8, 32x24, 64 spp: per 8x8 region, each roulette's mean
/// against no roulette's (the shared z-test of `common::agree`: false failures below 1e-6,
/// fixed seeds).
#[test]
fn every_roulette_converges_to_the_same_image() {
    let scene = default_scene();
    let mut base = render::settings(32, 24, 8, 64);
    base.paths.roulette.continue_prob = 1.0;
    let none = render::wavefront(&scene, &base).0;
    let variants = [
        ("fixed 0.65 from depth 1", base.clone().with(|s| s.paths.roulette.continue_prob = 0.65)),
        ("throughput from depth 1", base.clone().with(|s| s.paths.roulette.kind = RouletteKind::Throughput)),
        (
            "throughput from depth 3",
            base.clone().with(|s| {
                s.paths.roulette.kind = RouletteKind::Throughput;
                s.paths.roulette.start_depth = 3
            }),
        ),
    ];
    for (what, s) in variants {
        let (acc, st) = render::wavefront(&scene, &s);
        let (_, st_none) = render::wavefront(&scene, &base);
        assert!(st.extension_rays < st_none.extension_rays, "{what}: roulette stopped no path");
        agree::assert_regions_agree(&acc, &none, 8, 0.0, what);
    }
}

/// The roulette effect follows the starting depth: from depth `d` it needs `-m d + 2`.
#[test]
fn roulette_runs_only_where_paths_reach_its_depth() {
    let scene = default_scene();
    let s = |m: u32, rr_depth: u32| {
        render::settings(8, 6, m, 1).with(|s| {
            s.paths.roulette.kind = RouletteKind::Throughput;
            s.paths.roulette.start_depth = rr_depth
        })
    };
    assert!(Effects::of(&scene, &s(3, 1)).russian_roulette);
    assert!(!Effects::of(&scene, &s(6, 5)).russian_roulette);
    assert!(Effects::of(&scene, &s(7, 5)).russian_roulette);
}

/// The command line's default roulette follows the file: the seed's fixed 0.65 from the
/// second bounce for `.dae` (the CS184 pictures), throughput from depth 5 for other formats
/// (the same scene, written as OBJ); the stats say which ran.
#[test]
fn the_default_roulette_follows_the_format() {
    let dir = crate::common::temp_dir("roulette-default");
    let scenes = crate::common::repo_root().join("scenes");
    for (file, want) in [("cornell_mesh.dae", "--rr 0.65"), ("cornell_mesh.obj", "throughput from depth 5")] {
        let stats = dir.join("s.json");
        let path = scenes.join(file);
        let o = crate::common::run_wavepath([
            path.to_str().unwrap(),
            "-r",
            "16",
            "12",
            "-m",
            "8",
            "--stats",
            stats.to_str().unwrap(),
            "-f",
            dir.join("o.pfm").to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        let reasons = json["effect_reasons"].as_array().unwrap();
        let reason = reasons
            .iter()
            .find(|e| e["name"] == "russian-roulette")
            .and_then(|e| e["reason"].as_str())
            .unwrap_or_default();
        assert!(reason.contains(want), "{file}: {reason} ({})", json["effect_reasons"]);
    }
}
