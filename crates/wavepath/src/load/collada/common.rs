//! COLLADA's common profile (`profile_COMMON`) as other tools write it, for files that are
//! not the CS184 course's (`dialect.rs`): `<lambert>`, `<phong>`, `<blinn>` and `<constant>`
//! with their colours, textures, transparency and index of refraction (COLLADA 1.4.1
//! specification, chapter 8, "profile_COMMON").
//!
//! | effect | becomes |
//! |---|---|
//! | `<constant>` | an emitter of its `<emission>` colour that reflects nothing |
//! | `<lambert>`, or `<phong>`/`<blinn>` with a black or absent `<specular>` | Lambertian `<diffuse>` |
//! | `<phong>`, `<blinn>` | `Bsdf::Phong` (shaded by `bsdf/glossy.rs`): Lambertian `<diffuse>` plus GGX `<specular>`, alpha = sqrt(2 / (`<shininess>` + 2)) (the MTL `illum 2` rule; Blinn's exponent read as Phong's) |
//! | `<transparent>`/`<transparency>` letting light through | smooth dielectric of index `<index_of_refraction>` (1 when absent: the surface filters light without bending it), transmittance the transparency's colour |
//! | `<reflective>` x `<reflectivity>` on a black `<diffuse>` | mirror of that reflectance |
//! | `<diffuse><texture>` | the image as the albedo, through `<newparam>` sampler2D -> surface -> `<init_from>` -> `<library_images>` |
//!
//! `<emission>` gives the emitted radiance of every shader. Textures of other parameters
//! and a reflection mixed with a diffuse colour are not rendered, with one warning each.

use super::xml::{Doc, child, path};
use crate::scene::texture::TextureImage;
use crate::scene::{Bsdf, Material, Texture};
use anyhow::Result;
use glam::Vec3;
use roxmltree::Node;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Albedo of a shader without a `<diffuse>` colour.
const DEFAULT_ALBEDO: f32 = 0.5;

/// A colour parameter: a colour with its alpha, or a `<texture>` element.
enum Param<'a, 'input> {
    Color(Vec3, f32),
    Texture(Node<'a, 'input>),
}

/// Where a file's images are and where warnings go.
pub struct Context<'c> {
    pub dir: &'c Path,
    pub notes: &'c mut Vec<String>,
}

impl Context<'_> {
    fn warn(&mut self, file: &str, material: &str, what: &str) {
        self.notes.push(format!("warning: {file}: material '{material}': {what}"));
    }
}

