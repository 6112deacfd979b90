//! glTF 2.0 (.gltf with .bin or data URIs, .glb) through the gltf crate.
//!
//! The default scene's node tree is flattened into world space in depth-first order
//! (children in the order the file lists them); each mesh primitive in a triangle mode
//! (list, strip, fan; Draco-compressed or quantised) is appended in that order, once per
//! GPU instance. Skins and animations are ignored: a skinned mesh loads in its bind pose.
//! The glTF y-up frame is used as it is. Materials keep glTF's own BRDF
//! ([`crate::bsdf::Pbr`]); extensions that only refine appearance and that wavepath does
//! not render are accepted with one warning, so a model is drawn approximately rather than
//! refused.

mod alpha;
mod draco;
mod extensions;
mod tangents;

use crate::scene::texture::{Filter, TextureImage, Wrap};
use crate::scene::{Alpha, Bsdf, Camera, Light, Material, Mesh, Scene, Texture};
use anyhow::{Result, anyhow};
use glam::{Affine2, Mat3, Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::khr_lights_punctual::Kind;
use gltf::texture::{MagFilter, WrappingMode};
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub fn load(path: &Path) -> Result<Scene> {
    let shown = path.display();
    // The gltf crate does unchecked arithmetic on some header and accessor fields, which a
    // hostile file can make overflow (a panic in builds with overflow checks).
    let result = std::panic::catch_unwind(|| read(path))
        .unwrap_or_else(|_| Err("malformed file (a length or count is out of range)".into()));
    result.map_err(|e| anyhow!("{shown}: {e}"))
}

fn read(path: &Path) -> Result<Scene, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
    if bytes.starts_with(b"glTF") && glb_length_is_bad(&bytes) {
        return Err("binary glTF header length does not match the file".into());
    }
    precheck(&bytes)?;
    let raw = gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| e.to_string())?;
    let mut json = raw.document.into_json();
    // The crate refuses required extensions it does not know; this loader reads these itself.
    json.extensions_required.retain(|e| !read_here(e));
    draco::attach_views(&mut json);
    let document = gltf::Document::from_json(json).map_err(|e| e.to_string())?;
    let gltf = gltf::Gltf { document, blob: raw.blob };
    let base = path.parent().unwrap_or(Path::new("."));
    for b in gltf.document.buffers() {
        if let gltf::buffer::Source::Uri(uri) = b.source()
            && !uri.starts_with("data:")
            && !base.join(uri).is_file()
        {
            return Err(format!("buffer {}: cannot read {}", b.index(), base.join(uri).display()));
        }
    }
    let buffers = gltf::import_buffers(&gltf.document, Some(base), gltf.blob.clone()).map_err(|e| e.to_string())?;
    let doc = &gltf.document;

    let mut notes = Vec::new();
    let images = decode_images(doc, base, &buffers, path, &mut notes)?;
    // One line per drawing mode, however many primitives use it.
    let mut skipped_modes = std::collections::BTreeMap::new();
    let mut materials: Vec<Material> =
        doc.materials().map(|m| extensions::extend(material(&m, &images), &m, &images)).collect();
    alpha::apply(doc, &mut materials, &images, (base, &buffers), path, &mut notes);
    let uv_sets: Vec<u32> = doc.materials().map(|m| uv_set(&m, path, &mut notes)).collect();
    let ignored: Vec<&str> =
        doc.extensions_used().filter(|e| !KNOWN_EXTENSIONS.contains(e) && !extensions::READ.contains(e)).collect();
    if !ignored.is_empty() {
        notes.push(format!(
            "warning: {}: {} not rendered (the file is drawn without {})",
            path.display(),
            ignored.join(", "),
            if ignored.len() == 1 { "it" } else { "them" }
        ));
    }
    let default_material = materials.len() as u32;
    materials.push(Material::default());

    let mut mesh = Mesh::default();
    let mut all_normals = true;
    let mut camera = None;
    let mut lights = Vec::new();
    for (node, world) in flatten(doc)? {
        if camera.is_none()
            && let Some(cam) = node.camera()
        {
            camera = Some(make_camera(&cam, &world)?);
        }
        if let Some(light) = node.light() {
            lights.push(make_light(&light, &world));
        }
        let Some(m) = node.mesh() else { continue };
        let worlds =
            instances(&node, doc, &buffers)?.map_or_else(|| vec![world], |l| l.iter().map(|i| world * *i).collect());
        for prim in m.primitives() {
            use gltf::mesh::Mode;
            if !matches!(prim.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                *skipped_modes.entry(format!("{:?}", prim.mode())).or_insert(0usize) += 1;
                continue;
            }
            let mat = prim.material().index().map_or(default_material, |i| i as u32);
            let set = prim.material().index().map_or(0, |i| uv_sets[i]);
            for w in &worlds {
                let part = primitive(&prim, doc, &buffers, w, mat, set)
                    .map_err(|e| format!("mesh {} primitive {}: {e}", m.index(), prim.index()))?;
                all_normals &= part.normals.is_some();
                mesh.append(part);
            }
        }
    }
    for (mode, n) in skipped_modes {
        notes.push(format!(
            "warning: {}: {n} primitives of mode {mode} skipped; only triangles are loaded",
            path.display()
        ));
    }
    if !all_normals {
        mesh.normals = None;
    }
    if mesh.triangles.is_empty() {
        return Err("no triangles in the default scene".into());
    }
    let has_camera = camera.is_some();
    let mut scene = Scene { mesh, materials, lights, camera: camera.unwrap_or_default(), notes, ..Scene::default() };
    scene.source.reader = "gltf";
    super::finish_mesh_only(&mut scene, has_camera);
    Ok(scene)
}

