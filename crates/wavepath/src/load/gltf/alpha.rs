//! glTF `alphaMode`, `alphaCutoff` and the coverage they read: the base colour's alpha
//! (`baseColorFactor[3]` x the alpha channel of `baseColorTexture`, or the diffuse ones of
//! `KHR_materials_pbrSpecularGlossiness`), sampled as the base colour texture is (its sampler,
//! uv set and `KHR_texture_transform`). `OPAQUE` ignores alpha, as the specification says;
//! `MASK` cuts at `alphaCutoff` (0.5 by default); `BLEND` is the stochastic cutout of
//! [`crate::scene::alpha`]. Vertex colours' alpha is not read (nor are their colours').
use super::{Images, data_uri, texture, uri_path};
use crate::scene::alpha::{AlphaImage, AlphaMap};
use crate::scene::{Alpha, AlphaMode, Material};
use glam::Vec3;
use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// Sets each material's alpha from its glTF material (`materials[i]` is material `i`),
/// decoding the alpha channel of every image a cut material reads, once each. An image that
/// cannot be read is a warning: the material keeps its factor.
pub fn apply(
    doc: &gltf::Document,
    materials: &mut [Material],
    images: &Images,
    (base, buffers): (&Path, &[gltf::buffer::Data]),
    path: &Path,
    notes: &mut Vec<String>,
) {
    let mut decoded: HashMap<usize, Option<Arc<AlphaImage>>> = HashMap::new();
    for (m, out) in doc.materials().zip(materials.iter_mut()) {
        let mode = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => continue,
            gltf::material::AlphaMode::Mask => {
                AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(Alpha::DEFAULT_CUTOFF) }
            }
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        };
        let (factor, info) = match m.pbr_specular_glossiness() {
            Some(sg) => (sg.diffuse_factor()[3], sg.diffuse_texture()),
            None => {
                let pbr = m.pbr_metallic_roughness();
                (pbr.base_color_factor()[3], pbr.base_color_texture())
            }
        };
        let map = info.and_then(|info| {
            let t = texture(&info, images, false, Vec3::ONE);
            let i = images.by_texture.get(info.texture().index()).copied().flatten()?;
            let image = decoded
                .entry(i)
                .or_insert_with(|| {
                    let img = doc.images().nth(i)?;
                    match image_bytes(&img, base, buffers).and_then(|b| AlphaImage::decode_alpha(&b)) {
                        Ok(a) => a.map(Arc::new),
                        Err(e) => {
                            notes.push(format!(
                                "warning: {}: image {i}: its alpha cannot be read ({e}); the material keeps its alpha factor",
                                path.display()
                            ));
                            None
                        }
                    }
                })
                .clone()?;
            Some(AlphaMap {
                path: t.path,
                image: Some(image),
                wrap: t.wrap,
                filter: t.filter,
                flip_v: t.flip_v,
                transform: t.transform,
            })
        });
        let alpha = Alpha { mode, factor, map };
        if !alpha.is_opaque() && out.is_emissive() {
            notes.push(format!(
                "warning: {}: {}: an emitter is not cut (alphaMode {:?} ignored): light is sampled over its whole area",
                path.display(),
                out.name,
                m.alpha_mode()
            ));
        }
        out.alpha = alpha;
    }
}

/// The encoded bytes of an image: a buffer view (.glb), a data URI or a file beside the scene.
fn image_bytes<'a>(img: &gltf::Image, base: &Path, buffers: &'a [gltf::buffer::Data]) -> Result<Cow<'a, [u8]>, String> {
    match img.source() {
        gltf::image::Source::View { view, .. } => buffers
            .get(view.buffer().index())
            .and_then(|b| b.0.get(view.offset()..view.offset() + view.length()))
            .map(Cow::Borrowed)
            .ok_or_else(|| "buffer view outside its buffer".into()),
        gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => data_uri(uri).map(Cow::Owned),
        gltf::image::Source::Uri { uri, .. } => {
            let file = base.join(uri_path(uri));
            std::fs::read(&file).map(Cow::Owned).map_err(|e| format!("{}: {e}", file.display()))
        }
    }
}
