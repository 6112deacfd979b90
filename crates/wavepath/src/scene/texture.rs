//! Albedo textures: an image decoded once at load time (sRGB to linear), looked up through
//! the mesh's uv coordinates with the glTF sampler's wrap and filter modes.
//!
//! Image rows are stored top first. glTF puts uv (0, 0) at the image's top-left corner; OBJ
//! puts v = 0 at the bottom (`flip_v`). Linear filtering interpolates between texel centres
//! (texel i covers [i, i+1) / size), as OpenGL does for GL_LINEAR without mipmaps.

use anyhow::{Result, anyhow, bail};
use glam::{Affine2, Vec2, Vec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What happens to uv outside [0, 1] (glTF `wrapS`/`wrapT`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    ClampToEdge,
    MirroredRepeat,
}

/// Magnification filter (glTF `magFilter`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Nearest,
    Linear,
}

/// Linear RGB texels, row 0 at the top of the image.
#[derive(Clone, PartialEq)]
pub struct TextureImage {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Vec3>,
}

impl std::fmt::Debug for TextureImage {
    // Scene hashes use Debug: a size and a checksum instead of every texel.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let sum: f64 = self.texels.iter().map(|t| (t.x + 2.0 * t.y + 3.0 * t.z) as f64).sum();
        write!(f, "TextureImage({}x{}, checksum {sum:.6})", self.width, self.height)
    }
}

/// The sRGB transfer function's inverse (IEC 61966-2-1).
#[inline]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

impl TextureImage {
    /// Decodes an encoded image (PNG, JPEG, ...) whose colours are sRGB.
    pub fn decode_srgb(bytes: &[u8]) -> Result<TextureImage> {
        Self::from_srgb(image::load_from_memory(bytes).map_err(|e| anyhow!("{e}"))?)
    }

    /// Decodes an encoded image whose values are linear data (glTF metallic-roughness maps).
    pub fn decode_linear(bytes: &[u8]) -> Result<TextureImage> {
        Self::convert(image::load_from_memory(bytes).map_err(|e| anyhow!("{e}"))?, |c| c)
    }

    /// Decodes an encoded image's alpha channel (linear) into all three channels (the
    /// glossiness of a glTF specular-glossiness texture); opaque images give 1.
    pub fn decode_alpha(bytes: &[u8]) -> Result<TextureImage> {
        let img = image::load_from_memory(bytes).map_err(|e| anyhow!("{e}"))?.into_rgba8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        if w == 0 || h == 0 {
            bail!("image has no pixels");
        }
        let texels = img.pixels().map(|p| Vec3::splat(p.0[3] as f32 / 255.0)).collect();
        Ok(TextureImage { width: w, height: h, texels })
    }

    fn from_srgb(img: image::DynamicImage) -> Result<TextureImage> {
        Self::convert(img, srgb_to_linear)
    }

    /// 8-bit channels through `transfer` (0..1 in, linear out).
    fn convert(img: image::DynamicImage, transfer: fn(f32) -> f32) -> Result<TextureImage> {
        let img = img.into_rgb8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        if w == 0 || h == 0 {
            bail!("image has no pixels");
        }
        // 256-entry table: the same conversion for every texel, without powf per texel.
        let lut: Vec<f32> = (0..256).map(|i| transfer(i as f32 / 255.0)).collect();
        let texels =
            img.pixels().map(|p| Vec3::new(lut[p.0[0] as usize], lut[p.0[1] as usize], lut[p.0[2] as usize])).collect();
        Ok(TextureImage { width: w, height: h, texels })
    }

    /// Reads and decodes an image file of colours; errors are one line naming the file.
    pub fn open_srgb(path: &Path) -> Result<TextureImage> {
        Self::open(path, srgb_to_linear)
    }

    /// Reads and decodes an image file of linear data (MTL roughness and metalness maps).
    pub fn open_linear(path: &Path) -> Result<TextureImage> {
        Self::open(path, |c| c)
    }

