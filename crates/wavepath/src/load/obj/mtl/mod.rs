//! A small MTL reader: tobj's own one panics on spec-legal short colour lines
//! (`Kd 0.5`, where g and b default to r), so the materials are parsed here.
//!
//! [`keys`] reads a block's statements, [`illum`] decides what they become, [`maps`] reads
//! the images they name.

mod illum;
mod keys;
mod maps;

pub use maps::load_images;

use super::dissolve::Dissolve;
use crate::scene::Material;
use keys::Entry;
use std::collections::BTreeSet;
use std::path::Path;

/// A library's materials and what the reader could not follow.
pub struct Library {
    pub materials: Vec<Material>,
    /// Per material, its roughness and metalness maps (`map_Pr`, `map_Pm`), to be read into
    /// its metallic-roughness texture.
    pbr_maps: Vec<maps::PbrMaps>,
    /// One line each, without the file's name (the caller adds it).
    pub notes: Vec<String>,
}

/// Parses an `.mtl` file's text into named materials. `dir` resolves texture paths.
/// Errors carry the line number; the caller adds the file name.
pub fn parse(text: &str, dir: &Path) -> Result<Library, String> {
    let mut entries: Vec<Entry> = Vec::new();
    // The alpha keys (`d`, `Tr`, `map_d`) of each entry, read apart (`super::dissolve`).
    let mut dissolves: Vec<Dissolve> = Vec::new();
    // Each entry's normal or height map (`norm`, `bump`, `map_Bump`: `super::relief`).
    let mut reliefs: Vec<Option<crate::scene::ReliefMap>> = Vec::new();
    let mut ignored = BTreeSet::new();
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
            entries.push(Entry::new(name));
            dissolves.push(Dissolve::default());
            reliefs.push(None);
            continue;
        }
        let Some(entry) = entries.last_mut() else {
            // Statements before the first newmtl have no material to apply to.
            continue;
        };
        if let Some(d) = dissolves.last_mut()
            && d.read(key, &rest, dir).map_err(|e| at(&e))?
        {
            continue;
        }
        if let Some(r) = super::relief::parse(key, &rest, dir).map_err(|e| at(&e))? {
            if let Some(slot) = reliefs.last_mut() {
                *slot = Some(r);
            }
            continue;
        }
        if !entry.read(key, &rest, dir).map_err(|e| at(&e))? {
            ignored.insert(key.to_owned());
        }
    }
    let mut notes = Vec::new();
    if !ignored.is_empty() {
        notes.push(format!("keys not read: {}", ignored.into_iter().collect::<Vec<_>>().join(", ")));
    }
    let unapplied: BTreeSet<&str> = entries.iter().flat_map(|e| e.unapplied.iter().copied()).collect();
    if !unapplied.is_empty() {
        notes.push(format!(
            "{} not applied (the specular colour and exponent are the material's constants)",
            unapplied.into_iter().collect::<Vec<_>>().join(", ")
        ));
    }
    let mut materials = Vec::with_capacity(entries.len());
    for ((e, d), r) in entries.iter().zip(&mut dissolves).zip(&mut reliefs) {
        let mut m = illum::material(e, &mut notes);
        m.alpha = d.take(&e.name, &mut notes);
        m.relief = r.take();
        materials.push(m);
    }
    let pbr_maps = entries.iter().map(maps::PbrMaps::of).collect();
    Ok(Library { materials, pbr_maps, notes })
}
