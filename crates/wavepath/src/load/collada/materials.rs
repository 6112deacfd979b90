//! `material -> instance_effect -> effect`, and the CS184 BSDF extras.
//!
//! Materials are converted when a geometry instance first binds them, so the scene holds
//! only the materials it uses, in order of first use.

use super::common::Context;
use super::xml::{Doc, child, children, cs184_extra, path};
use crate::scene::{Bsdf, Material};
use anyhow::Result;
use glam::Vec3;
use roxmltree::Node;
use std::collections::HashMap;
use std::path::PathBuf;

/// Albedo of surfaces whose file gives none (as in the reference renderer).
const DEFAULT_ALBEDO: f32 = 0.5;

#[derive(Default)]
pub struct Materials {
    pub list: Vec<Material>,
    by_node: HashMap<roxmltree::NodeId, u32>,
    default: Option<u32>,
    /// The file is not the CS184 course's: effects without a CGL extra are read by the
    /// common profile in full (`common.rs`), not as the course's diffuse colour.
    pub common_profile: bool,
    /// The folder image paths are relative to.
    pub dir: PathBuf,
    /// Warnings for the scene's notes.
    pub notes: Vec<String>,
}

/// An instance's `bind_material`: material symbol -> material index.
pub struct Binding {
    pairs: Vec<(String, u32)>,
}

impl Binding {
    /// The material of a primitive group. Primitives that name no symbol take the first
    /// bound material, as the reference renderer gives one material per instance; a symbol
    /// that is not bound gets the default material.
    pub fn lookup(&self, symbol: Option<&str>, mats: &mut Materials) -> u32 {
        let found = match symbol {
            Some(s) => self.pairs.iter().find(|(k, _)| k == s),
            None => self.pairs.first(),
        };
        found.map(|&(_, m)| m).unwrap_or_else(|| mats.default_id())
    }

    /// The material of a sphere: the first bound one.
    pub fn first(&self, mats: &mut Materials) -> u32 {
        self.lookup(None, mats)
    }
}

impl Materials {
    pub fn new(common_profile: bool, dir: PathBuf) -> Materials {
        Materials { common_profile, dir, ..Materials::default() }
    }

    pub fn default_id(&mut self) -> u32 {
        *self.default.get_or_insert_with(|| {
            self.list.push(Material::diffuse("default", Vec3::splat(DEFAULT_ALBEDO)));
            (self.list.len() - 1) as u32
        })
    }

    /// Reads `instance_geometry/bind_material/technique_common/instance_material`.
    pub fn binding<'a, 'input>(&mut self, d: &Doc<'a, 'input>, instance: Node<'a, 'input>) -> Result<Binding> {
        let mut pairs = Vec::new();
        if let Some(tc) = path(instance, &["bind_material", "technique_common"]) {
            for im in children(tc, "instance_material") {
                let symbol = im.attribute("symbol").ok_or_else(|| d.err(im, "missing 'symbol' attribute"))?;
                let mat = d.resolve(im, "target", &["material"])?;
                let id = self.material(d, mat)?;
                pairs.push((symbol.to_owned(), id));
            }
        }
        Ok(Binding { pairs })
    }

    fn material<'a, 'input>(&mut self, d: &Doc<'a, 'input>, mat: Node<'a, 'input>) -> Result<u32> {
        if let Some(&i) = self.by_node.get(&mat.id()) {
            return Ok(i);
        }
        let name = mat.attribute("name").or(mat.attribute("id")).unwrap_or("material");
        let ie = d.child(mat, "instance_effect")?;
        let effect = d.resolve(ie, "url", &["effect"])?;
        let m = if self.common_profile && cs184_extra(effect).is_none() {
            let base = Material::diffuse(name, Vec3::splat(DEFAULT_ALBEDO));
            super::common::material(d, base, effect, &mut Context { dir: &self.dir, notes: &mut self.notes })?
        } else {
            effect_material(d, name, effect)?
        };
        self.list.push(m);
        let i = (self.list.len() - 1) as u32;
        self.by_node.insert(mat.id(), i);
        Ok(i)
    }
}

/// The first child of the effect's CS184 extra decides the surface; otherwise it is
/// diffuse with the common profile's diffuse colour.
fn effect_material(d: &Doc, name: &str, effect: Node) -> Result<Material> {
    let base = Material::diffuse(name, Vec3::splat(DEFAULT_ALBEDO));
    let Some(bsdf) = cs184_extra(effect) else {
        return common_material(d, base, effect);
    };
    let color_or =
        |tag: &str, default: f32| -> Result<Vec3> { child(bsdf, tag).map_or(Ok(Vec3::splat(default)), |c| d.color(c)) };
    let scalar = |tag: &str| -> Result<f32> { d.float(d.child(bsdf, tag)?) };
    let scalar_or = |tag: &str, default: f32| -> Result<f32> { child(bsdf, tag).map_or(Ok(default), |c| d.float(c)) };
    let bsdf = match bsdf.tag_name().name() {
        "emission" => return Ok(Material::emitter(name, d.color(d.child(bsdf, "radiance")?)?)),
        "mirror" => Bsdf::Mirror { reflectance: color_or("reflectance", 1.0)? },
        "glass" => Bsdf::Glass {
            reflectance: color_or("reflectance", 1.0)?,
            transmittance: color_or("transmittance", 1.0)?,
            roughness: scalar_or("roughness", 0.0)?,
            ior: positive(d, bsdf, "ior", scalar("ior")?)?,
        },
        "refraction" => Bsdf::Refraction {
            transmittance: color_or("transmittance", 1.0)?,
            roughness: scalar_or("roughness", 0.0)?,
            ior: positive(d, bsdf, "ior", scalar("ior")?)?,
        },
        "microfacet" => Bsdf::Microfacet {
            alpha: positive(d, bsdf, "alpha", scalar("alpha")?)?,
            eta: d.color(d.child(bsdf, "eta")?)?,
            k: d.color(d.child(bsdf, "k")?)?,
        },
        "diffuse" | "lambertian" => Bsdf::Diffuse { albedo: color_or("albedo", DEFAULT_ALBEDO)? },
        other => {
            return Err(d.err(
                bsdf,
                format!("unknown CGL material <{other}> (expected emission, mirror, glass, refraction or microfacet)"),
            ));
        }
    };
    Ok(Material { bsdf, ..base })
}

fn positive(d: &Doc, node: Node, what: &str, v: f32) -> Result<f32> {
    if v > 0.0 { Ok(v) } else { Err(d.err(node, format!("{what} {v} must be positive"))) }
}

/// The course's reading of `profile_COMMON/technique/(phong|lambert|blinn|constant)`:
/// diffuse colour as albedo, emission colour as emitted radiance (other files:
/// `common.rs`).
fn common_material(d: &Doc, mut m: Material, effect: Node) -> Result<Material> {
    let Some(tech) = path(effect, &["profile_COMMON", "technique"]) else {
        return Ok(m);
    };
    let Some(shader) = tech
        .children()
        .find(|c| c.is_element() && matches!(c.tag_name().name(), "phong" | "lambert" | "blinn" | "constant"))
    else {
        return Ok(m);
    };
    // A <texture> instead of a <color> keeps the default albedo.
    if let Some(c) = path(shader, &["diffuse", "color"]) {
        m.bsdf = Bsdf::Diffuse { albedo: d.color(c)? };
    }
    if let Some(c) = path(shader, &["emission", "color"]) {
        let e = d.color(c)?;
        if e.min_element() < 0.0 {
            return Err(d.err(c, "negative emission"));
        }
        m.emission = e;
    }
    Ok(m)
}