/// Extensions the loader reads.
const KNOWN_EXTENSIONS: [&str; 9] = [
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_unlit",
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_texture_transform",
    "EXT_mesh_gpu_instancing",
    "KHR_mesh_quantization",
    "KHR_draco_mesh_compression",
    "EXT_texture_webp",
];

/// Extensions a file may require: the ones the loader reads, and material extensions it
/// does not (a material it cannot render exactly still has its geometry and base model:
/// drawn approximately, with a warning, rather than not at all).
fn may_require(e: &str) -> bool {
    KNOWN_EXTENSIONS.contains(&e)
        || e.starts_with("KHR_materials_")
        || matches!(e, "KHR_texture_basisu" | "MSFT_texture_dds")
}

/// Extensions read by this loader rather than the gltf crate (whose validation refuses
/// required extensions it does not know).
fn read_here(e: &str) -> bool {
    matches!(e, "EXT_mesh_gpu_instancing" | "KHR_mesh_quantization" | "KHR_draco_mesh_compression")
        || (e.starts_with("KHR_materials_") && !gltf::json::extensions::ENABLED_EXTENSIONS.contains(&e))
}

/// The instance transforms of a node's `EXT_mesh_gpu_instancing` (TRANSLATION, ROTATION as
/// a unit quaternion x y z w, SCALE; f32 accessors of one count), each applied before the
/// node's own transform; `None` when the node is not instanced.
fn instances(
    node: &gltf::Node,
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
) -> Result<Option<Vec<Mat4>>, String> {
    let Some(ext) = node.extension_value("EXT_mesh_gpu_instancing") else { return Ok(None) };
    let what = |m: &str| format!("node {}: EXT_mesh_gpu_instancing: {m}", node.index());
    let attrs = ext["attributes"].as_object().ok_or_else(|| what("no attributes"))?;
    let read = |name: &str, dims: Dimensions| -> Result<Option<Vec<f32>>, String> {
        let Some(i) = attrs.get(name) else { return Ok(None) };
        let acc = i
            .as_u64()
            .and_then(|i| doc.accessors().nth(i as usize))
            .ok_or_else(|| what(&format!("{name} accessor does not exist")))?;
        check_accessor(Some(acc.clone()), name, &[DataType::F32], dims).map_err(|e| what(&e))?;
        read_quantised(&acc, buffers).map(Some).map_err(|e| what(&format!("{name}: {e}")))
    };
    let t = read("TRANSLATION", Dimensions::Vec3)?;
    let r = read("ROTATION", Dimensions::Vec4)?;
    let s = read("SCALE", Dimensions::Vec3)?;
    let counts: Vec<usize> =
        [t.as_ref().map(|v| v.len() / 3), r.as_ref().map(|v| v.len() / 4), s.as_ref().map(|v| v.len() / 3)]
            .into_iter()
            .flatten()
            .collect();
    let Some(&n) = counts.first() else { return Err(what("no TRANSLATION, ROTATION or SCALE")) };
    if counts.iter().any(|&c| c != n) {
        return Err(what("attributes of different counts"));
    }
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let tr = t.as_ref().map_or(Vec3::ZERO, |v| Vec3::from_slice(&v[3 * k..]));
        let rot = r.as_ref().map_or(glam::Quat::IDENTITY, |v| glam::Quat::from_slice(&v[4 * k..]).normalize());
        let sc = s.as_ref().map_or(Vec3::ONE, |v| Vec3::from_slice(&v[3 * k..]));
        let m = Mat4::from_scale_rotation_translation(sc, rot, tr);
        if !m.is_finite() {
            return Err(what(&format!("instance {k} has a non-finite transform")));
        }
        out.push(m);
    }
    Ok(Some(out))
}

