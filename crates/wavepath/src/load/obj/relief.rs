//! MTL relief maps: `norm` (a tangent-space normal map, as Blender's exporter writes it)
//! and `bump` / `map_Bump` (a height map, scaled by its `-bm` option), read as linear data
//! with v up like the other OBJ textures.

use crate::scene::texture::TextureImage;
use crate::scene::{Material, Relief, ReliefMap, Texture};
use std::path::Path;

/// The relief map statement `key` `words` names, or `None` when `key` is not one. `dir`
/// resolves the file name (the last word, after any options).
pub fn parse(key: &str, words: &[&str], dir: &Path) -> Result<Option<ReliefMap>, String> {
    let relief = match key {
        "norm" => Relief::Normal { scale: 1.0 },
        "bump" | "map_Bump" | "map_bump" => {
            let bm = match words.iter().position(|w| *w == "-bm") {
                Some(i) => {
                    let v = words.get(i + 1).ok_or("-bm without a value")?;
                    v.parse::<f32>().ok().filter(|x| x.is_finite()).ok_or(format!("-bm '{v}' is not a number"))?
                }
                None => 1.0,
            };
            Relief::Height { bm }
        }
        _ => return Ok(None),
    };
    let Some(file) = words.last() else { return Err(format!("{key} without a file name")) };
    let texture = Texture::obj(dir.join(file.replace('\\', "/")));
    Ok(Some(ReliefMap { texture, relief }))
}

/// Decodes `mat`'s relief image (linear); one that cannot be read leaves the material flat,
/// with a warning naming the library `mtl`.
pub fn decode(mat: &mut Material, mtl: &Path, notes: &mut Vec<String>) {
    let Some(r) = &mut mat.relief else { return };
    let path = r.texture.path.clone();
    let img = std::fs::read(&path)
        .map_err(|e| format!("cannot read {} ({e})", path.display()))
        .and_then(|b| TextureImage::decode_linear(&b).map_err(|e| format!("{}: {e:#}", path.display())));
    match img {
        Ok(img) => r.texture.image = Some(std::sync::Arc::new(img)),
        Err(e) => {
            notes.push(format!("warning: {}: relief map {e}; the surface is drawn flat", mtl.display()));
            mat.relief = None;
        }
    }
}