    fn open(path: &Path, transfer: fn(f32) -> f32) -> Result<TextureImage> {
        // The content decides the format where it can; the extension where it cannot (TGA has
        // no signature).
        let reader = image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| anyhow!("{}: cannot read texture: {e}", path.display()))?;
        let img = reader.decode().map_err(|e| anyhow!("{}: not a readable texture: {e}", path.display()))?;
        Self::convert(img, transfer).map_err(|e| anyhow!("{}: {e}", path.display()))
    }

    #[inline]
    fn at(&self, x: usize, y: usize) -> Vec3 {
        self.texels[y * self.width + x]
    }
}

/// An albedo image and how to sample it.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// The file, or for an embedded image the scene file with `#image N`.
    pub path: PathBuf,
    /// The decoded image; `None` until (or unless) it could be read.
    pub image: Option<Arc<TextureImage>>,
    /// Wrap modes for u and v.
    pub wrap: [Wrap; 2],
    pub filter: Filter,
    /// OBJ: v = 0 is the image's bottom row.
    pub flip_v: bool,
    /// Multiplies the texel (glTF `baseColorFactor`; 1 for OBJ, where the map replaces Kd).
    pub factor: Vec3,
    /// Applied to the mesh's uv before the lookup (glTF `KHR_texture_transform`: offset x
    /// rotation x scale).
    pub transform: Affine2,
}

impl Texture {
    /// An OBJ `map_Kd`: repeat, bilinear, v up, not yet decoded.
    pub fn obj(path: PathBuf) -> Texture {
        Texture {
            path,
            image: None,
            wrap: [Wrap::Repeat; 2],
            filter: Filter::Linear,
            flip_v: true,
            factor: Vec3::ONE,
            transform: Affine2::IDENTITY,
        }
    }

    /// Factor x texel at `uv` (an albedo, or an emitted radiance); `None` when the image is
    /// missing.
    #[inline]
    pub fn albedo(&self, uv: Vec2) -> Option<Vec3> {
        let img = self.image.as_deref()?;
        let uv = self.transform.transform_point2(uv);
        let v = if self.flip_v { 1.0 - uv.y } else { uv.y };
        Some(self.factor * sample(img, Vec2::new(uv.x, v), self.wrap, self.filter))
    }
}

/// Texel index `i` (any integer) folded into 0..n by `wrap`.
#[inline]
pub fn wrap_index(i: i64, n: usize, wrap: Wrap) -> usize {
    let n = n as i64;
    (match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m >= n { 2 * n - 1 - m } else { m }
        }
    }) as usize
}

/// The image at `uv` (u right, v down from the top row).
#[inline]
pub fn sample(img: &TextureImage, uv: Vec2, wrap: [Wrap; 2], filter: Filter) -> Vec3 {
    let (w, h) = (img.width, img.height);
    let (x, y) = (uv.x * w as f32, uv.y * h as f32);
    if !x.is_finite() || !y.is_finite() {
        return img.at(0, 0);
    }
    match filter {
        Filter::Nearest => img.at(wrap_index(x.floor() as i64, w, wrap[0]), wrap_index(y.floor() as i64, h, wrap[1])),
        Filter::Linear => {
            let (fx, fy) = (x - 0.5, y - 0.5);
            let (x0, y0) = (fx.floor(), fy.floor());
            let (tx, ty) = (fx - x0, fy - y0);
            let (x0, y0) = (x0 as i64, y0 as i64);
            let (xa, xb) = (wrap_index(x0, w, wrap[0]), wrap_index(x0 + 1, w, wrap[0]));
            let (ya, yb) = (wrap_index(y0, h, wrap[1]), wrap_index(y0 + 1, h, wrap[1]));
            let top = img.at(xa, ya).lerp(img.at(xb, ya), tx);
            let bottom = img.at(xa, yb).lerp(img.at(xb, yb), tx);
            top.lerp(bottom, ty)
        }
    }
}