/// The references that the gltf crate follows before range-checking them (its validation
/// reads a primitive's POSITION accessor, and an image in a buffer view its mimeType, with
/// an unchecked index or unwrap): a damaged file would panic inside the crate.
fn precheck(bytes: &[u8]) -> Result<(), String> {
    let json: std::borrow::Cow<[u8]> = if bytes.starts_with(b"glTF") {
        gltf::Glb::from_slice(bytes).map_err(|e| e.to_string())?.json
    } else {
        bytes.into()
    };
    // The real cause first: a file of another glTF version, or one that requires an extension
    // the loader does not read, would otherwise be reported through the symptoms the
    // crate's validation finds (for a Draco file, hundreds of "missing data").
    if let Ok(v) = serde_json::from_slice::<serde_json::Value>(&json) {
        let version = v["asset"]["version"].as_str().unwrap_or("");
        if !version.starts_with("2.") {
            return Err(format!("glTF version '{version}' is not supported; convert the file to glTF 2.0"));
        }
        let required = v["extensionsRequired"].as_array().map(Vec::as_slice).unwrap_or_default();
        let unsupported: Vec<&str> = required.iter().filter_map(|e| e.as_str()).filter(|e| !may_require(e)).collect();
        if !unsupported.is_empty() {
            return Err(format!("requires {}, which wavepath does not support", unsupported.join(", ")));
        }
    }
    // A document that does not parse is reported by the crate itself.
    let Ok(root) = gltf::json::deserialize::from_slice::<gltf::json::Root>(&json) else { return Ok(()) };
    let accessors = root.accessors.len();
    for (mi, m) in root.meshes.iter().enumerate() {
        for (pi, p) in m.primitives.iter().enumerate() {
            let refs = p.attributes.values().chain(p.indices.as_ref());
            if let Some(a) = refs.map(|a| a.value()).find(|&a| a >= accessors) {
                return Err(format!("mesh {mi} primitive {pi}: accessor {a} does not exist ({accessors} accessors)"));
            }
        }
    }
    for (i, img) in root.images.iter().enumerate() {
        match (&img.buffer_view, &img.uri) {
            (Some(v), _) if v.value() >= root.buffer_views.len() => {
                return Err(format!("image {i}: buffer view {} does not exist", v.value()));
            }
            (Some(_), _) if img.mime_type.is_none() => {
                return Err(format!("image {i} is in a buffer view but has no mimeType"));
            }
            (None, None) => return Err(format!("image {i} has neither a uri nor a buffer view")),
            _ => {}
        }
    }
    Ok(())
}

/// A .glb whose declared length exceeds the data or is shorter than its own header.
fn glb_length_is_bad(bytes: &[u8]) -> bool {
    let Some(len) = bytes.get(8..12) else { return true };
    let len = u32::from_le_bytes([len[0], len[1], len[2], len[3]]) as usize;
    len < 20 || len > bytes.len()
}

/// Every node of the default scene (or of all root nodes when the file names no scene) with
/// its world matrix, parents before children. A node reached twice (a cycle or a shared
/// child) is an error: glTF node hierarchies are strict trees.
fn flatten(doc: &gltf::Document) -> Result<Vec<(gltf::Node<'_>, Mat4)>, String> {
    let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => s.nodes().collect(),
        None => {
            let mut is_child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            doc.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut seen = vec![false; doc.nodes().len()];
    let mut out = Vec::new();
    let mut stack: Vec<(gltf::Node, Mat4)> = roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(format!("node {} appears twice in the node hierarchy", node.index()));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err(format!("node {} has a non-finite transform", node.index()));
        }
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
        out.push((node, world));
    }
    Ok(out)
}

/// The triangles of a primitive's index list. Strips alternate their winding so that every
/// triangle keeps the first one's orientation (glTF 2.0 spec, 3.7.2.1); fans share the first
/// vertex. Degenerate triangles (repeated indices, used to stitch strips) are dropped.
fn triangles_of(mode: gltf::mesh::Mode, idx: &[u32]) -> Result<Vec<[u32; 3]>, String> {
    use gltf::mesh::Mode;
    let all: Vec<[u32; 3]> = match mode {
        Mode::TriangleStrip => (2..idx.len())
            .map(|i| if i % 2 == 0 { [idx[i - 2], idx[i - 1], idx[i]] } else { [idx[i - 2], idx[i], idx[i - 1]] })
            .collect(),
        Mode::TriangleFan => (2..idx.len()).map(|i| [idx[0], idx[i - 1], idx[i]]).collect(),
        _ => {
            if !idx.len().is_multiple_of(3) {
                return Err(format!("{} indices is not a multiple of 3", idx.len()));
            }
            return Ok(idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect());
        }
    };
    Ok(all.into_iter().filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]).collect())
}

