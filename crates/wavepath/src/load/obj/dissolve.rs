//! The MTL keys of a material's alpha: `d` (opacity, "dissolve"), `Tr` (transparency, 1 - d)
//! and `map_d` (a scalar opacity map), read as [`crate::scene::alpha`] models them:
//!
//! - `map_d` present: a cutout, `Mask` at 0.5 of `d` x texel. What exporters write maps for is
//!   foliage, fences and decals, whose maps are nearly all 0 or 1: a cut at the middle is
//!   what the common viewers show, and stays sharp however many samples are taken.
//! - no map and `d` < 1: `Blend` of coverage `d`. A uniform `d` means partial coverage (a
//!   dissolved surface, a tinted window), which a threshold would turn into all or nothing;
//!   the stochastic cutout lets `1 - d` of the light through on average.
//! - `d` >= 1 (or neither key): opaque.
//!
//! Materials of the transparent illumination models (`illum` 4, 6, 7, 9: glass, refraction)
//! ignore `d`/`Tr` without a map: their transparency is the dielectric's (an exporter writes
//! `d` < 1 there for rasterisers), and a stochastic cutout on top would pass light twice.
//!
//! When both `d` and `Tr` are given, `d` wins (some exporters write `Tr` as an opacity, the
//! opposite of the specification; `d` has one meaning everywhere). The map reads the
//! image's alpha channel where it has one, else its luminance.
use crate::scene::alpha::{AlphaImage, AlphaMap};
use crate::scene::{Alpha, AlphaMode};
use std::path::Path;
use std::sync::Arc;

/// The alpha keys of the material being read.
#[derive(Default)]
pub struct Dissolve {
    d: Option<f32>,
    tr: Option<f32>,
    map: Option<AlphaMap>,
    /// The material's `illum`, seen (not taken) on the way.
    illum: Option<u32>,
}

impl Dissolve {
    /// Takes `key` if it is one of the alpha keys (true); `rest` its words, `dir` where
    /// texture paths start.
    pub fn read(&mut self, key: &str, rest: &[&str], dir: &Path) -> Result<bool, String> {
        match key {
            "d" | "Tr" => {
                // `d -halo 0.5`: the halo form is read as plain opacity.
                let Some(w) = rest.iter().rfind(|w| !w.starts_with('-')) else {
                    return Err(format!("{key} without a value"));
                };
                let x: f32 = w.parse().map_err(|_| format!("{key}: '{w}' is not a number"))?;
                if !x.is_finite() {
                    return Err(format!("{key}: {x} is not finite"));
                }
                let x = x.clamp(0.0, 1.0);
                if key == "d" { self.d = Some(x) } else { self.tr = Some(x) }
            }
            "map_d" => {
                // Options (`-bm 1`, `-imfchan m`, ...) come first; the file name is the last word.
                let Some(file) = rest.last() else { return Err("map_d without a file name".into()) };
                // Windows exporters write `.\\tex\\a.png`.
                self.map = Some(AlphaMap::obj(dir.join(file.replace('\\', "/"))));
            }
            "illum" => {
                // Not taken: only noted (the illumination model is read elsewhere).
                self.illum = rest.first().and_then(|w| w.parse().ok());
                return Ok(false);
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// The alpha of the material these keys were read for (the state is cleared for the
    /// next one).
    pub fn take(&mut self) -> Alpha {
        let Dissolve { d, tr, map, illum } = std::mem::take(self);
        let factor = d.or(tr.map(|t| 1.0 - t)).unwrap_or(1.0);
        let dielectric = matches!(illum, Some(4 | 6 | 7 | 9));
        match map {
            Some(map) => Alpha { mode: AlphaMode::Mask { cutoff: Alpha::DEFAULT_CUTOFF }, factor, map: Some(map) },
            None if factor < 1.0 && !dielectric => Alpha { mode: AlphaMode::Blend, factor, map: None },
            None => Alpha::OPAQUE,
        }
    }
}

/// Decodes `alpha`'s map, if any, from its file; a map that cannot be read is a warning (the
/// material keeps its factor) in `notes`, as is a material that nothing of would be drawn.
/// `mtl` is the library, `name` the material (for the messages).
pub fn decode(alpha: &mut Alpha, mtl: &Path, name: &str, notes: &mut Vec<String>) {
    if let Some(map) = &mut alpha.map {
        let read = std::fs::read(&map.path).map_err(|e| e.to_string()).and_then(|b| AlphaImage::decode_matte(&b));
        match read {
            Ok(img) => map.image = Some(Arc::new(img)),
            Err(e) => notes.push(format!(
                "warning: {}: map_d {} cannot be read ({e}); {name} keeps d",
                mtl.display(),
                map.path.display()
            )),
        }
    }
    if alpha.factor <= 0.0 && alpha.mode != AlphaMode::Opaque {
        notes.push(format!("warning: {}: {name} has opacity 0 (d 0 or Tr 1): it is not drawn", mtl.display()));
    }
}