/// Per material, the texture a render looks albedo up in; built once per render.
#[derive(Clone, Debug, Default)]
pub struct Textures {
    per_material: Vec<Option<Texture>>,
    /// Per material, the emission texture.
    emission: Vec<Option<Texture>>,
    /// Per material, the metallic-roughness texture.
    metal_rough: Vec<Option<Texture>>,
    /// Per material, the transmission texture (glTF `KHR_materials_transmission`).
    transmission: Vec<Option<Texture>>,
    /// Per material, the specular and glossiness textures of a specular-glossiness one.
    specular_glossiness: Vec<Option<(Texture, Texture)>>,
    /// Any material has a decoded texture and the mesh has uvs: otherwise lookups return
    /// `None` at the cost of one predictable branch.
    any: bool,
}

impl Textures {
    pub fn new(scene: &super::Scene) -> Textures {
        let decoded = |t: &Option<Texture>| t.clone().filter(|t| t.image.is_some());
        let per_material: Vec<Option<Texture>> = scene.materials.iter().map(|m| decoded(&m.albedo_texture)).collect();
        let emission: Vec<Option<Texture>> = scene.materials.iter().map(|m| decoded(&m.emission_texture)).collect();
        let metal_rough: Vec<Option<Texture>> =
            scene.materials.iter().map(|m| decoded(&m.metallic_roughness_texture)).collect();
        let transmission: Vec<Option<Texture>> = scene
            .materials
            .iter()
            .map(|m| decoded(&m.layers.as_ref().and_then(|l| l.transmission_texture.clone())))
            .collect();
        let specular_glossiness: Vec<Option<(Texture, Texture)>> = scene
            .materials
            .iter()
            .map(|m| {
                let t = m.specular_glossiness_texture.as_deref()?;
                (t.specular.image.is_some() && t.glossiness.image.is_some())
                    .then(|| (t.specular.clone(), t.glossiness.clone()))
            })
            .collect();
        let relief = scene.materials.iter().any(|m| m.relief.as_ref().is_some_and(|r| r.texture.image.is_some()));
        let any = scene.mesh.uvs.is_some()
            && (relief
                || per_material.iter().chain(&emission).chain(&metal_rough).chain(&transmission).any(Option::is_some)
                || specular_glossiness.iter().any(Option::is_some));
        Textures { per_material, emission, metal_rough, transmission, specular_glossiness, any }
    }

    /// The textured emission of `material` at `uv`, or `None` (use the material's own).
    #[inline]
    pub fn emission(&self, material: usize, uv: Vec2) -> Option<Vec3> {
        if !self.any {
            return None;
        }
        self.emission.get(material)?.as_ref()?.albedo(uv)
    }

    /// Metalness and roughness of `material` at `uv` from its metallic-roughness texture, or
    /// `None` (use the material's factors).
    #[inline]
    pub fn metal_rough(&self, material: usize, uv: Vec2) -> Option<Vec2> {
        if !self.any {
            return None;
        }
        let t = self.metal_rough.get(material)?.as_ref()?.albedo(uv)?;
        Some(Vec2::new(t.z, t.y))
    }

    /// The transmission of `material` at `uv` (factor x red channel), or `None`.
    #[inline]
    pub fn transmission(&self, material: usize, uv: Vec2) -> Option<f32> {
        if !self.any {
            return None;
        }
        Some(self.transmission.get(material)?.as_ref()?.albedo(uv)?.x)
    }

    /// The specular colour and glossiness of a specular-glossiness `material` at `uv` from
    /// its texture (factors applied), or `None`.
    #[inline(never)]
    pub fn specular_glossiness(&self, material: usize, uv: Vec2) -> Option<(Vec3, f32)> {
        if !self.any {
            return None;
        }
        let (s, g) = self.specular_glossiness.get(material)?.as_ref()?;
        Some((s.albedo(uv)?, g.albedo(uv)?.x))
    }

    /// Whether `material`'s emission varies over its surface.
    #[inline]
    pub fn has_emission(&self, material: usize) -> bool {
        self.any && self.emission.get(material).is_some_and(Option::is_some)
    }

    /// The textured albedo of `material` at `uv`, or `None` (use the material's own).
    #[inline]
    pub fn albedo(&self, material: usize, uv: Vec2) -> Option<Vec3> {
        if !self.any {
            return None;
        }
        self.per_material.get(material)?.as_ref()?.albedo(uv)
    }