/// A non-sparse accessor read directly as floats (f32 as stored, for the quantised
/// attributes and instance transforms the crate does not read); 8- and 16-bit integers
/// normalised ones mapped to
/// [0, 1] or [-1, 1] as the glTF specification defines (signed: max(c / (2^(n-1) - 1), -1)),
/// others as their values.
fn read_quantised(acc: &gltf::Accessor, buffers: &[gltf::buffer::Data]) -> Result<Vec<f32>, String> {
    let what = |m: &str| format!("accessor {}: {m}", acc.index());
    if acc.sparse().is_some() {
        return Err(what("sparse quantised data is not supported"));
    }
    let view = acc.view().ok_or_else(|| what("no buffer view"))?;
    let data = buffers.get(view.buffer().index()).map(|d| &d.0[..]).unwrap_or_default();
    let (n, size) = (acc.dimensions().multiplicity(), acc.data_type().size());
    let stride = view.stride().unwrap_or(n * size);
    let start = view.offset() + acc.offset();
    // Checked before anything is allocated: a damaged count must not ask for terabytes.
    let end = acc.count().checked_mul(stride).and_then(|b| b.checked_add(start));
    if acc.count() > 0 && end.is_none_or(|e| e - stride + n * size > data.len()) {
        return Err(what("data outside its buffer"));
    }
    let norm = acc.normalized();
    let mut out = Vec::with_capacity(acc.count() * n);
    for k in 0..acc.count() {
        for c in 0..n {
            let at = start + k * stride + c * size;
            let b = &data[at..at + size];
            let v = match acc.data_type() {
                DataType::I8 => (b[0] as i8) as f32 / if norm { 127.0 } else { 1.0 },
                DataType::U8 => b[0] as f32 / if norm { 255.0 } else { 1.0 },
                DataType::I16 => i16::from_le_bytes([b[0], b[1]]) as f32 / if norm { 32767.0 } else { 1.0 },
                DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as f32 / if norm { 65535.0 } else { 1.0 },
                DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                DataType::U32 => return Err(what("32-bit integers are not a vertex attribute type")),
            };
            out.push(if norm { v.max(-1.0) } else { v });
        }
    }
    Ok(out)
}

/// Refuses an accessor whose component type or shape is not one the semantic allows: the
/// gltf crate reads such data with debug-only checks, so it would panic or read garbage.
fn check_accessor(acc: Option<gltf::Accessor>, what: &str, types: &[DataType], dims: Dimensions) -> Result<(), String> {
    let Some(acc) = acc else { return Ok(()) };
    if !types.contains(&acc.data_type()) || acc.dimensions() != dims {
        return Err(format!(
            "{what} accessor {} holds {:?} {:?}, not {:?} of {:?}",
            acc.index(),
            acc.dimensions(),
            acc.data_type(),
            dims,
            types
        ));
    }
    Ok(())
}

/// One primitive's triangles in world space, with uvs from set `uv_set`: from its Draco
/// stream when it has one, else from its accessors.
fn primitive(
    prim: &gltf::Primitive,
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    world: &Mat4,
    mat: u32,
    uv_set: u32,
) -> Result<Mesh, String> {
    let (raw, mode) = match draco::decode(prim, doc, buffers, uv_set)? {
        // Draco streams hold triangle lists, whatever the primitive's mode says.
        Some(d) => (d, gltf::mesh::Mode::Triangles),
        None => (accessors(prim, buffers, uv_set)?, prim.mode()),
    };
    let positions: Vec<Vec3> = raw.positions.into_iter().map(|p| world.transform_point3(p)).collect();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i} has a NaN or infinite coordinate"));
    }
    let n = positions.len();
    let normal_matrix = Mat3::from_mat4(*world).inverse().transpose();
    let normals = raw
        .normals
        .map(|v| v.into_iter().map(|v| (normal_matrix * v).normalize_or_zero()).collect::<Vec<_>>())
        .filter(|v| v.len() == n && v.iter().all(|x| x.is_finite()));
    let uvs = raw.uvs.filter(|v| v.len() == n);
    let colors = raw.colors.filter(|v| v.len() == n);
    if let Some(&bad) = raw.indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("index {bad} is out of range for {n} vertices"));
    }
    let triangles = triangles_of(mode, &raw.indices)?;
    let material_ids = crate::scene::MaterialIds::uniform(mat, triangles.len());
    let tangents =
        tangents::of_primitive(prim, buffers, world, &positions, normals.as_deref(), uvs.as_deref(), &triangles);
    Ok(Mesh { positions, normals, uvs, colors, tangents, triangles, material_ids })
}

