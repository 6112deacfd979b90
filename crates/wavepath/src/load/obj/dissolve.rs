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
//!
//! A material whose keys would make it wholly invisible (opacity 0, with or without a map)
//! is drawn, with a warning naming the file, the material and the key:
//!
//! - `Tr 1` without `d`: read as an opacity of 1. MeshLab's MTL writer puts `Tr 1` on every
//!   opaque material (trimesh's `fuze.obj` and `capsule.obj` are such files), following the
//!   exporters that write `Tr` as an opacity; a transparency of exactly 1 is where the two
//!   readings can be told apart, since only one of them draws anything. Other `Tr` values
//!   keep the specification's meaning: there the two readings cannot be told apart.
//! - `d 0`: drawn opaque too. A wholly dissolved material draws nothing at all, which no
//!   author exports on purpose (an object meant to be absent is deleted or hidden, not
//!   exported); the files that carry it come from converters that write `d` as a
//!   transparency (some write `d` and `Tr` both as the transparency, so an opaque object
//!   comes out as `d 0`). Of the two ways to be wrong, a drawn object with a warning is seen
//!   and fixed with one edit of the file, while a missing one is a hole easily not noticed.
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

    /// The alpha of the material `name` these keys were read for (the state is cleared for
    /// the next one); a reading that would draw nothing is replaced as the module says, with
    /// a line in `notes` (the caller adds the file's name).
    pub fn take(&mut self, name: &str, notes: &mut Vec<String>) -> Alpha {
        let Dissolve { d, tr, map, illum } = std::mem::take(self);
        let dielectric = matches!(illum, Some(4 | 6 | 7 | 9));
        // Without a map a dielectric's factor is not read, so it cannot hide the material.
        let factor_read = map.is_some() || !dielectric;
        let factor = match (d, tr) {
            (Some(d), _) if d <= 0.0 && factor_read => {
                notes.push(format!(
                    "material '{name}': d 0 would make it wholly invisible; drawn opaque (d read as a \
                     transparency, as some converters write it)"
                ));
                1.0
            }
            (Some(d), _) => d,
            (None, Some(t)) if t >= 1.0 && factor_read => {
                notes.push(format!(
                    "material '{name}': Tr 1 without d would make it wholly invisible; read as an opacity \
                     of 1 (MeshLab's convention), so it is drawn"
                ));
                1.0
            }
            (None, Some(t)) => 1.0 - t,
            (None, None) => 1.0,
        };
        match map {
            Some(map) => Alpha { mode: AlphaMode::Mask { cutoff: Alpha::DEFAULT_CUTOFF }, factor, map: Some(map) },
            None if factor < 1.0 && !dielectric => Alpha { mode: AlphaMode::Blend, factor, map: None },
            None => Alpha::OPAQUE,
        }
    }
}

/// Decodes `alpha`'s map, if any, from its file; a map that cannot be read is a warning (the
/// material keeps its factor) in `notes`. `mtl` is the library, `name` the material (for the
/// message).
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
}
