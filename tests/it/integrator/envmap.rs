//! Environment maps through the command line: a bad map is a one-line error, and `info`
//! reports the map.

use crate::common;
use std::path::Path;

/// `-e` with a missing or broken file is a one-line error naming it (damaged maps of every
/// kind: `load::damaged`).
#[test]
fn bad_environment_map_is_a_one_line_error() {
    let dir = common::temp_dir("envmap-bad");
    let text = dir.join("sky.hdr");
    std::fs::write(&text, "this is not a Radiance picture\n").unwrap();
    let empty = dir.join("empty.exr");
    std::fs::write(&empty, b"").unwrap();
    for map in [Path::new("/nonexistent/sky.exr"), &text, &empty] {
        let out = common::run_wavepath([
            "-r",
            "8",
            "8",
            "-e",
            map.to_str().unwrap(),
            "-f",
            dir.join("out.png").to_str().unwrap(),
        ]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(map.to_str().unwrap()), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    assert!(!dir.join("out.png").exists(), "no image for a bad map");
}

/// `info -e` loads the map and reports its size (read from the file's own header) and the
/// effect it turns on; a bad map is the same one-line error as for a render.
#[test]
fn info_reports_the_environment_map() {
    let (Some(map), Some(scene)) =
        (common::scene("envmaps/uffizi_1200x600.hdr"), common::scene("cs184/sky/CBspheres_lambertian.dae"))
    else {
        return;
    };
    let (scene, map) = (scene.to_str().unwrap(), map.to_str().unwrap());
    let out = common::run_wavepath(["info", scene, "-e", map, "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let (w, h) = image::image_dimensions(map).unwrap();
    let env = v["environment"].as_str().unwrap();
    assert!(env.contains(&format!("{w}x{h}")) && env.contains("uffizi"), "{env}");
    assert!(v["effects"].as_array().unwrap().iter().any(|e| e == "environment-map"), "{v}");
    // Without -e the same scene has no map.
    let out = common::run_wavepath(["info", scene, "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(!v["effects"].as_array().unwrap().iter().any(|e| e == "environment-map"), "{v}");
    let out = common::run_wavepath(["info", scene, "-e", "/nonexistent/sky.hdr"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("/nonexistent/sky.hdr") && err.trim().lines().count() == 1, "{err}");
}