/// A primitive's attributes and indices as its accessors hold them (object space).
fn accessors(prim: &gltf::Primitive, buffers: &[gltf::buffer::Data], uv_set: u32) -> Result<draco::Decoded, String> {
    use gltf::Semantic;
    // The types KHR_mesh_quantization allows besides f32.
    use DataType::{F32, I8, I16, U8, U16};
    check_accessor(prim.get(&Semantic::Positions), "POSITION", &[F32, I8, U8, I16, U16], Dimensions::Vec3)?;
    check_accessor(prim.get(&Semantic::Normals), "NORMAL", &[F32, I8, I16], Dimensions::Vec3)?;
    let uv_name = format!("TEXCOORD_{uv_set}");
    check_accessor(prim.get(&Semantic::TexCoords(uv_set)), &uv_name, &[F32, I8, U8, I16, U16], Dimensions::Vec2)?;
    check_accessor(prim.indices(), "index", &[DataType::U8, DataType::U16, DataType::U32], Dimensions::Scalar)?;
    let color_types = [DataType::F32, DataType::U8, DataType::U16];
    if let Some(c) = prim.get(&Semantic::Colors(0))
        && c.dimensions() != Dimensions::Vec4
    {
        check_accessor(Some(c), "COLOR_0", &color_types, Dimensions::Vec3)?;
    } else {
        check_accessor(prim.get(&Semantic::Colors(0)), "COLOR_0", &color_types, Dimensions::Vec4)?;
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    // Quantised attributes (KHR_mesh_quantization) are read here; f32 ones (which may be
    // sparse) through the crate.
    let quantised = |s: Semantic| prim.get(&s).filter(|a| a.data_type() != DataType::F32);
    let positions: Vec<Vec3> = match quantised(Semantic::Positions) {
        Some(acc) => read_quantised(&acc, buffers)?.chunks_exact(3).map(Vec3::from_slice).collect(),
        None => {
            reader.read_positions().ok_or("no POSITION data (missing or outside its buffer)")?.map(Vec3::from).collect()
        }
    };
    let normals: Option<Vec<Vec3>> = match quantised(Semantic::Normals) {
        Some(acc) => Some(read_quantised(&acc, buffers)?.chunks_exact(3).map(Vec3::from_slice).collect()),
        None => reader.read_normals().map(|it| it.map(Vec3::from).collect()),
    };
    let uvs: Option<Vec<Vec2>> = match quantised(Semantic::TexCoords(uv_set)) {
        Some(acc) => Some(read_quantised(&acc, buffers)?.chunks_exact(2).map(Vec2::from_slice).collect()),
        None => reader.read_tex_coords(uv_set).map(|t| t.into_f32().map(Vec2::from).collect()),
    };
    let indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None if prim.indices().is_some() => return Err("index data outside its buffer".into()),
        None => (0..positions.len() as u32).collect(),
    };
    // COLOR_0 is linear RGB(A) (f32, or normalised u8/u16); alpha is not used.
    let colors = reader.read_colors(0).map(|c| c.into_rgb_f32().map(Vec3::from).collect());
    Ok(draco::Decoded { positions, normals, uvs, colors, indices })
}

/// A glTF material as the closest model wavepath has: metallic-roughness and
/// specular-glossiness as [`crate::bsdf::Pbr`] (their colour, metalness and roughness
/// textures included), `KHR_materials_unlit` as an emitter of its base colour that reflects
/// nothing.
fn material(m: &gltf::Material, images: &Images) -> Material {
    let name = m.name().map_or_else(|| format!("material {}", m.index().unwrap_or(0)), str::to_string);
    let strength = m.emissive_strength().unwrap_or(1.0);
    let emission = Vec3::from(m.emissive_factor()) * strength;
    // Emission is factor x texel: a texture under a black factor emits nothing.
    let emission_texture = m
        .emissive_texture()
        .filter(|_| emission.max_element() > 0.0)
        .map(|info| texture(&info, images, false, emission));
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    let base = Vec3::new(r, g, b);
    let base_texture = |factor| pbr.base_color_texture().map(|info| texture(&info, images, false, factor));
    if m.unlit() {
        // What the eye sees is the base colour itself: emitted, with no light reflected.
        let emission_texture = base_texture(base).filter(|_| base.max_element() > 0.0);
        let two_sided_emission = m.double_sided();
        return Material { emission_texture, two_sided_emission, ..Material::emitter(&name, base) };
    }
    if let Some(sg) = m.pbr_specular_glossiness() {
        let [r, g, b, _] = sg.diffuse_factor();
        let diffuse = Vec3::new(r, g, b);
        return Material {
            name,
            bsdf: Bsdf::SpecularGlossiness {
                diffuse,
                specular: Vec3::from(sg.specular_factor()),
                glossiness: sg.glossiness_factor(),
            },
            emission,
            albedo_texture: sg.diffuse_texture().map(|info| texture(&info, images, false, diffuse)),
            emission_texture,
            metallic_roughness_texture: None,
            two_sided_emission: m.double_sided(),
            alpha: Alpha::OPAQUE,
            relief: None,
            layers: None,
            specular_glossiness_texture: None,
        };
    }
    let (metallic, roughness) = (pbr.metallic_factor(), pbr.roughness_factor());
    Material {
        name,
        bsdf: Bsdf::MetallicRoughness { base, metallic, roughness },
        emission,
        albedo_texture: base_texture(base),
        emission_texture,
        metallic_roughness_texture: pbr
            .metallic_roughness_texture()
            .map(|info| texture(&info, images, true, Vec3::new(1.0, roughness, metallic))),
        two_sided_emission: m.double_sided(),
        alpha: Alpha::OPAQUE,
        relief: None,
        layers: None,
        specular_glossiness_texture: None,
    }
}

