//! The images a library names: `map_Kd` (sRGB colours) and the PBR extension's `map_Pr` and
//! `map_Pm` (linear, one channel each), which become one metallic-roughness texture laid
//! out as glTF's: green roughness, blue metalness.

use super::Library;
use super::keys::Entry;
use crate::scene::texture::{Filter, TextureImage, Wrap, sample};
use crate::scene::{Bsdf, Texture};
use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A material's roughness and metalness maps.
#[derive(Clone, Debug, Default)]
pub struct PbrMaps {
    roughness: Option<PathBuf>,
    metalness: Option<PathBuf>,
}

impl PbrMaps {
    pub fn of(e: &Entry) -> PbrMaps {
        PbrMaps { roughness: e.map_pr.clone(), metalness: e.map_pm.clone() }
    }
}

/// Reads every image `lib`'s materials name (`file` is the library, for the warnings). An
/// image that is missing or does not decode leaves the material its constant, with a
/// warning line in `notes`.
pub fn load_images(lib: &mut Library, file: &Path, notes: &mut Vec<String>) {
    let shown = file.display();
    for m in &mut lib.materials {
        let Some(t) = &mut m.albedo_texture else { continue };
        if !t.path.is_file() {
            notes.push(format!("warning: {shown}: texture {} not found", t.path.display()));
            continue;
        }
        match TextureImage::open_srgb(&t.path) {
            Ok(img) => t.image = Some(Arc::new(img)),
            Err(e) => notes.push(format!("warning: {shown}: {e:#}; using Kd")),
        }
    }
    for (m, maps) in lib.materials.iter_mut().zip(&lib.pbr_maps) {
        let Bsdf::MetallicRoughness { metallic, roughness, .. } = m.bsdf else { continue };
        let mut read = |path: &Option<PathBuf>, constant: &str| {
            let path = path.as_ref()?;
            match TextureImage::open_linear(path) {
                Ok(img) => Some(img),
                Err(e) => {
                    notes.push(format!("warning: {shown}: {e:#}; using {constant}"));
                    None
                }
            }
        };
        let (r, mt) = (read(&maps.roughness, "Pr"), read(&maps.metalness, "Pm"));
        let Some(path) = maps.roughness.clone().filter(|_| r.is_some()).or(maps.metalness.clone()) else { continue };
        let Some(image) = metal_rough_image(r.as_ref(), mt.as_ref()) else { continue };
        // The maps replace the constants (as `map_Kd` replaces `Kd`); the factor keeps the
        // constant of a channel without a map.
        let factor =
            Vec3::new(1.0, if r.is_some() { 1.0 } else { roughness }, if mt.is_some() { 1.0 } else { metallic });
        m.metallic_roughness_texture = Some(Texture { image: Some(Arc::new(image)), factor, ..Texture::obj(path) });
    }
}

/// One image of texels (1, roughness, metalness) from the two maps' first channels (a
/// channel without a map is 1). It has the roughness map's size when there is one; the
/// other map is read at its texel centres (nearest texel).
pub fn metal_rough_image(rough: Option<&TextureImage>, metal: Option<&TextureImage>) -> Option<TextureImage> {
    let grid = rough.or(metal)?;
    let (w, h) = (grid.width, grid.height);
    let at = |img: Option<&TextureImage>, x: usize, y: usize| -> f32 {
        let Some(img) = img else { return 1.0 };
        if img.width == w && img.height == h {
            return img.texels[y * w + x].x;
        }
        let uv = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
        sample(img, uv, [Wrap::ClampToEdge; 2], Filter::Nearest).x
    };
    let mut texels = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            texels.push(Vec3::new(1.0, at(rough, x, y), at(metal, x, y)));
        }
    }
    Some(TextureImage { width: w, height: h, texels })
}
