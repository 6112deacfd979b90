//! The scene's materials as the tables shading reads: per material its diffuse albedo,
//! emission, metalness and roughness, scattering model, textures and layer data.

use super::layers::LayerData;
use crate::bsdf::{Kind, Model};
use crate::scene::{Bsdf, MaterialIds, Scene, Sphere, Textures};
use glam::{Vec2, Vec3};

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
    /// Per material: it is Lambertian (its hits are shaded by the diffuse lane kernel).
    pub lambertian: Vec<bool>,
    /// Albedo textures per material; empty lookups when the scene has none.
    pub textures: Textures,
    /// What the glTF material extensions need per render ([`LayerData`]).
    pub layers: LayerData,
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
            lambertian: models.iter().map(|m| matches!(m, crate::bsdf::Model::Lambert(_))).collect(),
            models,
            textures: Textures::new(scene),
            layers: LayerData::new(scene),
            triangle_ids: &scene.mesh.material_ids,
            triangles: scene.mesh.triangles.len(),
            spheres: &scene.spheres,
        }
    }

    /// The material of primitive `prim` (a triangle, or a sphere after the triangles).
    #[inline]
    pub fn material_of(&self, prim: u32) -> usize {
        let p = prim as usize;
        if p < self.triangles {
            self.triangle_ids[p] as usize
        } else {
            self.spheres[p - self.triangles].material as usize
        }
    }
}