/// The uv set a texture reads (`KHR_texture_transform` may override it).
fn tex_coord(info: &gltf::texture::Info) -> u32 {
    info.texture_transform().and_then(|t| t.tex_coord()).unwrap_or_else(|| info.tex_coord())
}

/// Every texture a material reads, in the order its uv set is chosen by, and whether it
/// holds linear data (the metallic-roughness map) rather than sRGB colours.
fn textures_of<'a>(m: &gltf::Material<'a>) -> Vec<(gltf::texture::Info<'a>, bool)> {
    let pbr = m.pbr_metallic_roughness();
    let sg = m.pbr_specular_glossiness().and_then(|sg| sg.diffuse_texture());
    let colours = [pbr.base_color_texture(), sg, m.emissive_texture()].into_iter().flatten().map(|t| (t, false));
    colours.chain(pbr.metallic_roughness_texture().map(|t| (t, true))).collect()
}

/// The uv set a material's primitives are read with: the one its textures use (the base
/// colour's when they differ, with a warning; one set is kept per vertex).
fn uv_set(m: &gltf::Material, path: &Path, notes: &mut Vec<String>) -> u32 {
    let sets: Vec<u32> = textures_of(m).iter().map(|(t, _)| tex_coord(t)).collect();
    let first = sets.first().copied().unwrap_or(0);
    if sets.iter().any(|&s| s != first) {
        notes.push(format!(
            "warning: {}: material {}: its textures read different uv sets; all use TEXCOORD_{first}",
            path.display(),
            m.index().unwrap_or(0)
        ));
    }
    first
}

/// A glTF texture (its image, sampler and uv transform) scaled by `factor`; `linear`: the
/// image holds data, not colours.
fn texture(info: &gltf::texture::Info, images: &Images, linear: bool, factor: Vec3) -> Texture {
    let transform =
        info.texture_transform().map_or(Affine2::IDENTITY, |t| uv_transform(t.offset(), t.rotation(), t.scale()));
    texture_of(info.texture(), transform, images, linear, factor)
}

/// A glTF texture (image, sampler) with the uv transform given (the extensions read theirs
/// from raw JSON), scaled by `factor`; `linear`: the image holds data, not colours.
fn texture_of(tex: gltf::texture::Texture, transform: Affine2, images: &Images, linear: bool, factor: Vec3) -> Texture {
    let sampler = tex.sampler();
    let wrap = |w: WrappingMode| match w {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
    };
    let source = images.by_texture.get(tex.index()).copied().flatten();
    let decoded = if linear { &images.linear } else { &images.srgb };
    Texture {
        path: source.and_then(|i| images.paths.get(i).cloned()).unwrap_or_default(),
        image: source.and_then(|i| decoded.get(i).cloned().flatten()),
        wrap: [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())],
        // No mipmaps: the magnification filter decides (glTF leaves it open when absent).
        filter: match sampler.mag_filter() {
            Some(MagFilter::Nearest) => Filter::Nearest,
            _ => Filter::Linear,
        },
        flip_v: false,
        factor,
        transform,
    }
}

/// `KHR_texture_transform`'s matrix: translation x rotation x scale, where the rotation
/// turns uv by `rotation` radians counter-clockwise in the image as displayed (rows
/// `[cos sin; -sin cos]`, v pointing down).
fn uv_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Affine2 {
    let (s, c) = rotation.sin_cos();
    let m = Affine2::from_cols(Vec2::new(c, -s) * scale[0], Vec2::new(s, c) * scale[1], Vec2::from(offset));
    if m.is_finite() { m } else { Affine2::IDENTITY }
}

