pub use super::alpha::Alpha;
pub use super::layers::{Layers, SpecularGlossinessMap};
pub use super::relief::{Relief, ReliefMap};
pub use super::texture::Texture;
use glam::Vec3;

/// The scattering model of a surface, as the scene file states it.
///
/// Every model the CS184 files describe is kept, so that later stages can render it; the
/// variants carry exactly the file's parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum Bsdf {
    Diffuse {
        albedo: Vec3,
    },
    Mirror {
        reflectance: Vec3,
    },
    Glass {
        reflectance: Vec3,
        transmittance: Vec3,
        roughness: f32,
        ior: f32,
    },
    Refraction {
        transmittance: Vec3,
        roughness: f32,
        ior: f32,
    },
    Microfacet {
        alpha: f32,
        eta: Vec3,
        k: Vec3,
    },
    Phong {
        diffuse: Vec3,
        specular: Vec3,
        shininess: f32,
    },
    /// glTF's core model: a diffuse base under a GGX specular layer, mixed by metalness
    /// (shaded by [`crate::bsdf::Pbr`]).
    MetallicRoughness {
        base: Vec3,
        metallic: f32,
        roughness: f32,
    },
    /// glTF `KHR_materials_pbrSpecularGlossiness`, shaded by the same model.
    SpecularGlossiness {
        diffuse: Vec3,
        specular: Vec3,
        glossiness: f32,
    },
}

impl Bsdf {
    pub fn kind(&self) -> &'static str {
        match self {
            Bsdf::Diffuse { .. } => "diffuse",
            Bsdf::Mirror { .. } => "mirror",
            Bsdf::Glass { .. } => "glass",
            Bsdf::Refraction { .. } => "refraction",
            Bsdf::Microfacet { .. } => "microfacet",
            Bsdf::Phong { .. } => "phong",
            Bsdf::MetallicRoughness { .. } => "metallic-roughness",
            Bsdf::SpecularGlossiness { .. } => "specular-glossiness",
        }
    }

    /// The albedo used while only diffuse transport is rendered.
    pub fn diffuse_albedo(&self) -> Vec3 {
        match *self {
            Bsdf::Diffuse { albedo } => albedo,
            Bsdf::Mirror { reflectance } => reflectance,
            Bsdf::Glass { transmittance, .. } | Bsdf::Refraction { transmittance, .. } => transmittance,
            Bsdf::Microfacet { .. } => Vec3::splat(0.5),
            Bsdf::Phong { diffuse, .. } | Bsdf::SpecularGlossiness { diffuse, .. } => diffuse,
            Bsdf::MetallicRoughness { base, .. } => base,
        }
    }
}

/// The microfacet roughness (alpha) of Phong exponent `n`, by the Phong–Beckmann
/// correspondence of Walter et al. 2007 (n = 2 / alpha^2 - 2): how MTL `Ns` and COLLADA
/// `<shininess>` become [`Bsdf::Phong`]'s lobe width, and MTL `Ns` a PBR roughness.
#[inline]
pub fn phong_alpha(n: f32) -> f32 {
    (2.0 / (n.max(0.0) + 2.0)).sqrt()
}

/// A surface's appearance: how it scatters and what it emits.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub bsdf: Bsdf,
    /// Emitted radiance (zero for non-emitters).
    pub emission: Vec3,
    pub albedo_texture: Option<Texture>,
    /// Emitted radiance as an image (glTF `emissiveTexture`): `emission` is then the largest
    /// it can be (the factor), and a point emits factor x texel.
    pub emission_texture: Option<Texture>,
    /// glTF `metallicRoughnessTexture` (linear): green scales roughness, blue metalness;
    /// `factor` holds (1, roughness, metallic), so a lookup gives the values at a point.
    pub metallic_roughness_texture: Option<Texture>,
    /// Whether the surface emits from both faces (the CS184 emission BSDF, a glTF
    /// `doubleSided` material) or only from its front, the side its winding's normal points
    /// to (OBJ `Ke`, a single-sided glTF material: what the formats' own renderers show).
    pub two_sided_emission: bool,
    /// Where the surface is there at all (cutouts; see [`super::alpha`]).
    pub alpha: Alpha,
    /// A normal or height map tilting the shading normal (glTF `normalTexture`, MTL
    /// `norm`/`bump`).
    pub relief: Option<ReliefMap>,
    /// glTF material extensions beyond the core model (transmission, volume, clearcoat...):
    /// `None` for every other material, which keeps its own model.
    pub layers: Option<Box<Layers>>,
    /// The specular-glossiness texture of a `SpecularGlossiness` material.
    pub specular_glossiness_texture: Option<Box<SpecularGlossinessMap>>,
}

impl Default for Material {
    fn default() -> Self {
        Material::diffuse("default", Vec3::splat(0.5))
    }
}