    pub fn any(&self) -> bool {
        self.any
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img() -> TextureImage {
        // 4x2: red ramp in x, green marks row 1.
        let texels = (0..8).map(|i| Vec3::new((i % 4) as f32, (i / 4) as f32, 0.0)).collect();
        TextureImage { width: 4, height: 2, texels }
    }

    #[test]
    fn wrap_modes() {
        let r: Vec<usize> = (-5..9).map(|i| wrap_index(i, 4, Wrap::Repeat)).collect();
        assert_eq!(r, [3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0]);
        let c: Vec<usize> = (-5..9).map(|i| wrap_index(i, 4, Wrap::ClampToEdge)).collect();
        assert_eq!(c, [0, 0, 0, 0, 0, 0, 1, 2, 3, 3, 3, 3, 3, 3]);
        // Mirrored: 0 1 2 3 | 3 2 1 0 | 0 1 2 3, and the same reflected below 0.
        let m: Vec<usize> = (-5..9).map(|i| wrap_index(i, 4, Wrap::MirroredRepeat)).collect();
        assert_eq!(m, [3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0]);
    }

    #[test]
    fn nearest_and_linear_filters() {
        let t = img();
        let rep = [Wrap::Repeat; 2];
        let cl = [Wrap::ClampToEdge; 2];
        // Nearest: the texel the point falls in.
        assert_eq!(sample(&t, Vec2::new(0.3, 0.2), rep, Filter::Nearest), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(sample(&t, Vec2::new(1.3, 0.7), rep, Filter::Nearest), Vec3::new(1.0, 1.0, 0.0));
        // Linear at a texel centre is the texel; halfway between centres the mean.
        assert_eq!(sample(&t, Vec2::new(2.5 / 4.0, 0.25), cl, Filter::Linear), Vec3::new(2.0, 0.0, 0.0));
        let mid = sample(&t, Vec2::new(2.0 / 4.0, 0.5), cl, Filter::Linear);
        assert!((mid - Vec3::new(1.5, 0.5, 0.0)).length() < 1e-6, "{mid}");
        // At the left edge, repeat blends with the last column, clamp does not.
        let e_rep = sample(&t, Vec2::new(0.0, 0.25), rep, Filter::Linear);
        let e_cl = sample(&t, Vec2::new(0.0, 0.25), cl, Filter::Linear);
        assert!((e_rep.x - 1.5).abs() < 1e-6 && e_cl.x.abs() < 1e-6, "{e_rep} {e_cl}");
        // Mirrored repeat at u = 1.125 reads column 3 (mirror of 4), at 1.375 column 2.
        let mr = [Wrap::MirroredRepeat; 2];
        assert_eq!(sample(&t, Vec2::new(1.125, 0.25), mr, Filter::Nearest).x, 3.0);
        assert_eq!(sample(&t, Vec2::new(1.375, 0.25), mr, Filter::Nearest).x, 2.0);
    }

    #[test]
    fn obj_flips_v_and_gltf_applies_factor() {
        let mut t = Texture::obj("x.png".into());
        t.image = Some(Arc::new(img()));
        t.filter = Filter::Nearest;
        // OBJ v = 0.9 is near the top: row 0.
        assert_eq!(t.albedo(Vec2::new(0.1, 0.9)).unwrap().y, 0.0);
        assert_eq!(t.albedo(Vec2::new(0.1, 0.1)).unwrap().y, 1.0);
        t.flip_v = false;
        t.factor = Vec3::splat(0.5);
        assert_eq!(t.albedo(Vec2::new(0.1, 0.9)).unwrap().y, 0.5);
    }

    #[test]
    fn srgb_decoding() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.21404).abs() < 1e-4);
        let e = TextureImage::open_srgb(Path::new("/nonexistent/t.png")).unwrap_err().to_string();
        assert!(e.contains("/nonexistent/t.png") && !e.contains('\n'));
    }
}
