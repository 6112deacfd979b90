//! The scene's materials as the tables shading reads: per material its diffuse albedo,
//! emission, metalness and roughness, scattering model, textures and layer data.

use super::layers::LayerData;
use crate::bsdf::{Kind, Model};
use crate::scene::{Bsdf, MaterialIds, Scene, Sphere, Textures};
use glam::{Vec2, Vec3};

/// Triangles up to which a mesh in several runs keeps each triangle's material one by one
/// (8 MB of ids at most: built once per render plan).
const DENSE_UP_TO: usize = 1 << 22;

/// Each triangle's material of `ids` one by one, or nothing where the runs are cheap to
/// search (one run) or the table would be large.
fn dense_ids(ids: &MaterialIds, materials: usize) -> Vec<u16> {
    if ids.len() > DENSE_UP_TO || ids.runs().nth(1).is_none() || materials > usize::from(u16::MAX) + 1 {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(ids.len());
    for (start, end, id) in ids.runs() {
        out.resize(end, id as u16);
        debug_assert_eq!(out.len() - (end - start), start);
    }
    out
}

/// Per-material tables, indexed by material id.
pub struct MaterialTable<'a> {
    /// Per material: diffuse albedo and emitted radiance.
    pub albedo: Vec<Vec3>,
    pub emission: Vec<Vec3>,
    /// Per material: whether it emits from both faces or only from the front one.
    pub two_sided_emission: Vec<bool>,
    /// Per material: metalness and roughness factors (metallic-roughness materials).
    pub metal_rough: Vec<Vec2>,
    /// Per material: its scattering model (used only when `non_diffuse`).
    pub models: Vec<Model>,
    /// Some material is not Lambertian: shading goes through [`ShadingFrame`](super::material::ShadingFrame).
    pub non_diffuse: bool,
    /// Albedo textures per material; empty lookups when the scene has none.
    pub textures: Textures,
    /// What the glTF material extensions need per render ([`LayerData`]).
    pub layers: LayerData,
    /// Each triangle's material one by one, for meshes of up to [`DENSE_UP_TO`] triangles in
    /// more than one run (empty otherwise): a shaded hit's material is then one load instead
    /// of a binary search over the runs, a chain of dependent loads every hit waited on.
    dense: Vec<u16>,
    /// Which material each primitive has: triangles by their ids, then spheres.
    triangle_ids: &'a MaterialIds,
    triangles: usize,
    spheres: &'a [Sphere],
}

impl<'a> MaterialTable<'a> {
    pub fn new(scene: &'a Scene) -> MaterialTable<'a> {
        let models: Vec<Model> = scene.materials.iter().map(Model::of_material).collect();
        MaterialTable {
            albedo: scene.materials.iter().map(|m| m.bsdf.diffuse_albedo()).collect(),
            emission: scene.materials.iter().map(|m| m.emission).collect(),
            two_sided_emission: scene.materials.iter().map(|m| m.two_sided_emission).collect(),
            metal_rough: scene
                .materials
                .iter()
                .map(|m| match m.bsdf {
                    Bsdf::MetallicRoughness { metallic, roughness, .. } => Vec2::new(metallic, roughness),
                    _ => Vec2::ZERO,
                })
                .collect(),
            non_diffuse: models.iter().any(|m| m.kind() != Kind::Diffuse),
            models,
            textures: Textures::new(scene),
            layers: LayerData::new(scene),
            dense: dense_ids(&scene.mesh.material_ids, scene.materials.len()),
            triangle_ids: &scene.mesh.material_ids,
            triangles: scene.mesh.triangles.len(),
            spheres: &scene.spheres,
        }
    }

    /// The material of primitive `prim` (a triangle, or a sphere after the triangles).
    #[inline]
    pub fn material_of(&self, prim: u32) -> usize {
        let p = prim as usize;
        if let Some(&m) = self.dense.get(p) {
            return m as usize;
        }
        if p < self.triangles {
            self.triangle_ids[p] as usize
        } else {
            self.spheres[p - self.triangles].material as usize
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table holds each triangle's material of the runs, and is left out where the runs
    /// are cheap to search or the table would be large.
    #[test]
    fn dense_ids_are_the_runs_ids() {
        let mut ids = MaterialIds::default();
        for (id, count) in [(3, 5), (0, 1), (7, 12), (3, 2), (65535, 4)] {
            ids.push_run(id, count);
        }
        let dense = dense_ids(&ids, 65536);
        assert_eq!(dense.len(), 24);
        for (t, &m) in dense.iter().enumerate() {
            assert_eq!(u32::from(m), ids[t], "triangle {t}");
        }
        assert!(dense_ids(&ids, 65537).is_empty(), "ids beyond u16");
        assert!(dense_ids(&MaterialIds::uniform(2, 100), 3).is_empty(), "one run");
        let mut big = MaterialIds::uniform(0, DENSE_UP_TO);
        big.push_run(1, 1);
        assert!(dense_ids(&big, 2).is_empty(), "more than DENSE_UP_TO triangles");
    }
}
