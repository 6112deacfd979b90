//! A small MTL reader: tobj's own one panics on spec-legal short colour lines
//! (`Kd 0.5`, where g and b default to r), so the materials are parsed here.

use crate::scene::{Material, Texture};
use glam::Vec3;
use std::path::Path;

/// Parses an `.mtl` file's text into named materials. `dir` resolves texture paths.
/// Errors carry the line number; the caller adds the file name.
pub fn parse(text: &str, dir: &Path) -> Result<Vec<Material>, String> {
    let mut out: Vec<Material> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else { continue };
        let rest: Vec<&str> = words.collect();
        let at = |msg: &str| format!("line {}: {msg}", i + 1);
        if key == "newmtl" {
            let name = line["newmtl".len()..].trim();
            if name.is_empty() {
                return Err(at("newmtl without a name"));
            }
            out.push(Material::diffuse(name, Vec3::splat(0.5)));
            continue;
        }
        let Some(mat) = out.last_mut() else {
            // Statements before the first newmtl have no material to apply to.
            continue;
        };
        match key {
            "Kd" => {
                let albedo = colour(&rest).map_err(|e| at(&e))?;
                mat.bsdf = crate::scene::Bsdf::Diffuse { albedo };
            }
            "Ke" => {
                mat.emission = colour(&rest).map_err(|e| at(&e))?;
                // Front face only, as the renderers that read MTL files emit (Mitsuba, pbrt,
                // Blender's importer): the side the face's winding points to.
                mat.two_sided_emission = false;
            }
            "map_Kd" => {
                // Options (`-bm 1 ...`) come first; the file name is the last word.
                let Some(file) = rest.last() else { return Err(at("map_Kd without a file name")) };
                // Windows exporters write `.\\tex\\a.png`.
                mat.albedo_texture = Some(Texture::obj(dir.join(file.replace('\\', "/"))));
            }
            _ => super::relief::read(key, &rest, dir, mat).map_err(|e| at(&e))?,
        }
    }
    Ok(out)
}

/// `r [g b]`: the MTL specification lets g and b default to r.
fn colour(words: &[&str]) -> Result<Vec3, String> {
    let nums: Vec<f32> = words
        .iter()
        .take_while(|w| !w.starts_with("spectral") && !w.starts_with("xyz"))
        .map(|w| w.parse::<f32>().map_err(|_| format!("'{w}' is not a number")))
        .collect::<Result<_, _>>()?;
    let c = match nums.as_slice() {
        [r] => Vec3::splat(*r),
        [r, g, b] => Vec3::new(*r, *g, *b),
        _ => return Err(format!("expected 1 or 3 colour values, found {}", nums.len())),
    };
    if !c.is_finite() || c.min_element() < 0.0 {
        return Err(format!("colour {c} is not finite and non-negative"));
    }
    Ok(c)
}
