//! Alpha cutouts: how much of a surface is there at a point (its coverage, 0 to 1) and what
//! a ray that meets it does with that.
//!
//! The test is made where hits are found (`crate::accel::cutout`), not in shading: a ray
//! through a hole is not a hit, so camera rays, bounces and shadow rays all pass through it
//! alike, and nothing downstream needs to know.
//!
//! - `Mask { cutoff }` (glTF `MASK`, and MTL `map_d`): the surface is there where coverage
//!   >= cutoff, absent elsewhere.
//! - `Blend` (glTF `BLEND`, and MTL `d` < 1 without a map): coverage is the probability that
//!   a ray meets the surface, decided per (ray, primitive) by a hash, so that every kernel
//!   makes the same decision and the image is the same on every ISA and thread count. On
//!   average the surface lets `1 - coverage` of the light through unchanged and scatters the
//!   rest as its BSDF says: a screen door at the scale of the pixel's samples, the
//!   physically consistent reading of partial coverage (it needs no ordering of
//!   transparent layers and converges to the same image as alpha compositing of the
//!   layers the samples meet).
//!
//! Emitters are never cut: light sampling picks points over an emitter's whole area, and a
//! point in a hole would send light from a surface the rays never meet. So a material that
//! emits keeps its full shape (its alpha is ignored); spheres are never cut either (no
//! format gives them alpha).
use super::texture::{Filter, Wrap, wrap_index};
use glam::{Affine2, Vec2};
use std::path::PathBuf;
use std::sync::Arc;

/// What a material's coverage means (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Coverage is ignored: the surface is everywhere.
    Opaque,
    /// There where coverage >= `cutoff` (glTF `alphaCutoff`, default 0.5).
    Mask { cutoff: f32 },
    /// Met with probability coverage.
    Blend,
}

/// A material's alpha: the mode, a constant factor and an optional coverage image, coverage
/// being factor x texel (glTF: baseColorFactor's alpha x the base colour texture's alpha;
/// MTL: `d` x `map_d`).
#[derive(Clone, Debug, PartialEq)]
pub struct Alpha {
    pub mode: AlphaMode,
    pub factor: f32,
    pub map: Option<AlphaMap>,
}

impl Default for Alpha {
    fn default() -> Self {
        Alpha::OPAQUE
    }
}

impl Alpha {
    pub const OPAQUE: Alpha = Alpha { mode: AlphaMode::Opaque, factor: 1.0, map: None };

    /// glTF's default cutoff for `MASK`, and the one MTL `map_d` cutouts use.
    pub const DEFAULT_CUTOFF: f32 = 0.5;

    /// Whether every ray that meets the surface hits it (nothing to test in traversal).
    pub fn is_opaque(&self) -> bool {
        let mapped = self.map.as_ref().is_some_and(|m| m.image.is_some());
        match self.mode {
            AlphaMode::Opaque => true,
            AlphaMode::Mask { cutoff } => !mapped && self.factor >= cutoff,
            AlphaMode::Blend => !mapped && self.factor >= 1.0,
        }
    }

    /// Coverage at `uv` (factor x texel; the factor alone without a decoded image).
    #[inline]
    pub fn coverage(&self, uv: Vec2) -> f32 {
        match self.map.as_ref().and_then(|m| m.lookup(uv)) {
            Some(a) => self.factor * a,
            None => self.factor,
        }
    }

    /// Whether a ray meets the surface where coverage is `coverage`; `xi` is the ray's
    /// uniform number in [0, 1) for this primitive (read by `Blend` only).
    #[inline]
    pub fn keeps(&self, coverage: f32, xi: f32) -> bool {
        match self.mode {
            AlphaMode::Opaque => true,
            AlphaMode::Mask { cutoff } => coverage >= cutoff,
            AlphaMode::Blend => xi < coverage,
        }
    }
}

/// One channel of an image, as coverage in [0, 1], row 0 at the top: kept only for the
/// materials that are cut (a quarter of an RGB texture's texels).
#[derive(Clone, PartialEq)]
pub struct AlphaImage {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<f32>,
}

impl std::fmt::Debug for AlphaImage {
    // Scene hashes use Debug: a size and a checksum instead of every texel.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let sum: f64 = self.texels.iter().map(|&t| t as f64).sum();
        write!(f, "AlphaImage({}x{}, checksum {sum:.6})", self.width, self.height)
    }
}

