//! Subdivided meshes from `wavepath subdivide` come back exactly, with their materials and
//! attributes.

use crate::common::{run_wavepath, temp_dir};
use glam::Vec3;
use std::collections::HashSet;
use std::path::Path;
use wavepath::{LoadOptions, Mesh, load};

/// The mesh of a PLY file as the loader reads it.
fn mesh_of(path: &Path) -> Mesh {
    load(path, &LoadOptions::default()).unwrap().mesh
}

/// Subdivision through the command: 4^n triangles; on a closed mesh V + E vertices a level
/// (E counted here from the triangles); the same area; every vertex on the original
/// surface; and the PLY it writes reads back to exactly the mesh the library makes.
#[test]
fn subdivide_command_writes_meshes_that_read_back_exactly() {
    let d = temp_dir("subdivide");
    let sphere = crate::common::meshgen::icosphere(2);
    let obj: String = sphere.positions.iter().map(|p| format!("v {} {} {}\n", p.x, p.y, p.z)).collect::<String>()
        + &sphere.triangles.iter().map(|t| format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1)).collect::<String>();
    std::fs::write(d.join("s.obj"), obj).unwrap();
    let src = wavepath::load(&d.join("s.obj"), &Default::default()).unwrap().mesh;
    let out = d.join("s2.ply");
    let o = run_wavepath(["subdivide", d.join("s.obj").to_str().unwrap(), out.to_str().unwrap(), "-n", "2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // No levels: the source mesh itself, converted.
    let same = d.join("s0.ply");
    let o = run_wavepath(["subdivide", d.join("s.obj").to_str().unwrap(), same.to_str().unwrap(), "-n", "0"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got = mesh_of(&same);
    assert_eq!((&got.positions, &got.triangles), (&src.positions, &src.triangles));
    let got = mesh_of(&out);
    let (p, t) = wavepath::subdivide::subdivide(&src.positions, &src.triangles, 2).unwrap();
    assert_eq!((&got.positions, &got.triangles), (&p, &t));
    assert_eq!(t.len(), src.triangles.len() * 16);
    let edges = |t: &[[u32; 3]]| -> usize {
        t.iter()
            .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
            .map(|(i, j)| (i.min(j), i.max(j)))
            .collect::<HashSet<_>>()
            .len()
    };
    let (one_p, one_t) = wavepath::subdivide::subdivide(&src.positions, &src.triangles, 1).unwrap();
    assert_eq!(one_p.len(), src.positions.len() + edges(&src.triangles));
    assert_eq!(p.len(), one_p.len() + edges(&one_t));
    let area = |p: &[Vec3], t: &[[u32; 3]]| -> f64 {
        t.iter()
            .map(|&[a, b, c]| {
                let (a, b, c) = (p[a as usize].as_dvec3(), p[b as usize].as_dvec3(), p[c as usize].as_dvec3());
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    };
    let (a0, a2) = (area(&src.positions, &src.triangles), area(&p, &t));
    assert!((a0 - a2).abs() < 1e-5 * a0, "area {a0} -> {a2}");
    // Each child lies in its parent's plane: the 16 children of triangle k are 16k..16k+16.
    for (k, tri) in src.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|i| src.positions[i as usize]);
        let n = (b - a).cross(c - a).normalize();
        for child in &t[16 * k..16 * k + 16] {
            for &i in child {
                assert!((p[i as usize] - a).dot(n).abs() < 1e-5, "triangle {k}: a child vertex leaves its plane");
            }
        }
    }
    // Bad requests: one line each, non-zero exit.
    for (args, needle) in [
        (vec!["subdivide", d.join("s.obj").to_str().unwrap(), "x.obj", "-n", "1"], "name it .ply"),
        (vec!["subdivide", d.join("s.obj").to_str().unwrap(), out.to_str().unwrap(), "-n", "12"], "more than the 2^30"),
        (vec!["subdivide", "/nonexistent.obj", out.to_str().unwrap(), "-n", "1"], "/nonexistent.obj"),
    ] {
        let o = run_wavepath(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(needle) && err.trim().lines().count() == 1, "{err}");
    }
}

/// `Mesh::subdivided` (behind `--subdivide`): children keep their parent's material, and
/// attributes that are linear over the surface stay exactly so (uv and colour set to
/// functions of the position); a constant normal stays that normal.
#[test]
fn subdivided_meshes_carry_materials_and_attributes() {
    let mut m = Mesh::default();
    let corners =
        [Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 1.0), Vec3::new(0.0, 0.0, 1.0)];
    m.positions = corners.to_vec();
    m.triangles = vec![[0, 1, 2], [0, 2, 3]];
    m.material_ids = vec![3, 5].into();
    m.normals = Some(vec![Vec3::Y; 4]);
    m.uvs = Some(corners.iter().map(|p| glam::Vec2::new(p.x / 2.0, p.z)).collect());
    m.colors = Some(corners.iter().map(|p| Vec3::new(p.x, p.z, 0.25)).collect());
    let s = m.clone().subdivided(3).unwrap();
    assert_eq!(s.triangles.len(), 2 * 64);
    assert_eq!(s.material_ids.iter().collect::<Vec<_>>(), [[3u32; 64], [5u32; 64]].concat());
    let (n, uv, c) = (s.normals.as_ref().unwrap(), s.uvs.as_ref().unwrap(), s.colors.as_ref().unwrap());
    assert!(n.len() == s.positions.len() && uv.len() == s.positions.len() && c.len() == s.positions.len());
    for (i, p) in s.positions.iter().enumerate() {
        assert_eq!(n[i], Vec3::Y, "vertex {i}");
        assert_eq!(uv[i], glam::Vec2::new(p.x / 2.0, p.z), "vertex {i}");
        assert_eq!(c[i], Vec3::new(p.x, p.z, 0.25), "vertex {i}");
    }
    assert_eq!(m.clone().subdivided(0).unwrap(), m);
    assert!(m.subdivided(15).is_none(), "2 x 4^15 triangles is past the limit");

    // Through the command line: the stats count the subdivided triangles; too many levels is
    // one line naming the file.
    let d = temp_dir("subdivide-render");
    let obj = d.join("quad.obj");
    std::fs::write(&obj, "v 0 0 0\nv 2 0 0\nv 2 0 1\nv 0 0 1\nf 1 2 3\nf 1 3 4\n").unwrap();
    let stats = d.join("stats.json");
    let (o, s) = (obj.to_str().unwrap(), stats.to_str().unwrap());
    let out =
        run_wavepath([o, "--subdivide", "2", "-r", "8", "6", "-f", d.join("q.png").to_str().unwrap(), "--stats", s]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(json["triangles"], 32);
    let out = run_wavepath([o, "--subdivide", "15", "-r", "8", "6", "-f", d.join("q.png").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("quad.obj") && err.trim().lines().count() == 1, "{err}");
}
