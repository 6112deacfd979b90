//! One `newmtl` block's statements, as the file writes them (before any rule of what they
//! become: [`super::illum`]).

use glam::Vec3;
use std::path::{Path, PathBuf};

/// What a material's block states; `None` where the file says nothing.
#[derive(Clone, Debug, Default)]
pub struct Entry {
    pub name: String,
    pub kd: Option<Vec3>,
    pub ks: Option<Vec3>,
    pub ke: Option<Vec3>,
    pub tf: Option<Vec3>,
    pub ns: Option<f32>,
    pub ni: Option<f32>,
    pub illum: Option<i64>,
    /// The PBR extension (Blender's exporter): roughness and metalness.
    pub pr: Option<f32>,
    pub pm: Option<f32>,
    /// Its clearcoat (`Pc`), clearcoat roughness (`Pcr`) and sheen (`Ps`): the layers of
    /// glTF's clearcoat and sheen extensions on top of the metallic-roughness base.
    pub pc: Option<f32>,
    pub pcr: Option<f32>,
    pub ps: Option<f32>,
    pub map_kd: Option<PathBuf>,
    pub map_pr: Option<PathBuf>,
    pub map_pm: Option<PathBuf>,
    /// Keys read whose values the material cannot use (`map_Ks`, `map_Ns`).
    pub unapplied: Vec<&'static str>,
}

impl Entry {
    pub fn new(name: &str) -> Entry {
        Entry { name: name.into(), ..Entry::default() }
    }

    /// Reads one statement; `Ok(false)` for a key this reader does not know. `dir` resolves
    /// texture paths.
    pub fn read(&mut self, key: &str, rest: &[&str], dir: &Path) -> Result<bool, String> {
        match key {
            "Kd" => self.kd = Some(colour(rest)?),
            "Ks" => self.ks = Some(colour(rest)?),
            "Ke" => self.ke = Some(colour(rest)?),
            "Tf" => self.tf = Some(colour(rest)?),
            "Ns" => self.ns = Some(scalar(key, rest)?),
            "Ni" => self.ni = Some(scalar(key, rest)?),
            "Pr" => self.pr = Some(scalar(key, rest)?),
            "Pm" => self.pm = Some(scalar(key, rest)?),
            "Pc" => self.pc = Some(scalar(key, rest)?),
            "Pcr" => self.pcr = Some(scalar(key, rest)?),
            "Ps" => self.ps = Some(scalar(key, rest)?),
            "illum" => self.illum = Some(illum(rest)?),
            "map_Kd" => self.map_kd = Some(map(key, rest, dir)?),
            "map_Pr" => self.map_pr = Some(map(key, rest, dir)?),
            "map_Pm" => self.map_pm = Some(map(key, rest, dir)?),
            "map_Ks" => self.unapplied.push("map_Ks"),
            "map_Ns" => self.unapplied.push("map_Ns"),
            // The ambient colour: a physically based renderer has no ambient term (light
            // that arrives from everywhere is the environment's, and paths find it).
            "Ka" | "map_Ka" => {}
            _ => return Ok(false),
        }
        Ok(true)
    }
}

/// A texture statement's file: options (`-bm 1 ...`) come first, the file name is the last
/// word. Windows exporters write `.\\tex\\a.png`.
fn map(key: &str, words: &[&str], dir: &Path) -> Result<PathBuf, String> {
    let Some(file) = words.last() else { return Err(format!("{key} without a file name")) };
    Ok(dir.join(file.replace('\\', "/")))
}

/// A key's single number (the first word).
fn scalar(key: &str, words: &[&str]) -> Result<f32, String> {
    let Some(w) = words.first() else { return Err(format!("{key} without a value")) };
    match w.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("{key} '{w}' is not a finite number")),
    }
}

/// `illum n`; some exporters write `2.0`.
fn illum(words: &[&str]) -> Result<i64, String> {
    let Some(w) = words.first() else { return Err("illum without a value".into()) };
    match (w.parse::<i64>(), w.parse::<f32>()) {
        (Ok(n), _) => Ok(n),
        (_, Ok(v)) if v.fract() == 0.0 && v.abs() < 1e6 => Ok(v as i64),
        _ => Err(format!("illum '{w}' is not a whole number")),
    }
}

/// `r [g b]`: the MTL specification lets g and b default to r.
pub fn colour(words: &[&str]) -> Result<Vec3, String> {
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