impl Material {
    pub fn diffuse(name: &str, albedo: Vec3) -> Self {
        Material {
            name: name.into(),
            bsdf: Bsdf::Diffuse { albedo },
            emission: Vec3::ZERO,
            albedo_texture: None,
            emission_texture: None,
            metallic_roughness_texture: None,
            two_sided_emission: true,
            alpha: Alpha::OPAQUE,
            relief: None,
            layers: None,
            specular_glossiness_texture: None,
        }
    }

    /// A pure emitter that reflects nothing (the CS184 `<emission>` BSDF).
    pub fn emitter(name: &str, radiance: Vec3) -> Self {
        Material {
            name: name.into(),
            bsdf: Bsdf::Diffuse { albedo: Vec3::ZERO },
            emission: radiance,
            albedo_texture: None,
            emission_texture: None,
            metallic_roughness_texture: None,
            two_sided_emission: true,
            alpha: Alpha::OPAQUE,
            relief: None,
            layers: None,
            specular_glossiness_texture: None,
        }
    }

    /// Every image the material looks up through the mesh's texture coordinates, by its
    /// field's name, with whether it was decoded (one that could not be read is looked up
    /// nowhere). The one list of a material's maps: whatever depends on some map being read
    /// (the uvs kept for a render) asks it, and the patterns below name every field, so a map
    /// added to the material or its layers does not compile until it is listed here.
    pub fn maps(&self) -> Vec<(&'static str, bool)> {
        let Material {
            name: _,
            bsdf: _,
            emission: _,
            albedo_texture,
            emission_texture,
            metallic_roughness_texture,
            two_sided_emission: _,
            alpha,
            relief,
            layers,
            specular_glossiness_texture,
        } = self;
        let mut maps = Vec::new();
        let mut texture = |name: &'static str, t: Option<&Texture>| {
            if let Some(t) = t {
                maps.push((name, t.image.is_some()));
            }
        };
        texture("albedo", albedo_texture.as_ref());
        texture("emission", emission_texture.as_ref());
        texture("metallic-roughness", metallic_roughness_texture.as_ref());
        texture("relief", relief.as_ref().map(|ReliefMap { texture: t, relief: _ }| t));
        if let Some(sg) = specular_glossiness_texture.as_deref() {
            let SpecularGlossinessMap { specular, glossiness } = sg;
            texture("specular", Some(specular));
            texture("glossiness", Some(glossiness));
        }
        if let Some(l) = layers.as_deref() {
            let Layers {
                transmission: _,
                transmission_texture,
                ior: _,
                thickness: _,
                attenuation_color: _,
                attenuation_distance: _,
                specular: _,
                specular_color: _,
                clearcoat: _,
                clearcoat_roughness: _,
                sheen_color: _,
                sheen_roughness: _,
            } = l;
            texture("transmission", transmission_texture.as_ref());
        }
        if let Some(a) = &alpha.map {
            maps.push(("alpha", a.image.is_some()));
        }
        maps
    }

    /// Whether a render of this material reads the mesh's texture coordinates: it has a
    /// decoded map of any kind.
    pub fn reads_uvs(&self) -> bool {
        self.maps().iter().any(|&(_, decoded)| decoded)
    }

    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    pub fn validate(&self) -> Result<(), String> {
        let finite = match self.bsdf {
            Bsdf::Diffuse { albedo } => albedo.is_finite(),
            Bsdf::Mirror { reflectance } => reflectance.is_finite(),
            Bsdf::Glass { reflectance, transmittance, roughness, ior } => {
                reflectance.is_finite() && transmittance.is_finite() && roughness.is_finite() && ior.is_finite()
            }
            Bsdf::Refraction { transmittance, roughness, ior } => {
                transmittance.is_finite() && roughness.is_finite() && ior.is_finite()
            }
            Bsdf::Microfacet { alpha, eta, k } => alpha.is_finite() && eta.is_finite() && k.is_finite(),
            Bsdf::Phong { diffuse, specular, shininess } => {
                diffuse.is_finite() && specular.is_finite() && shininess.is_finite()
            }
            Bsdf::MetallicRoughness { base, metallic, roughness } => {
                base.is_finite() && metallic.is_finite() && roughness.is_finite()
            }
            Bsdf::SpecularGlossiness { diffuse, specular, glossiness } => {
                diffuse.is_finite() && specular.is_finite() && glossiness.is_finite()
            }
        };
        let finite = finite && self.layers.as_ref().is_none_or(|l| l.is_finite());
        if !finite || !self.emission.is_finite() {
            return Err("a parameter is not finite".into());
        }
        if self.emission.min_element() < 0.0 {
            return Err("negative emission".into());
        }
        let cutoff = match self.alpha.mode {
            super::AlphaMode::Mask { cutoff } => cutoff,
            _ => 0.0,
        };
        if !self.alpha.factor.is_finite() || !cutoff.is_finite() {
            return Err("an alpha value is not finite".into());
        }
        Ok(())
    }
}