impl AlphaImage {
    /// The alpha channel of an encoded image (glTF base colour: alpha is linear); `None` when
    /// the image has none (every texel 1: nothing to cut).
    pub fn decode_alpha(bytes: &[u8]) -> Result<Option<AlphaImage>, String> {
        let img = image::load_from_memory(bytes).map_err(|e| e.to_string())?;
        if !img.color().has_alpha() {
            return Ok(None);
        }
        Ok(Some(Self::channel(&img.into_luma_alpha8(), 1)?))
    }

    /// An MTL scalar map (`map_d`): the alpha channel where the image has one (what
    /// exporters write cutouts as), else its luminance (the MTL specification's default
    /// channel for scalar maps).
    pub fn decode_matte(bytes: &[u8]) -> Result<AlphaImage, String> {
        let img = image::load_from_memory(bytes).map_err(|e| e.to_string())?;
        let channel = if img.color().has_alpha() { 1 } else { 0 };
        Self::channel(&img.into_luma_alpha8(), channel)
    }

    fn channel(img: &image::GrayAlphaImage, c: usize) -> Result<AlphaImage, String> {
        let (width, height) = (img.width() as usize, img.height() as usize);
        if width == 0 || height == 0 {
            return Err("image has no pixels".into());
        }
        let texels = img.pixels().map(|p| p.0[c] as f32 / 255.0).collect();
        Ok(AlphaImage { width, height, texels })
    }

    #[inline]
    fn at(&self, x: usize, y: usize) -> f32 {
        self.texels[y * self.width + x]
    }

    /// The image at `uv` (u right, v down from the top row), as `texture::sample` filters.
    #[inline]
    pub fn sample(&self, uv: Vec2, wrap: [Wrap; 2], filter: Filter) -> f32 {
        let (w, h) = (self.width, self.height);
        let (x, y) = (uv.x * w as f32, uv.y * h as f32);
        if !x.is_finite() || !y.is_finite() {
            return self.at(0, 0);
        }
        match filter {
            Filter::Nearest => {
                self.at(wrap_index(x.floor() as i64, w, wrap[0]), wrap_index(y.floor() as i64, h, wrap[1]))
            }
            Filter::Linear => {
                let (fx, fy) = (x - 0.5, y - 0.5);
                let (x0, y0) = (fx.floor(), fy.floor());
                let (tx, ty) = (fx - x0, fy - y0);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let (xa, xb) = (wrap_index(x0, w, wrap[0]), wrap_index(x0 + 1, w, wrap[0]));
                let (ya, yb) = (wrap_index(y0, h, wrap[1]), wrap_index(y0 + 1, h, wrap[1]));
                let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
                let top = lerp(self.at(xa, ya), self.at(xb, ya), tx);
                let bottom = lerp(self.at(xa, yb), self.at(xb, yb), tx);
                lerp(top, bottom, ty)
            }
        }
    }
}

/// A coverage image and how to sample it (the same rules as the albedo [`super::Texture`]
/// it usually comes with).
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaMap {
    /// The file, or for an embedded image the scene file with `#image N`.
    pub path: PathBuf,
    /// The decoded channel; `None` until (or unless) it could be read.
    pub image: Option<Arc<AlphaImage>>,
    pub wrap: [Wrap; 2],
    pub filter: Filter,
    /// OBJ: v = 0 is the image's bottom row.
    pub flip_v: bool,
    pub transform: Affine2,
}

impl AlphaMap {
    /// An OBJ `map_d`: repeat, bilinear, v up, not yet decoded.
    pub fn obj(path: PathBuf) -> AlphaMap {
        AlphaMap {
            path,
            image: None,
            wrap: [Wrap::Repeat; 2],
            filter: Filter::Linear,
            flip_v: true,
            transform: Affine2::IDENTITY,
        }
    }

    /// The texel at `uv`; `None` when the image is missing.
    #[inline]
    pub fn lookup(&self, uv: Vec2) -> Option<f32> {
        let img = self.image.as_deref()?;
        let uv = self.transform.transform_point2(uv);
        let v = if self.flip_v { 1.0 - uv.y } else { uv.y };
        Some(img.sample(Vec2::new(uv.x, v), self.wrap, self.filter))
    }
}
