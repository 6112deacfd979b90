//! The embedded default scene and the defaults given to files that carry no camera or light.

use crate::cs184::Dialect;
use crate::scene::{Camera, FovFit, Light, Material, Mesh, Scene, SceneSource, Sphere};

use glam::{Vec3, vec3};

/// Gives a mesh-only file (OBJ, PLY, glTF without camera or lights) a camera that frames
/// its bounds and, when nothing lights it, the default sky so that `wavepath bunny.obj`
/// shows the shape (the rule: [`Scene::set_environment`]).
pub fn finish_mesh_only(scene: &mut Scene, has_camera: bool) {
    if !has_camera && let Some((lo, hi)) = scene.bounds() {
        scene.camera = Camera::framing(lo, hi);
    }
    scene.light_by_default_sky();
}

/// A Cornell box with two diffuse spheres, the same layout and colours as the CS184
/// `CBspheres_lambertian` scene (Y-up, box [-1,1] x [0,1.5] x [-1,1]), lit by a 0.6 x 0.8
/// area light under the ceiling. Built in code so that `wavepath` works with no files.
pub fn default_scene() -> Scene {
    let mut materials = vec![
        Material::diffuse("white", Vec3::splat(0.6)),
        Material::diffuse("red", vec3(0.6, 0.2, 0.2)),
        Material::diffuse("blue", vec3(0.2, 0.2, 0.6)),
        Material::emitter("light", Vec3::splat(10.0)),
        Material::diffuse("sphere", Vec3::splat(0.8)),
    ];
    materials.shrink_to_fit();
    let mut mesh = Mesh::default();
    let quad = |mesh: &mut Mesh, c: [Vec3; 4], m: u32| {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(c);
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base, base + 2, base + 3]);
        mesh.material_ids.extend([m, m]);
    };
    let (x0, x1, y0, y1, z0, z1) = (-1.0, 1.0, 0.0, 1.5, -1.0, 1.0);
    // Windings face into the box.
    quad(&mut mesh, [vec3(x0, y0, z0), vec3(x0, y0, z1), vec3(x1, y0, z1), vec3(x1, y0, z0)], 0); // floor
    quad(&mut mesh, [vec3(x0, y1, z0), vec3(x1, y1, z0), vec3(x1, y1, z1), vec3(x0, y1, z1)], 0); // ceiling
    quad(&mut mesh, [vec3(x0, y0, z0), vec3(x1, y0, z0), vec3(x1, y1, z0), vec3(x0, y1, z0)], 0); // back
    quad(&mut mesh, [vec3(x0, y0, z0), vec3(x0, y1, z0), vec3(x0, y1, z1), vec3(x0, y0, z1)], 1); // left (red)
    quad(&mut mesh, [vec3(x1, y0, z0), vec3(x1, y0, z1), vec3(x1, y1, z1), vec3(x1, y1, z0)], 2); // right (blue)
    let ly = 1.49;
    quad(&mut mesh, [vec3(-0.4, ly, -0.3), vec3(0.4, ly, -0.3), vec3(0.4, ly, 0.3), vec3(-0.4, ly, 0.3)], 3);
    mesh.normals = Some(crate::scene::area_weighted_vertex_normals(&mesh.positions, &mesh.triangles));
    let spheres = vec![
        Sphere { center: vec3(0.4, 0.3, 0.3), radius: 0.3, material: 4 },
        Sphere { center: vec3(-0.4, 0.3, -0.3), radius: 0.3, material: 4 },
    ];
    let lights = vec![Light::Area {
        position: vec3(0.0, 1.49, 0.0),
        direction: vec3(0.0, -1.0, 0.0),
        dim_x: vec3(0.6, 0.0, 0.0),
        dim_y: vec3(0.0, 0.0, 0.8),
        radiance: Vec3::splat(10.0),
    }];
    let mut scene = Scene {
        name: "default (Cornell box with two spheres)".into(),
        source: SceneSource { dialect: Dialect::Cs184, reader: "embedded", default_sky: false },
        mesh,
        spheres,
        materials,
        lights,
        ..Scene::default()
    };
    let (lo, hi) = scene.bounds().expect("the default scene has geometry");
    let mut camera = Camera {
        nclip: 0.1,
        fclip: 100.0,
        vfov_deg: 2.0 * (24.567f32.to_radians().tan() / (4.0 / 3.0)).atan().to_degrees(),
        ..Camera::default()
    };
    camera.fit = FovFit::cs184(49.134_34, camera.vfov_deg);
    camera.fit_to(800.0, 600.0);
    camera.cs184_place(Vec3::Z, lo, hi);
    scene.camera = camera;
    scene
}
