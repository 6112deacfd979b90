//! Ray files: format, bad input, the renderer's own rays, and the peers' trace protocol.

use crate::common::meshgen::{icosphere, scene_of};
use crate::common::{self, temp_dir};
use glam::Vec3;
use std::process::Command;
use wavepath::Ray;
use wavepath::{Bvh, Intersector, TraceCounters};
use wavepath::{diffuse_rays, primary_rays};
use wavepath_apps::rayfile::file::{HitRecord, parse_rays, read_hits, read_rays, write_rays};
use wavepath_apps::rayfile::trace_all;

#[test]
fn ray_file_round_trip_and_layout() {
    let rays = vec![
        Ray { origin: Vec3::new(1.0, 2.0, 3.0), dir: Vec3::new(0.0, -0.0, 1.0), tmin: 0.5, tmax: f32::INFINITY },
        Ray::new(Vec3::splat(-1e5), Vec3::new(1e-30, 2.0, -3.0)),
    ];
    let p = temp_dir("rays-round-trip").join("rt.bin");
    write_rays(&p, &rays).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(bytes.len(), 16 + 32 * 2);
    assert_eq!(&bytes[0..4], b"RAYS");
    assert_eq!(u32::from_le_bytes(bytes[4..8].try_into().unwrap()), 1);
    assert_eq!(u64::from_le_bytes(bytes[8..16].try_into().unwrap()), 2);
    // Record order: ox oy oz tmin dx dy dz tmax.
    let f = |i: usize| f32::from_le_bytes(bytes[16 + 4 * i..20 + 4 * i].try_into().unwrap());
    assert_eq!([f(0), f(1), f(2), f(3), f(4), f(6), f(7)], [1.0, 2.0, 3.0, 0.5, 0.0, 1.0, f32::INFINITY]);
    assert!(f(5).is_sign_negative());
    let back = read_rays(&p).unwrap();
    assert_eq!(back.len(), 2);
    for (a, b) in back.iter().zip(&rays) {
        assert_eq!(format!("{a:?}"), format!("{b:?}"));
    }
}

#[test]
fn bad_ray_files_give_one_line_errors() {
    let p = std::path::Path::new("bad.bin");
    let mut good = b"RAYS".to_vec();
    good.extend(1u32.to_le_bytes());
    good.extend(3u64.to_le_bytes());
    good.extend([0u8; 32 * 2]);
    for (bytes, what) in [
        (&good[..10], "truncated"),
        (&b"RAYZ\x01\0\0\0\0\0\0\0\0\0\0\0"[..], "magic"),
        (&good[..], "header says 3 rays"),
        (&[b"RAYS".as_slice(), &2u32.to_le_bytes(), &0u64.to_le_bytes()].concat()[..], "version"),
    ] {
        let e = parse_rays(p, bytes).unwrap_err().to_string();
        assert!(e.starts_with("bad.bin: ") && e.contains(what) && !e.contains('\n'), "{e}");
    }
    let mut huge = b"RAYS".to_vec();
    huge.extend(1u32.to_le_bytes());
    huge.extend(u64::MAX.to_le_bytes());
    assert!(parse_rays(p, &huge).is_err());
    // The CLI reports it in one line and fails, whatever the mesh.
    let f = temp_dir("rays-bad").join("trunc.bin");
    std::fs::write(&f, &good[..40]).unwrap();
    let out = common::run_wavepath(["rays", "trace", "nothing.obj", f.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("trunc.bin") && err.trim().lines().count() == 1, "{err}");
}

#[test]
fn primary_rays_follow_the_renderer_camera() {
    let scene = scene_of(icosphere(4), vec![]);
    let (w, h) = (16, 9);
    let rays = primary_rays(&scene, w, h);
    assert_eq!(rays.len(), w * h);
    let mut cam = scene.camera;
    cam.fit_to(w as f32, h as f32);
    // Row-major from the bottom-left pixel centre.
    assert_eq!(rays[0], cam.generate_ray(0.5 / w as f32, 0.5 / h as f32));
    assert_eq!(rays[w + 3], cam.generate_ray(3.5 / w as f32, 1.5 / h as f32));
    assert_eq!(rays[w * h - 1], cam.generate_ray((w as f32 - 0.5) / w as f32, (h as f32 - 0.5) / h as f32));
}

#[test]
fn diffuse_rays_leave_a_convex_surface() {
    let mut scene = scene_of(icosphere(24), vec![]);
    // Put the camera outside, looking at the sphere, so most primary rays hit.
    scene.camera = wavepath::Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 40.0, 1.0);
    let bvh = Bvh::build(&scene);
    let primary = primary_rays(&scene, 64, 64);
    let diffuse = diffuse_rays(&scene, &bvh, &primary, 5);
    let mut c = TraceCounters::default();
    let nhit = primary.iter().filter(|r| bvh.closest_hit(r, &mut c).is_some()).count();
    assert_eq!(diffuse.len(), nhit);
    assert!(nhit > 1000);
    // On a convex closed sphere seen from outside, the bounce leaves outward and nothing is
    // hit again.
    for r in &diffuse {
        assert!(r.dir.normalize().dot(r.origin.normalize()) >= -0.05, "direction below the surface");
        assert!(r.origin.length() > 1.0 - 0.01);
    }
    let escaped = diffuse.iter().filter(|r| bvh.closest_hit(r, &mut c).is_none()).count();
    assert!(escaped as f64 > 0.99 * diffuse.len() as f64, "{escaped} of {} escaped", diffuse.len());
}