/// `m` (named, with the defaults) with what the effect's common profile says.
pub fn material<'a, 'input>(
    d: &Doc<'a, 'input>,
    mut m: Material,
    effect: Node<'a, 'input>,
    cx: &mut Context,
) -> Result<Material> {
    let Some(tech) = path(effect, &["profile_COMMON", "technique"]) else {
        return Ok(m);
    };
    let Some(shader) = tech
        .children()
        .find(|c| c.is_element() && matches!(c.tag_name().name(), "phong" | "lambert" | "blinn" | "constant"))
    else {
        return Ok(m);
    };
    let kind = shader.tag_name().name();
    let name = m.name.clone();
    let warn = |cx: &mut Context, what: &str| cx.warn(d.file, &name, what);
    match colour(d, shader, "emission")? {
        Some(Param::Color(e, _)) => {
            if e.min_element() < 0.0 {
                return Err(d.err(shader, "negative emission"));
            }
            m.emission = e;
        }
        Some(Param::Texture(_)) => warn(cx, "an emission texture is not read"),
        None => {}
    }
    if kind == "constant" {
        m.bsdf = Bsdf::Diffuse { albedo: Vec3::ZERO };
        return Ok(m);
    }
    let kd = match colour(d, shader, "diffuse")? {
        Some(Param::Color(c, _)) => c.max(Vec3::ZERO),
        Some(Param::Texture(t)) => {
            // A broken chain of references loses the texture, not the file.
            m.albedo_texture = texture(d, effect, t, cx).unwrap_or_else(|e| {
                cx.notes.push(format!("warning: {e:#}; using the default albedo"));
                None
            });
            Vec3::splat(DEFAULT_ALBEDO)
        }
        None => Vec3::splat(DEFAULT_ALBEDO),
    };
    m.bsdf = Bsdf::Diffuse { albedo: kd };
    if matches!(kind, "phong" | "blinn") {
        match colour(d, shader, "specular")? {
            Some(Param::Color(ks, _)) if ks.max_element() > 0.0 => {
                let shininess = scalar(d, shader, "shininess")?.unwrap_or(0.0);
                m.bsdf = Bsdf::Phong { diffuse: kd, specular: ks.max(Vec3::ZERO), shininess };
            }
            Some(Param::Texture(_)) => warn(cx, "a specular texture is not read"),
            _ => {}
        }
    }
    if let Some(Param::Color(r, _)) = colour(d, shader, "reflective")? {
        let r = r.max(Vec3::ZERO) * scalar(d, shader, "reflectivity")?.unwrap_or(0.0).clamp(0.0, 1.0);
        if r.max_element() > 0.0 {
            if kd.max_element() <= 0.0 && m.albedo_texture.is_none() {
                m.bsdf = Bsdf::Mirror { reflectance: r };
            } else {
                warn(cx, "its reflection, mixed with a diffuse colour, is not rendered");
            }
        }
    }
    if let Some(t) = transmittance(d, shader, cx, &name)? {
        let ior = scalar(d, shader, "index_of_refraction")?.filter(|&n| n > 0.0).unwrap_or(1.0);
        m.bsdf = Bsdf::Glass { reflectance: Vec3::ONE, transmittance: t, roughness: 0.0, ior };
    }
    Ok(m)
}

/// The colour of the light a shader lets through, when it lets any through: `<transparent>`
/// (its `opaque` mode, A_ONE by default) times `<transparency>` as the specification
/// defines the four modes. One of the two alone stands with the other's default (a white
/// A_ONE colour, an amount of 1).
fn transmittance<'a, 'input>(
    d: &Doc<'a, 'input>,
    shader: Node<'a, 'input>,
    cx: &mut Context,
    name: &str,
) -> Result<Option<Vec3>> {
    let amount = scalar(d, shader, "transparency")?;
    let node = child(shader, "transparent");
    let (c, a) = match colour(d, shader, "transparent")? {
        Some(Param::Color(c, a)) => (c.clamp(Vec3::ZERO, Vec3::ONE), a.clamp(0.0, 1.0)),
        Some(Param::Texture(_)) => {
            cx.warn(d.file, name, "a transparency texture is not read");
            return Ok(None);
        }
        None if amount.is_some() => (Vec3::ONE, 1.0),
        None => return Ok(None),
    };
    let f = amount.unwrap_or(1.0).clamp(0.0, 1.0);
    let mode = node.and_then(|n| n.attribute("opaque")).unwrap_or("A_ONE");
    let t = match mode {
        "A_ONE" => Vec3::splat(1.0 - a * f),
        "A_ZERO" => Vec3::splat(a * f),
        "RGB_ZERO" => c * f,
        "RGB_ONE" => Vec3::ONE - c * f,
        other => return Err(d.err(node.unwrap_or(shader), format!("unknown opaque mode \"{other}\""))),
    };
    Ok((t.max_element() > 1e-4).then_some(t))
}

/// A colour parameter (`<tag><color>` or `<tag><texture>`); `None` when absent or given by
/// a `<param>` reference.
fn colour<'a, 'input>(d: &Doc<'a, 'input>, shader: Node<'a, 'input>, tag: &str) -> Result<Option<Param<'a, 'input>>> {
    let Some(p) = child(shader, tag) else { return Ok(None) };
    if let Some(c) = child(p, "color") {
        let v = d.floats(c, Some(4))?;
        if v.len() < 3 {
            return Err(d.err(c, format!("a colour needs 3 numbers, found {}", v.len())));
        }
        return Ok(Some(Param::Color(Vec3::new(v[0], v[1], v[2]), v.get(3).copied().unwrap_or(1.0))));
    }
    Ok(child(p, "texture").map(Param::Texture))
}

