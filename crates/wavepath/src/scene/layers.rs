//! The glTF material extensions that add lobes to the metallic-roughness model
//! (`KHR_materials_transmission`, `_ior`, `_volume`, `_specular`, `_clearcoat`, `_sheen`),
//! as the Khronos specifications define their parameters (defaults included), and the
//! specular-glossiness texture. Shaded by [`crate::bsdf::Layered`].

use super::texture::Texture;
use glam::Vec3;

/// The extension parameters of one material; each field's default is the one that makes
/// its extension have no effect (or, for `ior`, the core model's 1.5).
#[derive(Clone, Debug, PartialEq)]
pub struct Layers {
    /// `KHR_materials_transmission`: the share of the dielectric base that is transmitted
    /// instead of diffusely reflected, times the red channel of `transmission_texture`.
    pub transmission: f32,
    pub transmission_texture: Option<Texture>,
    /// `KHR_materials_ior`.
    pub ior: f32,
    /// `KHR_materials_volume`: 0 is a thin wall (light passes straight through); otherwise
    /// the mesh is the boundary of a volume (refracting, absorbing).
    pub thickness: f32,
    /// Colour white light has after `attenuation_distance` inside the volume (Beer–Lambert).
    pub attenuation_color: Vec3,
    pub attenuation_distance: f32,
    /// `KHR_materials_specular`: strength and colour of the dielectric's reflection.
    pub specular: f32,
    pub specular_color: Vec3,
    /// `KHR_materials_clearcoat`: a second GGX layer (ior 1.5) on top.
    pub clearcoat: f32,
    pub clearcoat_roughness: f32,
    /// `KHR_materials_sheen`: a Charlie-distribution sheen on top of the base.
    pub sheen_color: Vec3,
    pub sheen_roughness: f32,
}

impl Default for Layers {
    fn default() -> Self {
        Layers {
            transmission: 0.0,
            transmission_texture: None,
            ior: 1.5,
            thickness: 0.0,
            attenuation_color: Vec3::ONE,
            attenuation_distance: f32::INFINITY,
            specular: 1.0,
            specular_color: Vec3::ONE,
            clearcoat: 0.0,
            clearcoat_roughness: 0.0,
            sheen_color: Vec3::ZERO,
            sheen_roughness: 0.0,
        }
    }
}

impl Layers {
    /// The volume's absorption coefficient per unit length (zero for thin walls and clear
    /// volumes): -ln(attenuation colour) / attenuation distance.
    pub fn sigma_a(&self) -> Vec3 {
        let d = self.attenuation_distance;
        if self.thickness <= 0.0 || d.is_nan() || d <= 0.0 || d.is_infinite() {
            return Vec3::ZERO;
        }
        let c = self.attenuation_color.clamp(Vec3::splat(1e-6), Vec3::ONE);
        Vec3::new(-c.x.ln(), -c.y.ln(), -c.z.ln()) / self.attenuation_distance
    }

    pub fn is_finite(&self) -> bool {
        [self.transmission, self.ior, self.thickness, self.specular, self.clearcoat, self.clearcoat_roughness]
            .iter()
            .all(|v| v.is_finite())
            && self.sheen_roughness.is_finite()
            && !self.attenuation_distance.is_nan()
            && self.attenuation_color.is_finite()
            && self.specular_color.is_finite()
            && self.sheen_color.is_finite()
    }
}

/// `KHR_materials_pbrSpecularGlossiness`'s `specularGlossinessTexture`: specular colour in
/// RGB (sRGB) and glossiness in alpha (linear), each times its factor.
#[derive(Clone, Debug, PartialEq)]
pub struct SpecularGlossinessMap {
    pub specular: Texture,
    /// The alpha channel in every channel of its image.
    pub glossiness: Texture,
}