/// Decoded images by index: as sRGB colour and as linear data, each only where a material
/// reads it that way.
struct Images {
    srgb: Vec<Option<Arc<TextureImage>>>,
    linear: Vec<Option<Arc<TextureImage>>>,
    /// Per image, the file (or the scene file with `#imageN` for an embedded one).
    paths: Vec<PathBuf>,
    /// Per texture, its image: the core `source`, else an `EXT_texture_webp` source; `None`
    /// for a texture whose only image is one wavepath cannot decode (KTX2 through
    /// `KHR_texture_basisu`, DDS).
    by_texture: Vec<Option<usize>>,
    /// Per image, its alpha channel where a specular-glossiness texture reads glossiness
    /// from it.
    gloss_alpha: Vec<Option<Arc<TextureImage>>>,
}

/// Decodes every image a material's texture uses, once per colour space: from a buffer view
/// (.glb), a data URI (glTF-Embedded) or a file beside the scene (percent-escapes decoded).
/// An image that cannot be read or decoded is a warning: the material keeps its factor.
fn decode_images(
    doc: &gltf::Document,
    base: &Path,
    buffers: &[gltf::buffer::Data],
    path: &Path,
    notes: &mut Vec<String>,
) -> Result<Images, String> {
    let image_count = doc.images().len();
    let by_texture: Vec<Option<usize>> = doc
        .textures()
        .map(|t| {
            t.source().map(|i| i.index()).or_else(|| {
                let i = t.extension_value("EXT_texture_webp")?["source"].as_u64()? as usize;
                (i < image_count).then_some(i)
            })
        })
        .collect();
    let mut srgb_used = std::collections::HashSet::new();
    let mut linear_used = std::collections::HashSet::new();
    let mut undecodable = std::collections::BTreeSet::new();
    let mut image_of = |t: gltf::texture::Texture| {
        let i = by_texture[t.index()];
        if i.is_none() {
            undecodable.insert(t.index());
        }
        i
    };
    let mut gloss_used = std::collections::HashSet::new();
    for m in doc.materials() {
        if let Some(t) = m.pbr_specular_glossiness().and_then(|sg| sg.specular_glossiness_texture())
            && let Some(i) = by_texture[t.texture().index()]
        {
            gloss_used.insert(i);
        }
        let core = textures_of(&m).into_iter().map(|(t, linear)| (t.texture(), linear));
        for (t, linear) in core.chain(extensions::textures(&m)) {
            if let Some(i) = image_of(t) {
                if linear { &mut linear_used } else { &mut srgb_used }.insert(i);
            }
        }
    }
    if let Some(&first) = undecodable.iter().next() {
        let kinds: Vec<String> = doc
            .textures()
            .nth(first)
            .and_then(|t| t.extensions().map(|e| e.keys().cloned().collect()))
            .unwrap_or_default();
        notes.push(format!(
            "warning: {}: {} texture(s) have no image wavepath can decode{}; their materials keep their factors",
            path.display(),
            undecodable.len(),
            if kinds.is_empty() { String::new() } else { format!(" ({})", kinds.join(", ")) }
        ));
    }
    let paths = doc
        .images()
        .map(|img| match img.source() {
            gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => base.join(uri_path(uri)),
            _ => PathBuf::from(format!("{}#image{}", path.display(), img.index())),
        })
        .collect();
    let mut images = Images { srgb: Vec::new(), linear: Vec::new(), paths, by_texture, gloss_alpha: Vec::new() };
    for img in doc.images() {
        let (srgb, linear) = (srgb_used.contains(&img.index()), linear_used.contains(&img.index()));
        if !srgb && !linear {
            images.srgb.push(None);
            images.linear.push(None);
            images.gloss_alpha.push(None);
            continue;
        }
        let what = format!("image {}", img.index());
        // A texture that cannot be had leaves the material its colour factor, with a warning:
        // one unsupported image (KTX2, Basis) should not cost the whole model.
        let mut warn =
            |why: String| notes.push(format!("warning: {}: {why}; the material keeps its factors", path.display()));
        let bytes: Option<Cow<[u8]>> = match img.source() {
            gltf::image::Source::View { view, .. } => Some(Cow::Borrowed(
                buffers
                    .get(view.buffer().index())
                    .and_then(|b| b.0.get(view.offset()..view.offset() + view.length()))
                    .ok_or(format!("{what}: buffer view outside its buffer"))?,
            )),
            gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => match data_uri(uri) {
                Ok(b) => Some(Cow::Owned(b)),
                Err(e) => {
                    warn(format!("{what}: {e}"));
                    None
                }
            },
            gltf::image::Source::Uri { uri, .. } => {
                let file = base.join(uri_path(uri));
                match std::fs::read(&file) {
                    Ok(b) => Some(Cow::Owned(b)),
                    Err(e) => {
                        warn(format!("texture {} cannot be read ({e})", file.display()));
                        None
                    }
                }
            }
        };
        let decode = |b: &[u8], linear: bool| {
            if linear { TextureImage::decode_linear(b) } else { TextureImage::decode_srgb(b) }
        };
        let mut one = |want: bool, linear: bool| {
            let b = bytes.as_deref().filter(|_| want)?;
            match decode(b, linear) {
                Ok(t) => Some(Arc::new(t)),
                Err(e) => {
                    warn(format!("{what} cannot be decoded ({e})"));
                    None
                }
            }
        };
        let s = one(srgb, false);
        // An image both kinds of texture read fails (or not) the same way: one warning.
        let l = if s.is_none() && srgb { None } else { one(linear, true) };
        let gloss = bytes.as_deref().filter(|_| gloss_used.contains(&img.index()) && s.is_some());
        images.gloss_alpha.push(gloss.and_then(|b| TextureImage::decode_alpha(b).ok()).map(Arc::new));
        images.srgb.push(s);
        images.linear.push(l);
    }
    Ok(images)
}

