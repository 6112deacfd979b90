//! What the glTF material extensions and relief maps need at render time, computed once
//! per render: which materials tilt their normals, the sheen albedo tables and the volumes'
//! absorption.

use super::{Transport, Vertex};
use crate::bsdf::{Layered, SHEEN_TABLE, sheen_albedo_table};
use crate::scene::Scene;
use glam::Vec3;

#[derive(Clone, Debug, Default)]
pub struct LayerData {
    /// Per material: it has a relief map (and the mesh the uvs to read it).
    pub relief: Vec<bool>,
    /// Per material: its sheen's directional albedo by cos_o (sheen materials only).
    sheen: Vec<Option<Box<[f32; SHEEN_TABLE]>>>,
    /// Per material: the absorption coefficient inside its volume (zero for most).
    sigma_a: Vec<Vec3>,
    /// Some material absorbs inside its volume.
    pub volumes: bool,
    /// Some material has a relief map.
    pub any_relief: bool,
}

impl LayerData {
    pub fn new(scene: &Scene) -> LayerData {
        let uvs = scene.mesh.uvs.is_some();
        let relief: Vec<bool> = scene
            .materials
            .iter()
            .map(|m| uvs && m.relief.as_ref().is_some_and(|r| r.texture.image.is_some()))
            .collect();
        let sheen = scene
            .materials
            .iter()
            .map(|m| {
                let l = m.layers.as_ref()?;
                (l.sheen_color != Vec3::ZERO).then(|| Box::new(sheen_albedo_table(l.sheen_roughness)))
            })
            .collect();
        let sigma_a: Vec<Vec3> =
            scene.materials.iter().map(|m| m.layers.as_ref().map_or(Vec3::ZERO, |l| l.sigma_a())).collect();
        let volumes = sigma_a.iter().any(|s| *s != Vec3::ZERO);
        let any_relief = relief.iter().any(|&r| r);
        LayerData { relief, sheen, sigma_a, volumes, any_relief }
    }

    /// The layered model of `v`'s material at `v` (base colour, metalness, roughness and
    /// transmission as textured there; the inside of a volume when `v` is hit from
    /// inside), seen from a direction of cosine `cos_o` to the shading normal. Kept out of
    /// line: the shading of every other model stays as small as it was.
    #[inline(never)]
    pub fn at(&self, t: &Transport, v: &Vertex, cos_o: f32) -> Layered {
        let m = v.material as usize;
        let Some(l) = t.scene.materials[m].layers.as_deref() else {
            unreachable!("a layered model comes from a material with layers")
        };
        let transmission = t.materials.textures.transmission(m, v.uv).unwrap_or(l.transmission);
        let model = Layered::new(v.albedo, v.metal_rough.x, v.metal_rough.y, transmission, l);
        let model = if v.front || model.thin { model } else { model.inside() };
        match &self.sheen[m] {
            Some(table) => model.seen_from(cos_o, table),
            None => model,
        }
    }

    /// The fraction of light that survives the segment of length `dist` a path just
    /// travelled to reach `v`: inside `v`'s volume when `v` is seen from inside
    /// (Beer–Lambert, exp(-sigma_a dist)); 1 otherwise. Meshes are taken to be closed and
    /// not nested.
    #[inline]
    pub fn absorbed(&self, v: &Vertex, dist: f32) -> Vec3 {
        let s = self.sigma_a[v.material as usize];
        if v.front || s == Vec3::ZERO {
            return Vec3::ONE;
        }
        let a = (-s * dist).exp();
        if a.is_finite() { a } else { Vec3::ZERO }
    }
}