/// A float parameter (`<tag><float>`).
fn scalar(d: &Doc, shader: Node, tag: &str) -> Result<Option<f32>> {
    match child(shader, tag).and_then(|p| child(p, "float")) {
        Some(f) => Ok(Some(d.float(f)?)),
        None => Ok(None),
    }
}

/// The image a `<texture texture="...">` names, read: through the effect's `<newparam>`
/// sampler2D (its `<source>` surface's `<init_from>`, or COLLADA 1.5's `<instance_image>`),
/// or, as some exporters write, the image's own id. A missing or unreadable image is a
/// warning and no texture.
fn texture<'a, 'input>(
    d: &Doc<'a, 'input>,
    effect: Node<'a, 'input>,
    tex: Node<'a, 'input>,
    cx: &mut Context,
) -> Result<Option<Texture>> {
    let name = tex.attribute("texture").ok_or_else(|| d.err(tex, "missing 'texture' attribute"))?;
    let newparam = |sid: &str| {
        effect
            .descendants()
            .find(|n| n.is_element() && n.tag_name().name() == "newparam" && n.attribute("sid") == Some(sid))
    };
    let mut image_id = name.to_owned();
    if let Some(sampler) = newparam(name).and_then(|p| child(p, "sampler2D")) {
        if let Some(src) = child(sampler, "source").and_then(|s| s.text()) {
            let surface = newparam(src.trim()).and_then(|p| child(p, "surface"));
            let Some(init) = surface.and_then(|s| child(s, "init_from")).and_then(|i| i.text()) else {
                return Err(
                    d.err(sampler, format!("sampler source \"{}\" is not a surface with <init_from>", src.trim()))
                );
            };
            image_id = init.trim().to_owned();
        } else if let Some(url) = child(sampler, "instance_image").and_then(|i| i.attribute("url")) {
            image_id = url.trim_start_matches('#').to_owned();
        }
    }
    let Some(image) = d.by_id(&image_id).filter(|n| n.tag_name().name() == "image") else {
        return Err(d.err(tex, format!("texture \"{name}\" leads to no <image> (looked for id \"{image_id}\")")));
    };
    let init = child(image, "init_from");
    let Some(uri) = init.and_then(|i| child(i, "ref").or(Some(i))).and_then(|n| n.text()).map(str::trim) else {
        return Err(d.err(image, "an image without <init_from>"));
    };
    let file = cx.dir.join(file_path(uri));
    let mut t = Texture::obj(file);
    match TextureImage::open_srgb(&t.path) {
        Ok(img) => t.image = Some(Arc::new(img)),
        Err(e) => {
            cx.notes.push(format!("warning: {}: {e:#}; using the diffuse colour", d.file));
            return Ok(None);
        }
    }
    Ok(Some(t))
}

/// A file path from an `<init_from>` URI: `file://` dropped, `%xx` escapes decoded, `\`
/// read as `/`.
fn file_path(uri: &str) -> PathBuf {
    let s = uri.strip_prefix("file://").unwrap_or(uri);
    // `file:///C:/x.png`: a Windows drive after the third slash.
    let s = match s.as_bytes() {
        [b'/', d, b':', ..] if d.is_ascii_alphabetic() => &s[1..],
        _ => s,
    };
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%'
            && i + 2 < bytes.len()
            && let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2]))
        {
            out.push((h * 16 + l) as u8);
            i += 3;
            continue;
        }
        out.push(if bytes[i] == b'\\' { b'/' } else { bytes[i] });
        i += 1;
    }
    PathBuf::from(String::from_utf8_lossy(&out).into_owned())
}