/// A relative URI as a file path: percent-escapes decoded ("Box%20With%20Spaces.png").
fn uri_path(uri: &str) -> PathBuf {
    PathBuf::from(urlencoding::decode(uri).map_or_else(|_| uri.to_string(), |s| s.into_owned()))
}

/// The bytes of a `data:[<mime>][;base64],<payload>` URI (RFC 2397): base64, or
/// percent-encoded text.
fn data_uri(uri: &str) -> Result<Vec<u8>, String> {
    use base64::Engine;
    let (head, payload) = uri.split_once(',').ok_or("data URI without a ','")?;
    if head.ends_with(";base64") {
        base64::engine::general_purpose::STANDARD
            .decode(payload.trim())
            .map_err(|e| format!("data URI is not valid base64 ({e})"))
    } else {
        Ok(urlencoding::decode_binary(payload.as_bytes()).into_owned())
    }
}

/// Rotation part of a node's world matrix with scale and shear removed: columns right, up,
/// backward (the camera looks down its local -Z with local +Y up).
fn orientation(world: &Mat4) -> Option<Mat3> {
    let back = world.z_axis.truncate().try_normalize()?;
    let right = world.y_axis.truncate().cross(back).try_normalize()?;
    let up = back.cross(right);
    Some(Mat3::from_cols(right, up, back))
}

/// A perspective camera, or an orthographic one whose half extents xmag and ymag become
/// its half-angle tangents ([`Camera::orthographic`]).
fn make_camera(cam: &gltf::Camera, world: &Mat4) -> Result<Camera, String> {
    let (vfov_deg, aspect, znear, zfar, orthographic) = match cam.projection() {
        gltf::camera::Projection::Perspective(p) => {
            (p.yfov().to_degrees(), p.aspect_ratio(), p.znear(), p.zfar(), false)
        }
        gltf::camera::Projection::Orthographic(o) => {
            let (x, y) = (o.xmag().abs(), o.ymag().abs());
            if !(x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite()) {
                return Err(format!("camera {}: orthographic view size {x} x {y} is not positive", cam.index()));
            }
            (2.0 * y.atan().to_degrees(), Some(x / y), o.znear(), Some(o.zfar()), true)
        }
    };
    let c2w = orientation(world).ok_or(format!("camera {} has a degenerate transform", cam.index()))?;
    let mut camera = Camera {
        position: world.w_axis.truncate(),
        c2w,
        hfov_deg: 0.0,
        vfov_deg,
        nclip: znear,
        fclip: zfar.unwrap_or(1e30),
        lens_radius: 0.0,
        focal_distance: crate::scene::CS184_FOCAL_DISTANCE,
        fit: crate::scene::FovFit::Vertical,
        orthographic,
    };
    camera.fit_to(aspect.unwrap_or(4.0 / 3.0), 1.0);
    Ok(camera)
}

/// KHR_lights_punctual: intensity = colour x intensity; directions are the node's local -Z.
/// Spot: glTF's outer cone angle is a half-angle in radians, `cone_angle` the full angle in
/// degrees (glTF's smooth fall-off between inner and outer cone has no field in
/// `Light::Spot`; `falloff_exponent` is 0).
fn make_light(light: &gltf::khr_lights_punctual::Light, world: &Mat4) -> Light {
    let intensity = Vec3::from(light.color()) * light.intensity();
    let position = world.w_axis.truncate();
    let direction = world.transform_vector3(-Vec3::Z).try_normalize().unwrap_or(-Vec3::Z);
    match light.kind() {
        Kind::Point => Light::Point { position, intensity, attenuation: [0.0, 0.0, 1.0] },
        Kind::Directional => Light::Directional { direction, radiance: intensity },
        Kind::Spot { outer_cone_angle, .. } => Light::Spot {
            position,
            direction,
            intensity,
            cone_angle: 2.0 * outer_cone_angle.to_degrees(),
            falloff_exponent: 0.0,
        },
    }
}
