//! Meshes generated in code.

use glam::{Vec3, vec3};
use wavepath::{Camera, Material, Mesh, Scene, Sphere};

/// A geodesic icosphere with `freq`^2 * 20 triangles, radius 1, shared vertices (closed).
pub fn icosphere(freq: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let v = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|p| Vec3::from(p).normalize());
    let faces = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let mut positions = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut vid = |p: Vec3, key: (u64, u64, u64)| -> u32 {
        *index.entry(key).or_insert_with(|| {
            positions.push(p.normalize());
            positions.len() as u32 - 1
        })
    };
    let mut triangles = Vec::new();
    let n = freq as u64;
    for f in faces {
        let (a, b, c) = (v[f[0]], v[f[1]], v[f[2]]);
        // Grid point (i, j) of the face: a + i/n (b - a) + j/n (c - a); the key is the
        // exact barycentric position in integers so shared edges share vertices.
        let key = |i: u64, j: u64| {
            let w = [(f[0], n - i - j), (f[1], i), (f[2], j)];
            let mut k = [(0usize, 0u64); 3];
            let mut m = 0;
            for (vi, wt) in w {
                if wt > 0 {
                    k[m] = (vi, wt);
                    m += 1;
                }
            }
            k[..m].sort();
            let pack = |e: (usize, u64)| (e.0 as u64) << 32 | e.1;
            (pack(k[0]), if m > 1 { pack(k[1]) } else { u64::MAX }, if m > 2 { pack(k[2]) } else { u64::MAX })
        };
        let p = |i: u64, j: u64| a + (b - a) * (i as f32 / n as f32) + (c - a) * (j as f32 / n as f32);
        let mut ids = vec![vec![0u32; (n + 1) as usize]; (n + 1) as usize];
        for i in 0..=n {
            for j in 0..=n - i {
                ids[i as usize][j as usize] = vid(p(i, j), key(i, j));
            }
        }
        for i in 0..n as usize {
            for j in 0..(n as usize - i) {
                triangles.push([ids[i][j], ids[i + 1][j], ids[i][j + 1]]);
                if j + 1 < n as usize - i {
                    triangles.push([ids[i + 1][j], ids[i + 1][j + 1], ids[i][j + 1]]);
                }
            }
        }
    }
    let material_ids = vec![0; triangles.len()];
    Mesh {
        positions,
        normals: None,
        uvs: None,
        colors: None,
        tangents: None,
        triangles,
        material_ids: material_ids.into(),
    }
}

/// Corners `c` in order as two triangles (c0 c1 c2, c0 c2 c3) of material `m`.
pub fn quad(mesh: &mut Mesh, c: [Vec3; 4], m: u32) {
    let base = mesh.positions.len() as u32;
    mesh.positions.extend(c);
    mesh.triangles.push([base, base + 1, base + 2]);
    mesh.triangles.push([base, base + 2, base + 3]);
    mesh.material_ids.extend([m, m]);
}

/// The default scene's materials, lights and camera with `mesh` and `spheres`.
pub fn scene_of(mesh: Mesh, spheres: Vec<Sphere>) -> Scene {
    let mut s = wavepath::default_scene();
    s.mesh = mesh;
    s.spheres = spheres;
    s
}

/// Height of [`emitter_above_floor`]'s emitter above the floor.
pub const EMITTER_GAP: f32 = 0.02;
/// Half the side of [`emitter_above_floor`]'s square emitter.
pub const EMITTER_HALF: f32 = 0.15;

/// A small square emitter hanging just above a diffuse floor, seen from above at `aspect`:
/// the scene where light sampling alone fills the picture with fireflies and MIS does not.
pub fn emitter_above_floor(aspect: f32) -> Scene {
    let mut mesh = Mesh::default();
    quad(&mut mesh, [vec3(-5.0, 0.0, -5.0), vec3(-5.0, 0.0, 5.0), vec3(5.0, 0.0, 5.0), vec3(5.0, 0.0, -5.0)], 0);
    // Wound to face the floor.
    let (a, y) = (EMITTER_HALF, EMITTER_GAP);
    quad(&mut mesh, [vec3(-a, y, -a), vec3(a, y, -a), vec3(a, y, a), vec3(-a, y, a)], 1);
    let mut camera = Camera::look_at(vec3(0.0, 0.45, 0.5), vec3(0.0, 0.0, 0.05), Vec3::Y, 50.0, aspect);
    camera.nclip = 1e-3;
    Scene {
        name: "emitter above a floor".into(),
        mesh,
        materials: vec![Material::diffuse("floor", Vec3::splat(0.8)), Material::emitter("light", Vec3::splat(5.0))],
        camera,
        ..Scene::default()
    }
}
