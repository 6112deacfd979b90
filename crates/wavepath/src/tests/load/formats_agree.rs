//! scenes/cornell_mesh.{obj,gltf,dae} (written by tools/make_scenes.py) describe one scene in
//! three formats: they must load to the same triangles in the same order, the same materials
//! per triangle and the same camera (the OBJ's is `Camera::framing`, the others are written
//! to equal it).

use crate::load::{CameraMode, LoadOptions, load};
use crate::scene::Scene;
use glam::Vec3;
use std::path::PathBuf;

fn authored(ext: &str) -> PathBuf {
    crate::tests::common::repo_root().join("scenes").join(format!("cornell_mesh.{ext}"))
}

fn load_as(ext: &str) -> Scene {
    // The .dae keeps its own camera and normals so that it is comparable with the others.
    let opts = LoadOptions { camera: CameraMode::File, smooth_normals: false, ..LoadOptions::default() };
    load(&authored(ext), &opts).unwrap_or_else(|e| panic!("{e:#}"))
}

fn assert_agree(a: &Scene, b: &Scene, what: &str) {
    assert_eq!(a.mesh.triangles.len(), b.mesh.triangles.len(), "{what}: triangle count");
    for i in 0..a.mesh.triangles.len() {
        for (p, q) in a.mesh.corners(i).iter().zip(b.mesh.corners(i)) {
            assert!(p.distance(q) < 1e-5, "{what}: triangle {i}: {p} vs {q}");
        }
        let ma = &a.materials[a.mesh.material_ids[i] as usize];
        let mb = &b.materials[b.mesh.material_ids[i] as usize];
        let (aa, ab) = (ma.bsdf.diffuse_albedo(), mb.bsdf.diffuse_albedo());
        assert!(aa.distance(ab) < 1e-5, "{what}: triangle {i} albedo {aa} vs {ab}");
        assert!(
            ma.emission.distance(mb.emission) < 1e-5,
            "{what}: triangle {i} emission {} vs {}",
            ma.emission,
            mb.emission
        );
    }
    // Each format has its own rule for the field of view; at the image they agree.
    let (mut ca, mut cb) = (a.camera, b.camera);
    ca.fit_to(4.0, 3.0);
    cb.fit_to(4.0, 3.0);
    assert!(ca.position.distance(cb.position) < 1e-4, "{what}: camera position {} vs {}", ca.position, cb.position);
    let (da, db) = (ca.c2w * -Vec3::Z, cb.c2w * -Vec3::Z);
    assert!(da.distance(db) < 1e-4, "{what}: view direction {da} vs {db}");
    let (ua, ub) = (ca.c2w * Vec3::Y, cb.c2w * Vec3::Y);
    assert!(ua.distance(ub) < 1e-4, "{what}: camera up {ua} vs {ub}");
    assert!((ca.vfov_deg - cb.vfov_deg).abs() < 1e-4, "{what}: vfov {} vs {}", ca.vfov_deg, cb.vfov_deg);
    assert!((ca.hfov_deg - cb.hfov_deg).abs() < 1e-4, "{what}: hfov {} vs {}", ca.hfov_deg, cb.hfov_deg);
}

#[test]
fn obj_matches_its_independent_description() {
    // The script's scene: 6 quads (12 triangles), a 6-quad box (12) and an icosahedron (20);
    // exactly one emitter of radiance 10, the red and blue walls.
    let obj = load_as("obj");
    assert_eq!(obj.mesh.triangles.len(), 44);
    let (lo, hi) = obj.bounds().unwrap();
    assert_eq!((lo, hi), (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 1.5, 1.0)));
    let emitting: Vec<usize> =
        (0..44).filter(|&i| obj.materials[obj.mesh.material_ids[i] as usize].is_emissive()).collect();
    assert_eq!(emitting, vec![10, 11]);
    for &i in &emitting {
        assert!(obj.mesh.corners(i).iter().all(|p| (p.y - 1.49).abs() < 1e-6));
        assert_eq!(obj.materials[obj.mesh.material_ids[i] as usize].emission, Vec3::splat(10.0));
    }
    assert!(obj.lights.is_empty(), "the emitter lights the scene: no hemisphere light");
}

#[test]
fn gltf_agrees_with_obj() {
    assert_agree(&load_as("obj"), &load_as("gltf"), "gltf vs obj");
}

#[test]
fn collada_agrees_with_obj() {
    assert_agree(&load_as("obj"), &load_as("dae"), "dae vs obj");
}