#[test]
fn trace_all_matches_single_rays_for_any_thread_count() {
    let scene = scene_of(icosphere(10), vec![]);
    let bvh = Bvh::build(&scene);
    let mut s = common::Xorshift(9);
    let rays: Vec<Ray> = (0..5000)
        .map(|_| {
            let o = Vec3::new(s.unit() - 0.5, s.unit() - 0.5, 3.0);
            Ray::new(o, Vec3::new(s.unit() - 0.5, s.unit() - 0.5, -1.0))
        })
        .collect();
    let mut c = TraceCounters::default();
    let want: Vec<HitRecord> = rays.iter().map(|r| HitRecord::from_hit(bvh.closest_hit(r, &mut c))).collect();
    assert!(want.iter().any(|h| h.prim != u32::MAX) && want.iter().any(|h| h.prim == u32::MAX));
    for threads in [1, 2, 3] {
        let mut got = vec![HitRecord::MISS; rays.len()];
        let counters = trace_all(&bvh, &rays, &mut got, threads);
        assert_eq!(got, want, "{threads} threads");
        assert_eq!(counters.rays, rays.len() as u64);
    }
}

/// End to end through the CLI.
#[test]
fn cli_dump_and_trace_a_mesh() {
    let Some(mesh) = common::scene("meshes/stanford-bunny.obj") else { return };
    let dir = temp_dir("rays-cli");
    let rays = dir.join("bunny_primary.bin");
    let hits = dir.join("bunny_hits.bin");
    let bin = common::wavepath_bin();
    let st = Command::new(&bin)
        .args(["rays", "dump"])
        .arg(&mesh)
        .args(["--kind", "primary", "-r", "80", "60", "--out"])
        .arg(&rays)
        .status()
        .unwrap();
    assert!(st.success());
    let out = Command::new(&bin)
        .args(["rays", "trace"])
        .arg(&mesh)
        .arg(&rays)
        .args(["2", "2", "-w", "0", "-o"])
        .arg(&hits)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let h = read_hits(&hits).unwrap();
    assert_eq!(h.len(), 80 * 60);
    assert_eq!(json["rays"], 4800);
    assert_eq!(json["threads"], 2);
    assert_eq!(json["reps"], 2);
    assert_eq!(json["peer"], "wavepath");
    let n = h.iter().filter(|x| x.prim != u32::MAX).count();
    assert_eq!(json["hits"], n as u64);
    let sum: f64 = h.iter().filter(|x| x.prim != u32::MAX).map(|x| x.t as f64).sum();
    assert!((json["checksum"].as_f64().unwrap() - sum).abs() <= 1e-6 * sum.max(1.0));
    assert!(n > 0);
}

/// `rays dump -c` traces from the camera file's view (the harness scenes' cameras): every
/// primary ray leaves the file's eye point, and the middle pixel's looks at its target.
#[test]
fn cli_dump_from_a_camera_file() {
    let dir = temp_dir("rays-camera");
    let cam = dir.join("camera.txt");
    // The CS184 dump: hfov vfov aspect near far / eye target / phi theta r min max / c2w /
    // screen w h distance / focal distance, lens radius.
    let eye_target = "0.25 1.0 3.9 0.25 1.0 2.9";
    std::fs::write(
        &cam,
        format!("39.32 30.0 1.3333334 0.01 100.0\n{eye_target}\n1.5707964 0.0 1 0 1e30\n1 0 0 0 1 0 0 0 1\n320 240 447.8\n4.7 0\n"),
    )
    .unwrap();
    let rays = dir.join("primary.bin");
    let st = Command::new(common::wavepath_bin())
        .args(["rays", "dump", "--kind", "primary", "-r", "33", "25", "-c"])
        .arg(&cam)
        .arg(common::repo_root().join("scenes/cornell_mesh.obj"))
        .arg("--out")
        .arg(&rays)
        .status()
        .unwrap();
    assert!(st.success());
    let r = read_rays(&rays).unwrap();
    assert_eq!(r.len(), 33 * 25);
    assert!(r.iter().all(|r| r.origin == Vec3::new(0.25, 1.0, 3.9)), "{:?}", r[0]);
    let mid = r[12 * 33 + 16].dir.normalize();
    assert!(mid.dot(Vec3::NEG_Z) > 0.9999, "{mid}");
}
