//! Which rays from a path's last vertex can find light at all.
//!
//! A vertex at the last depth sends its BSDF-sampled ray only to collect the light it
//! arrives at, weighed by MIS against the vertex's light samples (`Rules::diffuse_mis`,
//! glossy and delta vertices alike). In a scene whose only light a ray can find is its
//! emissive triangles (no light from infinity, no area light), a ray that misses every one
//! of them finds none, and most such rays do: lights are small. Those rays are tested
//! against a tree of the emissive triangles alone, a few dozen instructions, and only the
//! ones that hit an emitter are traced through the scene. The image is the one tracing
//! every ray gives: a skipped ray would have added exactly nothing.

use crate::accel::{Bvh, Intersector, TraceCounters};
use crate::cpu::Isa;
use crate::geometry::Ray;
use crate::scene::{MaterialIds, Mesh, Scene};

pub struct EmitterFilter {
    emitters: Bvh,
}

impl EmitterFilter {
    /// The filter of `scene`, when its emissive triangles are the only light a ray can find
    /// (`finds_other_light`: the light set has light from infinity or an area light).
    pub fn new(scene: &Scene, finds_other_light: bool, isa: Isa) -> Option<EmitterFilter> {
        let emits = |m: u32| {
            let mat = &scene.materials[m as usize];
            mat.is_emissive() || mat.emission_texture.is_some()
        };
        if finds_other_light || scene.spheres.iter().any(|s| emits(s.material)) {
            return None;
        }
        let mesh = &scene.mesh;
        let mut positions = Vec::new();
        for (tri, m) in mesh.triangles.iter().zip(mesh.material_ids.iter()) {
            if emits(m) {
                positions.extend(tri.iter().map(|&v| mesh.positions[v as usize]));
            }
        }
        if positions.is_empty() {
            return None;
        }
        let n = positions.len() / 3;
        let triangles = (0..n as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        let mesh = Mesh { positions, triangles, material_ids: MaterialIds::uniform(0, n), ..Mesh::default() };
        let emitters = Scene { mesh, materials: vec![Default::default()], ..Scene::default() };
        Some(EmitterFilter { emitters: Bvh::build(&emitters).with_isa(isa) })
    }

    /// Whether `ray` hits an emissive triangle anywhere along it. The test is the scene's own
    /// watertight triangle test on the same corners, so a ray whose closest hit in the scene
    /// is an emitter always passes; one that passes may still be blocked on its way there.
    #[inline]
    pub fn may_find_light(&self, ray: &Ray) -> bool {
        self.emitters.any_hit(ray, &mut TraceCounters::default())
    }
}
